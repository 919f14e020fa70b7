// The node's bias filter: the Kalman filter of a model observed through the averaging sampler
// (imu::discretize_averaged), computed on that model's structure instead of dense matrices.
//
// Structure (what configure() checks; every model build_model + discretize_averaged makes has
// it): states x = [p; J], p the model's n process states, J the sample's mean over its
// interval, appended last. Phi = [[D, 0], [c^T, 0]]: D block diagonal in blocks of 1 or 2
// consecutive states (one term each: a GM, the walk, a flicker member, the output filter are
// 1; a ramp, a sinusoid, the oscillation 2), c the mean's weights, J reset at every sample (its
// column of Phi is 0). Qd = [[Qb, qJ], [qJ^T, qJJ]] with Qb block diagonal like D. H = e_J.
// Because Phi(:, J) = 0, the prediction needs only the process covariance Ppp:
//   u = Ppp c,   P'pJ = D u + qJ,   P'JJ = c^T u + qJJ,   P'pp = D Ppp D^T + Qb,
// and the update with H = e_J (S = P'JJ + R, K = P'(:, J) / S) only
//   P+pp = P'pp - K_p P'pJ^T,   var(J+) = P'JJ R / S.
// Ppp is stored packed (lower triangle) and updated tile by tile (a tile: the rows of one
// block against the columns of another), so each entry is written once and the matrix is
// symmetric by construction. The update is the standard form: with H = e_J, the Joseph form
// P+ = (I - K H) P' (I - K H)^T + K R K^T restricted to Ppp is algebraically the same expression
// (P'pp - 2 v v^T / S + v v^T / S); symmetry, the diagonal floor at 0 and the cap (scaling a
// row and column, which keeps Ppp positive semi-definite) are what the dense filter's Joseph
// form and symmetrisation gave (test_averaged_kf compares both over 10^6 samples).
//
// Steady-state gain (set_steady_state(true)), as in KalmanFilter: K and S are compared at the
// ends of blocks of kSteadyBlock consecutive updates and frozen once they changed by at most
// kSteadyTol (relative); a sample without an update returns to the time-varying filter. A model
// with a persistent state that no noise drives (a constant ramp or sinusoid:
// ModelParams::signal_memory_s = 0) never freezes.
//
// Cost per sample, n process states, n1 of them in 1-state blocks and the rest in 2-state
// blocks: time-varying about 2 n^2 + 3 n multiply-adds when every block has one state (u: n^2,
// the tiles n (n + 1) / 2 of 3 flops) and up to 4x more on the 2-state tiles; frozen gain
// about 4 n. Memory: (n (n + 1) / 2 + 10 n) T plus 3 n bytes. No heap, not re-entrant on one
// instance.
#ifndef IMU_AVERAGED_KF_HPP
#define IMU_AVERAGED_KF_HPP

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "imu/bias_kf.hpp"
#include "imu/error_model.hpp"

namespace imu {

template <typename T, std::size_t kMaxProcess>
class AveragedKf {
  static_assert(kMaxProcess >= 1 && kMaxProcess <= 32, "kMaxProcess must be 1..32");

 public:
  static constexpr std::size_t kPacked = kMaxProcess * (kMaxProcess + 1) / 2;
  /// Updates per convergence block, and the relative change of K and S allowed over one block
  /// (KalmanFilter's).
  static constexpr std::uint32_t kSteadyBlock = 256;
  static constexpr double kSteadyTol = 1e-6;

  /// From a discretize_averaged model (m.n_states = n + 1, n <= kMaxProcess) with the structure
  /// of the file comment; x0 = 0, Ppp = the model's p0 process part. kBadModel otherwise, or
  /// for non-finite entries, R <= 0 or a non-finite known signal. O(n^2).
  template <std::size_t kMaxStates>
  [[nodiscard]] KfStatus configure(const DiscreteModel<kMaxStates>& m,
                                   double known_signal = 0.0) {
    if (m.n_states < 2 || m.n_states - 1 > kMaxProcess || !(m.r_filter() > 0.0) ||
        !std::isfinite(m.r_filter()) || !std::isfinite(known_signal)) {
      return KfStatus::kBadModel;
    }
    const std::size_t n = m.n_states - 1;
    if (!structured(m, n)) {
      return KfStatus::kBadModel;
    }
    AveragedKf f;  // filled completely, then copied: a refused model leaves *this untouched
    f.n_ = n;
    // The states in the filter's order: every 1-state block first, then the 2-state blocks,
    // each pair adjacent (from_[i]: the model's index of the filter's state i).
    std::size_t k = 0;
    for (std::size_t pass = 1; pass <= 2; ++pass) {
      for (std::size_t i = 0; i < n;) {
        const std::size_t size = i + 1 < n && coupled(m, i, i + 1) ? 2U : 1U;
        for (std::size_t a = 0; size == pass && a < size; ++a) {
          f.from_[k++] = static_cast<Index>(i + a);
        }
        i += size;
      }
      if (pass == 1) {
        f.n1_ = k;
      }
    }
    double pmax = m.p0(n, n) > m.qd(n, n) ? m.p0(n, n) : m.qd(n, n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t a = f.from_[i];
      const std::size_t b = f.from_[f.partner(i)];  // a itself in a 1-state block
      f.dd_[i] = static_cast<T>(m.phi(a, a));
      f.do_[i] = i < f.n1_ ? T(0) : static_cast<T>(m.phi(a, b));
      f.qd_[i] = static_cast<T>(m.qd(a, a));
      f.qo_[i] = i < f.n1_ ? T(0) : static_cast<T>(m.qd(a, b));
      f.c_[i] = static_cast<T>(m.phi(n, a));
      f.qj_[i] = static_cast<T>(m.qd(a, n));
      f.row_[i] = static_cast<Row>(i * (i + 1) / 2);
      for (std::size_t j = 0; j <= i; ++j) {
        f.p_[f.row_[i] + j] = static_cast<T>(m.p0(a, f.from_[j]));
      }
      pmax = m.p0(a, a) > pmax ? m.p0(a, a) : pmax;
      pmax = m.qd(a, a) > pmax ? m.qd(a, a) : pmax;
      // Persistent and undriven (a row of D but no drive): the gain never settles.
      if (!(m.qd(a, a) > 0.0)) {
        f.steady_allowed_ = false;
      }
    }
    f.qjj_ = static_cast<T>(m.qd(n, n));
    f.pjj_ = static_cast<T>(m.p0(n, n));
    f.r_ = static_cast<T>(m.r_filter());
    f.known_ = static_cast<T>(known_signal);
    // Generous bound for states that do not revert (walk, ramp): 1e6 x the largest initial or
    // per-step variance (KalmanFilter's). Hitting it is counted, never silent.
    f.p_max_ = static_cast<T>(1e6 * (pmax > 0.0 ? pmax : 1.0));
    f.steady_enabled_ = steady_enabled_;
    *this = f;
    return KfStatus::kOk;
  }

  void set_known_signal(T known) { known_ = known; }
  /// Allow (true) or forbid the frozen steady-state gain. Off by default; turning it off
  /// returns to the time-varying filter at once.
  void set_steady_state(bool enabled) {
    steady_enabled_ = enabled;
    reset_convergence();
  }
  [[nodiscard]] bool steady() const { return steady_; }
  [[nodiscard]] bool steady_allowed() const { return steady_allowed_; }
  /// The model's process states (the filter has one more, the sample mean).
  [[nodiscard]] std::size_t process_states() const { return n_; }

  /// One sample: predict, then update if is_static and z is finite. Time-varying or frozen
  /// (file comment). Non-finite z is counted (stats().rejected_nonfinite) and not used.
  KfStep<T> step(T z, bool is_static) {
    const bool update = is_static && std::isfinite(z);
    if (is_static && !update) {
      ++stats_.rejected_nonfinite;
    }
    if (steady_) {
      if (update) {
        return step_steady(z);
      }
      reset_convergence();  // no update: P grows, the time-varying filter takes over
    }
    return step_time_varying(z, update);
  }

  /// The bias the measurement sees: the sample mean's estimate, H x = x_J.
  [[nodiscard]] T bias() const { return xj_; }
  /// Its variance H P H^T (after the last step).
  [[nodiscard]] T bias_variance() const { return pjj_; }
  [[nodiscard]] const KfStats& stats() const { return stats_; }

 private:
  using Index = std::uint8_t;
  using Row = std::conditional_t<(kPacked < 256), std::uint8_t, std::uint16_t>;

  // The other state of i's 2-state block (the filter's order); i in a 1-state block.
  [[nodiscard]] std::size_t partner(std::size_t i) const {
    return i < n1_ ? i : n1_ + ((i - n1_) ^ 1U);
  }

  template <std::size_t kMaxStates>
  static bool nonzero(const DiscreteModel<kMaxStates>& m, std::size_t i, std::size_t j) {
    return std::fabs(m.phi(i, j)) > 0.0 || std::fabs(m.qd(i, j)) > 0.0;
  }
  template <std::size_t kMaxStates>
  static bool coupled(const DiscreteModel<kMaxStates>& m, std::size_t i, std::size_t j) {
    return nonzero(m, i, j) || nonzero(m, j, i);
  }
  // Every entry finite; H = e_J; Phi(:, J) = 0; the process parts of Phi and Qd couple a state
  // only with itself and, in a 2-state block, its neighbour; p0's process part is any
  // symmetric matrix.
  template <std::size_t kMaxStates>
  static bool structured(const DiscreteModel<kMaxStates>& m, std::size_t n) {
    for (std::size_t i = 0; i <= n; ++i) {
      for (std::size_t j = 0; j <= n; ++j) {
        if (!std::isfinite(m.phi(i, j)) || !std::isfinite(m.qd(i, j)) ||
            !std::isfinite(m.p0(i, j))) {
          return false;
        }
      }
      const bool h_ok = i == n ? std::fabs(m.h(0, i) - 1.0) <= 0.0 : !(std::fabs(m.h(0, i)) > 0.0);
      if (!h_ok || std::fabs(m.phi(i, n)) > 0.0) {
        return false;
      }
    }
    // Blocks: walk the states, a block is one state or two coupled neighbours; nothing else
    // couples.
    for (std::size_t i = 0; i < n;) {
      const std::size_t size = i + 1 < n && coupled(m, i, i + 1) ? 2U : 1U;
      for (std::size_t a = i; a < i + size; ++a) {
        for (std::size_t j = 0; j < n; ++j) {
          if ((j < i || j >= i + size) && coupled(m, a, j)) {
            return false;
          }
        }
      }
      i += size;
    }
    return true;
  }

  // u = Ppp c over the packed lower triangle (when the last step did not leave it).
  void compute_u() {
    for (std::size_t i = 0; i < n_; ++i) {
      u_[i] = T(0);
    }
    for (std::size_t i = 0; i < n_; ++i) {
      const T* row = p_ + row_[i];
      const T ci = c_[i];
      T acc = T(0);
      for (std::size_t j = 0; j < i; ++j) {
        acc += row[j] * c_[j];
        u_[j] += row[j] * ci;
      }
      u_[i] += acc + row[i] * ci;
    }
    u_valid_ = true;
  }

  KfStep<T> step_time_varying(T z, bool update) {
    if (!u_valid_) {
      compute_u();
    }
    // Prior of the mean: variance c^T u + qJJ, its cross terms v = D u + qJ, its estimate c^T x.
    T pjj = qjj_;
    T xj = T(0);
    T* const v = v_;  // scratch members, not locals: no zeroing per step
    for (std::size_t i = 0; i < n1_; ++i) {
      v[i] = dd_[i] * u_[i] + qj_[i];
      pjj += c_[i] * u_[i];
      xj += c_[i] * x_[i];
    }
    for (std::size_t i = n1_; i < n_; ++i) {
      v[i] = dd_[i] * u_[i] + do_[i] * u_[partner(i)] + qj_[i];
      pjj += c_[i] * u_[i];
      xj += c_[i] * x_[i];
    }
    ++stats_.predictions;
    KfStep<T> out;
    T* const k = k_;  // 0 without an update: x = D x, P = D P D^T + Qb
    T kj = T(0);
    T e = T(0);
    if (update) {
      const T s = pjj + r_;
      e = (z - known_) - xj;
      const T inv_s = T(1) / s;
      for (std::size_t i = 0; i < n_; ++i) {
        k[i] = v[i] * inv_s;
      }
      kj = pjj * inv_s;
      xj += kj * e;
      pjj = pjj * r_ * inv_s;
      ++stats_.updates;
      out.updated = true;
      out.innovation = e;
      out.innovation_var = s;
    } else {
      for (std::size_t i = 0; i < n_; ++i) {
        k[i] = T(0);
      }
    }
    advance_state(k_, e);
    xj_ = xj;
    pjj_ = pjj;
    predict_and_update(k_, v_);
    bound_covariance();
    if (update) {
      track_convergence(k_, kj, out.innovation_var);
    } else {
      block_updates_ = 0;  // a block is consecutive updates
    }
    return out;
  }

  // x = D x + K e in place (a 2-state block's pair from both old values).
  void advance_state(const T (&k)[kMaxProcess], T e) {
    for (std::size_t i = 0; i < n1_; ++i) {
      x_[i] = dd_[i] * x_[i] + k[i] * e;
    }
    for (std::size_t a = n1_; a < n_; a += 2) {
      const T xa = x_[a];
      const T xb = x_[a + 1];
      x_[a] = dd_[a] * xa + do_[a] * xb + k[a] * e;
      x_[a + 1] = do_[a + 1] * xa + dd_[a + 1] * xb + k[a + 1] * e;
    }
  }

  // Ppp = D Ppp D^T + Qb - K v^T in place, with the next step's u = Ppp c from the new entries,
  // row by row in order: the rows of 1-state blocks (the first n1_), then those of the 2-state
  // blocks. u_[i] is first written by row i (earlier rows only touch u_[j], j < i), so nothing
  // zeroes it first.
  void predict_and_update(const T (&k)[kMaxProcess], const T (&v)[kMaxProcess]) {
    update_one_state_rows(k, v);
    update_two_state_rows(k, v);
    u_valid_ = true;
  }

  // Rows of 1-state blocks: each entry needs only its own old value. They go in pairs: a
  // column's D, v, c and u are loaded once for both rows (the same operations in the same order
  // as one row after the other). With n1_ odd, row 0 goes alone first: it is only its diagonal.
  void update_one_state_rows(const T (&k)[kMaxProcess], const T (&v)[kMaxProcess]) {
    std::size_t i = n1_ % 2;
    if (i == 1) {
      const T p00 = dd_[0] * p_[0] * dd_[0] + qd_[0] - k[0] * v[0];
      p_[0] = p00;
      u_[0] = p00 * c_[0];
    }
    for (; i < n1_; i += 2) {
      const std::size_t i1 = i + 1;
      T* r0 = p_ + row_[i];
      T* r1 = p_ + row_[i1];
      const T d0 = dd_[i];
      const T d1 = dd_[i1];
      const T k0 = k[i];
      const T k1 = k[i1];
      const T c0 = c_[i];
      const T c1 = c_[i1];
      T acc0 = T(0);
      T acc1 = T(0);
      for (std::size_t j = 0; j < i; ++j) {
        const T dj = dd_[j];
        const T vj = v[j];
        const T cj = c_[j];
        const T p0 = d0 * r0[j] * dj - k0 * vj;
        const T p1 = d1 * r1[j] * dj - k1 * vj;
        r0[j] = p0;
        r1[j] = p1;
        acc0 += p0 * cj;
        acc1 += p1 * cj;
        u_[j] = (u_[j] + p0 * c0) + p1 * c1;
      }
      const T p00 = d0 * r0[i] * d0 + qd_[i] - k0 * v[i];
      const T p10 = d1 * r1[i] * d0 - k1 * v[i];
      const T p11 = d1 * r1[i1] * d1 + qd_[i1] - k1 * v[i1];
      r0[i] = p00;
      r1[i] = p10;
      r1[i1] = p11;
      u_[i] = (acc0 + p00 * c0) + p10 * c1;
      acc1 += p10 * c0;
      u_[i1] = acc1 + p11 * c1;
    }
  }

  // Rows of a 2-state block (a, a + 1): both rows are computed from their old values before
  // either is stored (the entry (a, a + 1) is in row a + 1).
  void update_two_state_rows(const T (&k)[kMaxProcess], const T (&v)[kMaxProcess]) {
    T* const ra_new = ra_new_;
    T* const rb_new = rb_new_;
    for (std::size_t a = n1_; a < n_; a += 2) {
      const std::size_t b = a + 1;
      T* ra = p_ + row_[a];
      T* rb = p_ + row_[b];
      const T daa = dd_[a];
      const T dab = do_[a];
      const T dba = do_[b];
      const T dbb = dd_[b];
      T acc_a = T(0);
      T acc_b = T(0);
      // Columns of the earlier blocks: (D_blk old(rows a, b; cols of j's block) D_j^T).
      for (std::size_t j = 0; j < a; ++j) {
        const std::size_t pj = partner(j);
        const T oa = daa * ra[j] + dab * rb[j];  // (D_blk old)(a, j)
        const T ob = dba * ra[j] + dbb * rb[j];
        T na = oa * dd_[j];
        T nb = ob * dd_[j];
        if (pj != j) {  // j in a 2-state block: its partner's column too
          const T oa_p = daa * ra[pj] + dab * rb[pj];
          const T ob_p = dba * ra[pj] + dbb * rb[pj];
          na += oa_p * do_[j];
          nb += ob_p * do_[j];
        }
        ra_new[j] = na - k[a] * v[j];
        rb_new[j] = nb - k[b] * v[j];
      }
      // The diagonal tile: old [[p_aa, p_ba], [p_ba, p_bb]].
      const T paa = ra[a];
      const T pba = rb[a];
      const T pbb = rb[b];
      const T ma = daa * paa + dab * pba;  // (D old)(a, a), (a, b), (b, a), (b, b)
      const T mab = daa * pba + dab * pbb;
      const T mb = dba * paa + dbb * pba;
      const T mbb = dba * pba + dbb * pbb;
      const T new_aa = ma * daa + mab * dab + qd_[a] - k[a] * v[a];
      const T new_ba = mb * daa + mbb * dab + qo_[b] - k[b] * v[a];
      const T new_bb = mb * dba + mbb * dbb + qd_[b] - k[b] * v[b];
      for (std::size_t j = 0; j < a; ++j) {
        ra[j] = ra_new[j];
        rb[j] = rb_new[j];
        acc_a += ra[j] * c_[j];
        acc_b += rb[j] * c_[j];
        u_[j] += ra[j] * c_[a] + rb[j] * c_[b];
      }
      ra[a] = new_aa;
      rb[a] = new_ba;
      rb[b] = new_bb;
      u_[a] = acc_a + new_aa * c_[a] + new_ba * c_[b];
      u_[b] = acc_b + new_ba * c_[a] + new_bb * c_[b];
    }
  }

  // Diagonal floor at 0; a diagonal above p_max scales its row and column (D P D, D > 0
  // diagonal, keeps P positive semi-definite). Either makes u stale.
  void bound_covariance() {
    for (std::size_t i = 0; i < n_; ++i) {
      T& pii = p_[row_[i] + i];
      if (pii < T(0)) {
        pii = T(0);
        ++stats_.covariance_floored;
        u_valid_ = false;
      } else if (pii > p_max_) {
        const T sc = std::sqrt(p_max_ / pii);
        for (std::size_t j = 0; j < n_; ++j) {
          p_[j <= i ? row_[i] + j : row_[j] + i] *= sc;
        }
        pii *= sc;  // the diagonal is in both the row and the column
        ++stats_.covariance_capped;
        u_valid_ = false;
      }
    }
  }

  // Frozen K and S: J = c^T x, e = z - known - J, x = D x + K e, J += K_J e.
  KfStep<T> step_steady(T z) {
    T xj = T(0);
    for (std::size_t i = 0; i < n_; ++i) {
      xj += c_[i] * x_[i];
    }
    const T e = (z - known_) - xj;
    advance_state(k_ss_, e);
    xj_ = xj + kj_ss_ * e;
    ++stats_.predictions;
    ++stats_.updates;
    KfStep<T> out;
    out.updated = true;
    out.innovation = e;
    out.innovation_var = s_ss_;
    return out;
  }

  void reset_convergence() {
    steady_ = false;
    block_updates_ = 0;
  }

  // After each time-varying update: compare K and S with the block's first; freeze when a block
  // of kSteadyBlock consecutive updates changed them by at most kSteadyTol (relative to the
  // largest gain, the absolute floor for entries that are zero).
  void track_convergence(const T (&k)[kMaxProcess], T kj, T s) {
    if (!steady_enabled_ || !steady_allowed_) {
      return;
    }
    if (block_updates_ == 0) {
      for (std::size_t i = 0; i < n_; ++i) {
        k_ss_[i] = k[i];
      }
      kj_ss_ = kj;
      s_ss_ = s;
    }
    if (++block_updates_ < kSteadyBlock) {
      return;
    }
    block_updates_ = 0;
    T kmax = std::fabs(kj_ss_);
    T dmax = std::fabs(kj - kj_ss_);
    for (std::size_t i = 0; i < n_; ++i) {
      const T a = std::fabs(k_ss_[i]);
      const T d = std::fabs(k[i] - k_ss_[i]);
      kmax = a > kmax ? a : kmax;
      dmax = d > dmax ? d : dmax;
    }
    const T tol = static_cast<T>(kSteadyTol);
    const bool settled = dmax <= tol * kmax && std::fabs(s - s_ss_) <= tol * s_ss_;
    for (std::size_t i = 0; i < n_; ++i) {
      k_ss_[i] = k[i];
    }
    kj_ss_ = kj;
    s_ss_ = s;
    steady_ = settled;
  }

  T p_[kPacked] = {};             // process covariance, packed lower triangle, filter's order
  T u_[kMaxProcess] = {};         // Ppp c of the current Ppp (u_valid_)
  T v_[kMaxProcess] = {};         // a step's P'(p, J) and gain: scratch, written before read
  T k_[kMaxProcess] = {};
  T ra_new_[kMaxProcess] = {};    // a 2-state block's new rows before they are stored
  T rb_new_[kMaxProcess] = {};
  T dd_[kMaxProcess] = {};        // D(i, i)
  T do_[kMaxProcess] = {};        // D(i, partner): 0 in a 1-state block
  T qd_[kMaxProcess] = {};        // Qb(i, i)
  T qo_[kMaxProcess] = {};        // Qb(i, partner)
  T c_[kMaxProcess] = {};         // Phi(J, i)
  T qj_[kMaxProcess] = {};        // Qd(i, J)
  T x_[kMaxProcess] = {};
  T k_ss_[kMaxProcess] = {};
  T qjj_ = T(0);
  T pjj_ = T(0);                  // variance of J after the last step
  T xj_ = T(0);
  T kj_ss_ = T(0);
  T s_ss_ = T(0);
  T r_ = T(1);
  T known_ = T(0);
  T p_max_ = T(1);
  KfStats stats_{};
  std::uint32_t block_updates_ = 0;
  std::size_t n_ = 0;
  std::size_t n1_ = 0;            // states in 1-state blocks, first in the filter's order
  Index from_[kMaxProcess] = {};  // the model's index of the filter's state i
  Row row_[kMaxProcess] = {};     // packed offset of row i
  bool u_valid_ = false;
  bool steady_enabled_ = false;
  bool steady_allowed_ = true;
  bool steady_ = false;
};

}  // namespace imu

#endif  // IMU_AVERAGED_KF_HPP

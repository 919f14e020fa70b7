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
    double pmax = m.p0(n, n) > m.qd(n, n) ? m.p0(n, n) : m.qd(n, n);
    for (std::size_t i = 0; i < n;) {
      const std::size_t size = i + 1 < n && coupled(m, i, i + 1) ? 2U : 1U;
      f.block_start_[f.n_blocks_] = static_cast<Index>(i);
      f.block_size_[f.n_blocks_] = static_cast<Index>(size);
      ++f.n_blocks_;
      for (std::size_t a = i; a < i + size; ++a) {
        f.block_col_[a] = static_cast<Index>(i);
        f.block_of_size2_[a] = size == 2;
        for (std::size_t b = 0; b < size; ++b) {
          f.d_[a][b] = static_cast<T>(m.phi(a, i + b));
          f.qb_[a][b] = static_cast<T>(m.qd(a, i + b));
        }
        f.c_[a] = static_cast<T>(m.phi(n, a));
        f.qj_[a] = static_cast<T>(m.qd(a, n));
        pmax = m.p0(a, a) > pmax ? m.p0(a, a) : pmax;
        pmax = m.qd(a, a) > pmax ? m.qd(a, a) : pmax;
        // Persistent and undriven (a row of D but no drive): the gain never settles.
        if (!(m.qd(a, a) > 0.0)) {
          f.steady_allowed_ = false;
        }
      }
      i += size;
    }
    for (std::size_t i = 0; i < n; ++i) {
      f.row_[i] = static_cast<Row>(i * (i + 1) / 2);
      for (std::size_t j = 0; j <= i; ++j) {
        f.p_[packed(i, j)] = static_cast<T>(m.p0(i, j));
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
  /// Process state i's estimate (i < process_states()).
  [[nodiscard]] T state(std::size_t i) const { return i < n_ ? x_[i] : T(0); }
  /// Process covariance entry (i, j) (i, j < process_states()).
  [[nodiscard]] T covariance(std::size_t i, std::size_t j) const {
    return i < n_ && j < n_ ? p_[packed(i, j)] : T(0);
  }
  [[nodiscard]] const KfStats& stats() const { return stats_; }

 private:
  using Index = std::uint8_t;
  using Row = std::conditional_t<(kPacked < 256), std::uint8_t, std::uint16_t>;

  // Lower-triangle packed index of (i, j), either order.
  static constexpr std::size_t packed(std::size_t i, std::size_t j) {
    return i >= j ? i * (i + 1) / 2 + j : j * (j + 1) / 2 + i;
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
    std::size_t start[kMaxProcess] = {};
    std::size_t size[kMaxProcess] = {};
    std::size_t nb = 0;
    for (std::size_t i = 0; i < n;) {
      const std::size_t s = i + 1 < n && coupled(m, i, i + 1) ? 2U : 1U;
      start[nb] = i;
      size[nb++] = s;
      i += s;
    }
    for (std::size_t b = 0; b < nb; ++b) {
      for (std::size_t i = start[b]; i < start[b] + size[b]; ++i) {
        for (std::size_t j = 0; j < n; ++j) {
          const bool inside = j >= start[b] && j < start[b] + size[b];
          if (!inside && coupled(m, i, j)) {
            return false;
          }
        }
      }
    }
    return true;
  }

  KfStep<T> step_time_varying(T z, bool update) {
    // u = Ppp c over the packed lower triangle.
    T u[kMaxProcess] = {};
    for (std::size_t i = 0; i < n_; ++i) {
      const T* row = p_ + row_[i];
      const T ci = c_[i];
      T acc = T(0);
      for (std::size_t j = 0; j < i; ++j) {
        acc += row[j] * c_[j];
        u[j] += row[j] * ci;
      }
      u[i] += acc + row[i] * ci;
    }
    // Prior of the mean: variance c^T u + qJJ and the cross terms v = D u + qJ; state and mean.
    T pjj = qjj_;
    T xj = T(0);
    T v[kMaxProcess] = {};
    T xn[kMaxProcess] = {};
    for (std::size_t b = 0; b < n_blocks_; ++b) {
      const std::size_t s0 = block_start_[b];
      const std::size_t sz = block_size_[b];
      for (std::size_t a = s0; a < s0 + sz; ++a) {
        T du = T(0);
        T dx = T(0);
        for (std::size_t k = 0; k < sz; ++k) {
          du += d_[a][k] * u[s0 + k];
          dx += d_[a][k] * x_[s0 + k];
        }
        v[a] = du + qj_[a];
        xn[a] = dx;
        pjj += c_[a] * u[a];
        xj += c_[a] * x_[a];
      }
    }
    ++stats_.predictions;
    KfStep<T> out;
    T k[kMaxProcess] = {};
    T kj = T(0);
    if (update) {
      const T s = pjj + r_;
      const T e = (z - known_) - xj;
      const T inv_s = T(1) / s;
      for (std::size_t i = 0; i < n_; ++i) {
        k[i] = v[i] * inv_s;
        xn[i] += k[i] * e;
      }
      kj = pjj * inv_s;
      xj += kj * e;
      pjj = pjj * r_ * inv_s;
      ++stats_.updates;
      out.updated = true;
      out.innovation = e;
      out.innovation_var = s;
    }
    for (std::size_t i = 0; i < n_; ++i) {
      x_[i] = xn[i];
    }
    xj_ = xj;
    pjj_ = pjj;
    predict_and_update_rows(k, v);
    bound_covariance();
    if (update) {
      track_convergence(k, kj, out.innovation_var);
    } else {
      block_updates_ = 0;  // a block is consecutive updates
    }
    return out;
  }

  // Ppp = D Ppp D^T + Qb - K v^T, one block of rows at a time: the rows A = D_b Ppp(b, :) of
  // block b read only the old rows of b (the entries right of the diagonal inside a 2-state
  // block are in its second row), and the new rows of b, (A D^T)(i, j) for j <= i, need only A:
  // so the rows of b are overwritten once both are computed, in place, in packed order.
  void predict_and_update_rows(const T (&k)[kMaxProcess], const T (&v)[kMaxProcess]) {
    T a_rows[2][kMaxProcess] = {};
    for (std::size_t b = 0; b < n_blocks_; ++b) {
      const std::size_t i0 = block_start_[b];
      const std::size_t nb = block_size_[b];
      const std::size_t width = i0 + nb;  // columns 0 .. the block's last state
      for (std::size_t r = 0; r < nb; ++r) {
        const std::size_t i = i0 + r;
        T* a = a_rows[r];
        const T d0 = d_[i][0];
        const T* p0 = p_ + row_[i0];  // row i0: columns 0 .. i0
        for (std::size_t y = 0; y <= i0; ++y) {
          a[y] = d0 * p0[y];
        }
        if (nb == 2) {
          const T d1 = d_[i][1];
          const T* p1 = p_ + row_[i0 + 1];  // row i0 + 1: columns 0 .. i0 + 1
          for (std::size_t y = 0; y <= i0; ++y) {
            a[y] += d1 * p1[y];
          }
          a[i0 + 1] = d0 * p1[i0] + d1 * p1[i0 + 1];  // old(i0, i0 + 1) = old(i0 + 1, i0)
        }
        (void)width;
      }
      for (std::size_t r = 0; r < nb; ++r) {
        const std::size_t i = i0 + r;
        const T* a = a_rows[r];
        T* row = p_ + row_[i];
        const T ki = k[i];
        for (std::size_t j = 0; j <= i; ++j) {
          const std::size_t j0 = block_col_[j];
          T acc = a[j0] * d_[j][0];
          if (block_of_size2_[j]) {
            acc += a[j0 + 1] * d_[j][1];
          }
          row[j] = acc - ki * v[j];
        }
        for (std::size_t j = i0; j <= i; ++j) {
          row[j] += qb_[i][j - i0];  // Qb inside the block
        }
      }
    }
  }

  // Diagonal floor at 0; a diagonal above p_max scales its row and column (D P D, D > 0
  // diagonal, keeps P positive semi-definite).
  void bound_covariance() {
    for (std::size_t i = 0; i < n_; ++i) {
      T& pii = p_[packed(i, i)];
      if (pii < T(0)) {
        pii = T(0);
        ++stats_.covariance_floored;
      } else if (pii > p_max_) {
        const T sc = std::sqrt(p_max_ / pii);
        for (std::size_t j = 0; j < n_; ++j) {
          p_[packed(i, j)] *= sc;
        }
        p_[packed(i, i)] *= sc;  // the diagonal is in both the row and the column
        ++stats_.covariance_capped;
      }
    }
  }

  // Frozen K and S: J = c^T x, x = D x, e = z - known - J, x += K e, J += K_J e.
  KfStep<T> step_steady(T z) {
    T xj = T(0);
    T xn[kMaxProcess] = {};
    for (std::size_t b = 0; b < n_blocks_; ++b) {
      const std::size_t s0 = block_start_[b];
      const std::size_t sz = block_size_[b];
      for (std::size_t a = s0; a < s0 + sz; ++a) {
        T dx = T(0);
        for (std::size_t q = 0; q < sz; ++q) {
          dx += d_[a][q] * x_[s0 + q];
        }
        xn[a] = dx;
        xj += c_[a] * x_[a];
      }
    }
    const T e = (z - known_) - xj;
    for (std::size_t i = 0; i < n_; ++i) {
      x_[i] = xn[i] + k_ss_[i] * e;
    }
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

  T p_[kPacked] = {};             // process covariance, packed lower triangle
  T d_[kMaxProcess][2] = {};      // D: row a's entries in its block's columns
  T qb_[kMaxProcess][2] = {};     // Qb likewise
  T c_[kMaxProcess] = {};         // Phi(J, p)
  T qj_[kMaxProcess] = {};        // Qd(p, J)
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
  std::size_t n_blocks_ = 0;
  Index block_start_[kMaxProcess] = {};
  Index block_size_[kMaxProcess] = {};
  Index block_col_[kMaxProcess] = {};    // first state of state i's block
  bool block_of_size2_[kMaxProcess] = {};
  Row row_[kMaxProcess] = {};            // packed offset of row i
  bool steady_enabled_ = false;
  bool steady_allowed_ = true;
  bool steady_ = false;
};

}  // namespace imu

#endif  // IMU_AVERAGED_KF_HPP

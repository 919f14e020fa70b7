// Bias Kalman filters on target: scalar (first-order GM, the first-order model) and n-state (any
// DiscreteModel), templated on the arithmetic type (float on the Cortex-M4F, double on the host).
//
// Per sample (step()):
//   1. predict: x = Phi x, P = Phi P Phi^T + Qd (always, every sample);
//   2. if the caller says the sensor is static: innovation e = (z - known_signal) - H x,
//      S = H P H^T + R, K = P H^T / S, x += K e, Joseph form P = (I - K H) P (I - K H)^T + K R K^T
//      (positive semi-definite by construction, also in float), then P is symmetrised.
// The known signal (e.g. local gravity projected on a vertical accelerometer, in the channel's
// units) is a parameter: set_known_signal(). R is DiscreteModel::r_filter(): white noise plus the
// quantization MA(1) variance treated as white (error_model.hpp explains the approximation).
// Non-finite z is not used (counted in stats.rejected_nonfinite, prediction still done).
// Diagonal entries of P are floored at 0 and capped at p_max (stats counters; the n-state
// filter caps by scaling row and column, which keeps P positive semi-definite), so P stays
// positive and bounded even for a random-walk state that is never observed.
//
// Float accuracy: the model is discretised in double and rounded to T once. Per-sample rounding
// in float is ~6e-8 relative; the filter is stable (|Phi (1 - K H)| < 1) so errors do not
// accumulate: test_bias_kf measures float vs double over 1e6 samples.
//
// Cost per sample: scalar 1 predict = 4 flops, update +~12 flops, 1 division; n-state predict
// 4 z n flops (z: non-zero entries of Phi, n <= z <= n^2; the node's 9-state models have 16),
// update ~6 n^2 h flops (h: non-zero entries of H, 1 for the node's models; Joseph form without
// forming I - K H). No heap, not re-entrant on one instance. sizeof(ScalarBiasKf<float>) is the
// whole state (see the benchmark).
//
// Steady-state gain (KalmanFilter, opt-in: set_steady_state(true)). With a time-invariant model
// and a measurement every sample, P converges to the solution of the discrete algebraic Riccati
// equation and K, S to constants. The filter runs time-varying and compares K and S at the ends
// of blocks of kSteadyBlock consecutive updates: when every |K_i - K_i'| <= kSteadyTol max_j |K_j|
// and |S - S'| <= kSteadyTol S (the norm-relative form is the absolute floor for entries that
// are zero, e.g. inert states), K and S are frozen and each sample costs x = Phi x over Phi's
// non-zero entries only (a list built at configure: the node's 9-state models are diagonal plus
// the averaging sampler's row, 16 of 81 entries), e = z - known - H x, x += K e. P stays the
// posterior of the last time-varying update (the steady state: bias_variance() is still right),
// the step reports S (innovation_var: NIS stays consistent). A sample without an update (not
// static, non-finite z: a gap in the measurements) makes P grow again: the filter drops back
// to the time-varying form from that P, and re-freezes only after a new converged block.
// Models with a persistent state that no noise drives (Qd(i,i) = 0 with a non-zero row of Phi:
// sinusoids, ramps) never freeze: their P decays as 1/k (sinusoid) or faster, the gain never
// settles, and a frozen one would forget what the filter has averaged. They stay time-varying.
// Inert states (Phi row = 0) do not prevent it.
#ifndef IMU_BIAS_KF_HPP
#define IMU_BIAS_KF_HPP

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "imu/error_model.hpp"
#include "imu/linalg.hpp"

namespace imu {

enum class KfStatus : std::uint8_t {
  kOk = 0,
  kBadModel,  ///< dimension mismatch, non-finite or negative variance, |phi| > 1
};

/// What one step did.
template <typename T>
struct KfStep {
  bool updated = false;  ///< the measurement was used
  T innovation = T(0);   ///< e = z - known - H x (prior), 0 when not updated
  T innovation_var = T(0);  ///< S
  /// e^2 / S, computed on request: the target's filters do not read it, so step() does not pay
  /// the division.
  [[nodiscard]] T nis() const {
    return innovation_var > T(0) ? innovation * innovation / innovation_var : T(0);
  }
};

struct KfStats {
  std::uint64_t predictions = 0;
  std::uint64_t updates = 0;
  std::uint64_t rejected_nonfinite = 0;  ///< static samples with non-finite z (not used)
  std::uint64_t covariance_floored = 0;  ///< a diagonal of P was < 0 and was set to 0
  std::uint64_t covariance_capped = 0;   ///< a diagonal of P exceeded p_max and was capped
};

/// Scalar filter for z = b + n, b_{k+1} = phi b_k + w_k.
template <typename T>
class ScalarBiasKf {
 public:
  /// From the first-order model (phi, Qw, Qn). p0: initial bias variance (default: Pss, i.e. the bias
  /// is unknown within its steady-state spread); b0: initial bias.
  [[nodiscard]] KfStatus configure(const FirstOrderGm& m, double known_signal = 0.0) {
    return configure(m.phi, m.qw, m.qn, m.pss_d, 0.0, known_signal);
  }
  /// From any 1-state DiscreteModel (r = r_filter()).
  [[nodiscard]] KfStatus configure(const DiscreteModel<1>& m, double known_signal = 0.0) {
    if (m.n_states != 1 || std::fabs(m.h(0, 0) - 1.0) > 0.0) {  // every 1-state term has H = 1
      return KfStatus::kBadModel;
    }
    return configure(m.phi(0, 0), m.qd(0, 0), m.r_filter(), m.p0(0, 0), 0.0,
                     known_signal);
  }
  [[nodiscard]] KfStatus configure(double phi, double qw, double r, double p0, double b0,
                                   double known_signal) {
    if (!std::isfinite(phi) || !(std::fabs(phi) <= 1.0) || !(qw >= 0.0) || !(r > 0.0) ||
        !(p0 >= 0.0) || !std::isfinite(qw + r + p0 + b0 + known_signal)) {
      return KfStatus::kBadModel;
    }
    phi_ = static_cast<T>(phi);
    qw_ = static_cast<T>(qw);
    r_ = static_cast<T>(r);
    b_ = static_cast<T>(b0);
    p_ = static_cast<T>(p0);
    known_ = static_cast<T>(known_signal);
    // Bound: the larger of p0 and the open-loop steady state, times 10.
    const double pss = phi * phi < 1.0 ? qw / (1.0 - phi * phi) : 1e30;
    p_max_ = static_cast<T>(10.0 * (p0 > pss ? p0 : pss));
    stats_ = KfStats{};
    return KfStatus::kOk;
  }

  void set_known_signal(T known) { known_ = known; }

  /// One sample: predict, then update if is_static. Constant time.
  KfStep<T> step(T z, bool is_static) {
    b_ = phi_ * b_;
    p_ = phi_ * phi_ * p_ + qw_;
    ++stats_.predictions;
    KfStep<T> out;
    if (is_static) {
      if (!std::isfinite(z)) {
        ++stats_.rejected_nonfinite;
      } else {
        const T e = (z - known_) - b_;
        const T s = p_ + r_;
        const T k = p_ / s;
        b_ += k * e;
        const T one_k = T(1) - k;
        p_ = one_k * one_k * p_ + k * k * r_;  // Joseph form
        ++stats_.updates;
        out.updated = true;
        out.innovation = e;
        out.innovation_var = s;
      }
    }
    if (p_ < T(0)) {
      p_ = T(0);
      ++stats_.covariance_floored;
    } else if (p_ > p_max_) {
      p_ = p_max_;
      ++stats_.covariance_capped;
    }
    return out;
  }

  /// k samples without a measurement (e.g. lost frames): the same as k calls of step(z, false)
  /// but constant time for any k. Up to kExactPredictSteps it is that loop (bit-identical
  /// results); above, the closed form in double, rounded to T once:
  ///   b_k = phi^k b,  P_k = phi^(2k) P + Qw (1 - phi^(2k)) / (1 - phi^2)  (P + k Qw if phi^2 = 1),
  /// which for k far beyond the correlation time is the steady state Qw / (1 - phi^2) and b = 0
  /// (phi^k underflows to 0: the prediction has forgotten everything). P is capped as in step().
  void predict(std::uint64_t k) {
    if (k <= kExactPredictSteps) {
      for (std::uint64_t i = 0; i < k; ++i) {
        (void)step(T(0), false);
      }
      return;
    }
    const double phi = static_cast<double>(phi_);
    const double qw = static_cast<double>(qw_);
    const double kd = static_cast<double>(k);
    const double phi_k = std::pow(phi, kd);
    const double phi_2k = phi_k * phi_k;
    const double one_m_phi2 = 1.0 - phi * phi;
    const double drive = one_m_phi2 > 0.0 ? qw * (1.0 - phi_2k) / one_m_phi2 : qw * kd;
    const double p = phi_2k * static_cast<double>(p_) + drive;
    b_ = static_cast<T>(phi_k * static_cast<double>(b_));
    stats_.predictions += k;
    if (!(p <= static_cast<double>(p_max_))) {  // also a non-finite drive (qw k overflow)
      p_ = p_max_;
      ++stats_.covariance_capped;
    } else {
      p_ = static_cast<T>(p);
    }
  }
  /// predict(k) for k up to this is a loop of step() (exact); above it is the closed form.
  static constexpr std::uint64_t kExactPredictSteps = 64;

  [[nodiscard]] T bias() const { return b_; }
  [[nodiscard]] T variance() const { return p_; }
  [[nodiscard]] const KfStats& stats() const { return stats_; }

 private:
  T phi_ = T(1);
  T qw_ = T(0);
  T r_ = T(1);
  T b_ = T(0);
  T p_ = T(0);
  T known_ = T(0);
  T p_max_ = T(1);
  KfStats stats_{};
};

/// n-state filter for a DiscreteModel with exactly N states (N = model.n_states).
template <typename T, std::size_t N>
class KalmanFilter {
 public:
  using Vec = Mat<T, N, 1>;
  using Square = Mat<T, N, N>;

  /// The model's P0 is the initial covariance, x0 = 0. kBadModel if model.n_states != N or the
  /// model has non-finite entries.
  template <std::size_t kMaxStates>
  [[nodiscard]] KfStatus configure(const DiscreteModel<kMaxStates>& m, double known_signal = 0.0) {
    static_assert(N <= kMaxStates, "filter larger than the model capacity");
    if (m.n_states != N || !(m.r_filter() > 0.0) || !std::isfinite(known_signal)) {
      return KfStatus::kBadModel;
    }
    double pmax = 0.0;
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t j = 0; j < N; ++j) {
        if (!std::isfinite(m.phi(i, j)) || !std::isfinite(m.qd(i, j)) ||
            !std::isfinite(m.p0(i, j))) {
          return KfStatus::kBadModel;
        }
        phi_(i, j) = static_cast<T>(m.phi(i, j));
        qd_(i, j) = static_cast<T>(m.qd(i, j));
        p_(i, j) = static_cast<T>(m.p0(i, j));
      }
      h_(0, i) = static_cast<T>(m.h(0, i));
      x_(i, 0) = T(0);
      pmax = m.p0(i, i) > pmax ? m.p0(i, i) : pmax;
      pmax = m.qd(i, i) > pmax ? m.qd(i, i) : pmax;
    }
    r_ = static_cast<T>(m.r_filter());
    known_ = static_cast<T>(known_signal);
    // Generous bound for states that are not mean-reverting (RRW, ramp): 1e6 x the largest
    // initial or per-step variance. Hitting it is counted, never silent.
    p_max_ = static_cast<T>(1e6 * (pmax > 0.0 ? pmax : 1.0));
    stats_ = KfStats{};
    index_phi(m);
    reset_convergence();
    return KfStatus::kOk;
  }

  void set_known_signal(T known) { known_ = known; }

  /// Allow (true) or forbid the frozen steady-state gain (see the file comment). Off by default.
  /// Turning it off returns to the time-varying filter at once.
  void set_steady_state(bool enabled) {
    steady_enabled_ = enabled;
    reset_convergence();
  }
  /// True while K and S are frozen.
  [[nodiscard]] bool steady() const { return steady_; }
  /// The model lets the gain freeze (no undriven persistent state).
  [[nodiscard]] bool steady_allowed() const { return steady_allowed_; }
  /// The frozen gain and innovation variance (meaningful while steady()).
  [[nodiscard]] const Vec& steady_gain() const { return k_ss_; }
  [[nodiscard]] T steady_innovation_var() const { return s_ss_; }
  /// Non-zero entries of Phi (what a steady-state step multiplies).
  [[nodiscard]] std::size_t phi_nonzeros() const { return row_start_[N]; }

  /// Updates per convergence block, and the relative change of K and S allowed over one block.
  static constexpr std::uint32_t kSteadyBlock = 256;
  static constexpr double kSteadyTol = 1e-6;

  /// One sample: predict, then update if is_static. Time-varying O(N x non-zeros of Phi + N^2 x
  /// non-zeros of H); with a frozen gain O(non-zeros of Phi + N).
  KfStep<T> step(T z, bool is_static) {
    if (steady_) {
      if (is_static && std::isfinite(z)) {
        return step_steady(z);
      }
      reset_convergence();  // no update: P grows, the time-varying filter takes over from here
    }
    return step_time_varying(z, is_static);
  }

  /// The bias the measurement sees, H x.
  [[nodiscard]] T bias() const { return h_times(x_); }
  /// Variance of H x: H P H^T.
  [[nodiscard]] T bias_variance() const {
    T s = T(0);
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t j = 0; j < N; ++j) {
        s += h_(0, i) * p_(i, j) * h_(0, j);
      }
    }
    return s;
  }
  [[nodiscard]] const Vec& state() const { return x_; }
  [[nodiscard]] const Square& covariance() const { return p_; }
  [[nodiscard]] const KfStats& stats() const { return stats_; }

 private:
  // The full filter: predict x and P, update with the Joseph form, floor and cap P.
  KfStep<T> step_time_varying(T z, bool is_static) {
    x_ = phi_times(x_);
    predict_covariance();
    ++stats_.predictions;
    KfStep<T> out;
    if (is_static) {
      if (!std::isfinite(z)) {
        ++stats_.rejected_nonfinite;
      } else {
        const Vec pht = times_ht(p_);
        const T s = h_times(pht, r_);
        const T e = (z - known_) - h_times(x_);
        Mat<T, N, 1> k{};
        for (std::size_t i = 0; i < N; ++i) {
          k(i, 0) = pht(i, 0) / s;
          x_(i, 0) += k(i, 0) * e;
        }
        joseph_update(k, pht);
        ++stats_.updates;
        out.updated = true;
        out.innovation = e;
        out.innovation_var = s;
        track_convergence(k, s);
      }
    }
    if (!out.updated) {
      block_updates_ = 0;  // a block is consecutive updates
    }
    symmetrize(p_);
    for (std::size_t i = 0; i < N; ++i) {
      if (p_(i, i) < T(0)) {
        p_(i, i) = T(0);
        ++stats_.covariance_floored;
      } else if (p_(i, i) > p_max_) {
        // Scale row and column i by s = sqrt(p_max / P_ii): D P D with D > 0 diagonal keeps P
        // positive semi-definite (clipping only the diagonal would not).
        const T sc = std::sqrt(p_max_ / p_(i, i));
        for (std::size_t j = 0; j < N; ++j) {
          p_(i, j) *= sc;
          p_(j, i) *= sc;
        }
        ++stats_.covariance_capped;
      }
    }
    return out;
  }
  // Frozen K and S: x = Phi x over the non-zeros of Phi, e = z - known - H x, x += K e.
  KfStep<T> step_steady(T z) {
    const Vec xp = phi_times(x_);
    const T e = (z - known_) - h_times(xp);
    for (std::size_t i = 0; i < N; ++i) {
      x_(i, 0) = xp(i, 0) + k_ss_(i, 0) * e;
    }
    ++stats_.predictions;
    ++stats_.updates;
    KfStep<T> out;
    out.updated = true;
    out.innovation = e;
    out.innovation_var = s_ss_;
    return out;
  }

  // init + H v over H's non-zero entries (in column order, added to init one by one).
  T h_times(const Vec& v, T init = T(0)) const {
    T acc = init;
    for (std::size_t q = 0; q < h_nnz_; ++q) {
      acc += h_(0, h_col_[q]) * v(h_col_[q], 0);
    }
    return acc;
  }
  // A H^T over H's non-zero entries.
  Vec times_ht(const Square& a) const {
    Vec out{};
    for (std::size_t i = 0; i < N; ++i) {
      T acc = T(0);
      for (std::size_t q = 0; q < h_nnz_; ++q) {
        acc += a(i, h_col_[q]) * h_(0, h_col_[q]);
      }
      out(i, 0) = acc;
    }
    return out;
  }

  // Phi v over Phi's non-zero entries (row by row, in column order).
  Vec phi_times(const Vec& v) const {
    Vec out{};
    for (std::size_t i = 0; i < N; ++i) {
      T acc = T(0);
      for (std::size_t q = row_start_[i]; q < row_start_[i + 1]; ++q) {
        acc += phi_(i, col_[q]) * v(col_[q], 0);
      }
      out(i, 0) = acc;
    }
    return out;
  }

  // P = Phi P Phi^T + Qd over Phi's non-zero entries: A = Phi P, then A Phi^T.
  void predict_covariance() {
    Square a{};
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t q = row_start_[i]; q < row_start_[i + 1]; ++q) {
        const T f = phi_(i, col_[q]);
        for (std::size_t j = 0; j < N; ++j) {
          a(i, j) += f * p_(col_[q], j);
        }
      }
    }
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t j = 0; j < N; ++j) {
        T acc = T(0);
        for (std::size_t q = row_start_[j]; q < row_start_[j + 1]; ++q) {
          acc += a(i, col_[q]) * phi_(j, col_[q]);
        }
        p_(i, j) = acc + qd_(i, j);
      }
    }
  }

  // Joseph form P = (I - K H) P (I - K H)^T + K R K^T without forming I - K H: with P symmetric,
  // A = (I - K H) P = P - K (P H^T)^T, then P = A - (A H^T) K^T + R K K^T, the last two terms
  // added as (R K_i - (A H^T)_i) K_j. O(N^2 x non-zeros of H).
  void joseph_update(const Vec& k, const Vec& pht) {
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t j = 0; j < N; ++j) {
        p_(i, j) -= k(i, 0) * pht(j, 0);
      }
    }
    const Vec aht = times_ht(p_);
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t j = 0; j < N; ++j) {
        p_(i, j) += (r_ * k(i, 0) - aht(i, 0)) * k(j, 0);
      }
    }
  }

  // Row-wise list of Phi's non-zero entries, the non-zero entries of H, and whether the model
  // lets the gain freeze.
  template <std::size_t kMaxStates>
  void index_phi(const DiscreteModel<kMaxStates>& m) {
    std::size_t q = 0;
    steady_allowed_ = true;
    for (std::size_t i = 0; i < N; ++i) {
      row_start_[i] = static_cast<Index>(q);
      bool row_zero = true;
      for (std::size_t j = 0; j < N; ++j) {
        if (std::fabs(phi_(i, j)) > T(0)) {
          col_[q++] = static_cast<Index>(j);
          row_zero = false;
        }
      }
      if (!row_zero && !(m.qd(i, i) > 0.0)) {
        steady_allowed_ = false;  // persistent and undriven: the gain never settles
      }
    }
    row_start_[N] = static_cast<Index>(q);
    h_nnz_ = 0;
    for (std::size_t j = 0; j < N; ++j) {
      if (std::fabs(h_(0, j)) > T(0)) {
        h_col_[h_nnz_++] = static_cast<Index>(j);
      }
    }
  }

  void reset_convergence() {
    steady_ = false;
    block_updates_ = 0;
  }

  // After each time-varying update: compare K and S with the block's first, freeze both when a
  // block of kSteadyBlock consecutive updates changed them by at most kSteadyTol (relative).
  void track_convergence(const Vec& k, T s) {
    if (!steady_enabled_ || !steady_allowed_) {
      return;
    }
    if (block_updates_ == 0) {
      k_ss_ = k;
      s_ss_ = s;
    }
    if (++block_updates_ < kSteadyBlock) {
      return;
    }
    block_updates_ = 0;
    T kmax = T(0);
    T dmax = T(0);
    for (std::size_t i = 0; i < N; ++i) {
      const T a = std::fabs(k_ss_(i, 0));
      const T d = std::fabs(k(i, 0) - k_ss_(i, 0));
      kmax = a > kmax ? a : kmax;
      dmax = d > dmax ? d : dmax;
    }
    const T tol = static_cast<T>(kSteadyTol);
    const bool settled = dmax <= tol * kmax && std::fabs(s - s_ss_) <= tol * s_ss_;
    k_ss_ = k;
    s_ss_ = s;
    steady_ = settled;
  }

  Square phi_{};
  Square qd_{};
  Square p_{};
  Mat<T, 1, N> h_{};
  Vec x_{};
  T r_ = T(1);
  T known_ = T(0);
  T p_max_ = T(1);
  KfStats stats_{};
  // Steady-state gain (see the file comment).
  Vec k_ss_{};
  T s_ss_ = T(0);
  std::uint32_t block_updates_ = 0;
  using Index = std::conditional_t<(N * N < 256), std::uint8_t, std::uint16_t>;
  Index row_start_[N + 1] = {};
  Index col_[N * N] = {};
  Index h_col_[N] = {};
  std::size_t h_nnz_ = 0;
  bool steady_enabled_ = false;
  bool steady_allowed_ = false;
  bool steady_ = false;
};

}  // namespace imu

#endif  // IMU_BIAS_KF_HPP

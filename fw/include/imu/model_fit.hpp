// Automatic fit of an error model to a measured Allan variance (MODELS.md "Weighted
// least-squares fit", CSM eqns. 63-64), fixed memory, runs on the target.
//
// For fixed correlation times the model AVAR is linear in theta = (N^2, Q^2, Sb_1, Sb_2, K^2,
// R^2, B^2) with basis functions 1/tau, 3/tau^2, g(tau; Tb_i), tau/3, tau^2/2 (g: MODELS.md GM
// formula with Sb = 1) and the flicker bank's AVAR at B = 1 (its times are fixed by its range). For each trial Tb the weighted least-squares problem
//     min sum_i w_i (sum_j theta_j f_j(tau_i) - avar_i)^2,  theta >= 0
// is solved by active-set NNLS (Lawson & Hanson) on the column-scaled normal equations. The
// correlation time is searched on a log grid (kGridPoints from tb_min_s to tb_max_s) and refined
// by golden-section search in log(Tb) around the best grid point; with two GM terms the two
// times are refined by coordinate search (alternating 1-D searches, kCoordinateRounds rounds).
// Weights: w_i = 1 / var(avar_i) with var = 2 avar^2 / edf_i (chi-square). The first pass uses
// the measured avar_i in var (unbiased for the scale but noisy), each of the
// `weight_iterations` further passes uses the previous fitted model's AVAR (iteratively
// reweighted least squares: removes the bias towards low measured values).
// Points outside [tau_min_s, tau_max_s] (with a relative slack of 1e-9), or with avar <= 0 or
// edf <= 0, are ignored.
// Not fitted: the sinusoid (nonlinear in f0; give it to the caller's own search).
//
// Cost: O(weight passes * (grid + golden) evaluations * n_points * p^2), p <= 6 parameters;
// ~1.5 ms on the host for white + GM on 48 points (198 solves), ~25 ms for white + 2 GM + RRW
// (1386 solves); see bench_bias_kf. Stack: ~5 kB (kMaxFitPoints points). No heap,
// re-entrant.
#ifndef IMU_MODEL_FIT_HPP
#define IMU_MODEL_FIT_HPP

#include <cstddef>
#include <cstdint>

#include "imu/error_model.hpp"
#include "imu/online_adev.hpp"

namespace imu {

/// Terms to fit (bit mask).
enum FitTerm : std::uint32_t {
  kFitWhite = 1U << 0,
  kFitQuantization = 1U << 1,
  kFitGm1 = 1U << 2,
  kFitGm2 = 1U << 3,  ///< requires kFitGm1
  kFitRrw = 1U << 4,
  kFitRamp = 1U << 5,
  kFitFlicker = 1U << 6,  ///< bias instability B (flicker bank over the flicker_tau range)
  kFitOscillation = 1U << 7,  ///< narrowband oscillation sigma^2 (osc_f0_hz, osc_beta fixed)
};

/// Largest number of ADEV points used (OnlineAdev<8, 22> reports at most 96).
inline constexpr std::size_t kMaxFitPoints = 128;

struct FitOptions {
  std::uint32_t terms = kFitWhite | kFitGm1;  ///< the example's "before" model
  double tau_min_s = 0.01;                     ///< the example's range [Ts, 100 s]
  double tau_max_s = 100.0;
  double tb_min_s = 0.0;  ///< correlation time search range; 0: tau_min_s
  double tb_max_s = 0.0;  ///< 0: 10 * tau_max_s
  /// > 0 (with kFitRrw): the walk's K held at this value, the other terms fitted beside it (a
  /// profile of the cost over K).
  double k_fixed = 0.0;
  int weight_iterations = 2;  ///< reweighting passes after the first (0..10)
  /// Upper limit on the EDF used in the weights (0: none, the pure CSM weighting). The
  /// estimates at neighbouring taus are strongly correlated, which 1/var weights ignore: with a
  /// model that cannot follow the data everywhere, the short taus (EDF ~1e6) then decide the
  /// fit alone. A cap (e.g. 1000) makes the fit closer to a relative least-squares fit.
  double edf_cap = 0.0;
  /// The tau range the bias-instability (flicker) bank covers (error_model.hpp flicker_bank);
  /// 0: tau_min_s / tau_max_s.
  double flicker_tau_lo_s = 0.0;
  double flicker_tau_hi_s = 0.0;
  /// The narrowband oscillation's shape (kFitOscillation fits its sigma^2 only): centre
  /// frequency [Hz] and damping rate [1/s], from the record's spectrum.
  double osc_f0_hz = 0.0;
  double osc_beta_per_s = 0.0;
  /// The record's sampling period: the oscillation's AVAR is of sample means
  /// (avar_oscillation_sampled; ModelParams::osc_ts_s). 0: continuous averages.
  double osc_ts_s = 0.0;
  /// The sensor's output filter the white noise is seen through (ModelParams::n_filter_s; the
  /// white basis is avar_white_filtered): fixed here, the caller searches it. 0: plain white.
  double white_filter_s = 0.0;
};

enum class FitStatus : std::uint8_t {
  kOk = 0,
  kBadOptions,     ///< empty/inverted range, no term, GM2 without GM1, iterations out of range
  kTooFewPoints,   ///< fewer usable points than fitted parameters
  kTooManyPoints,  ///< more than kMaxFitPoints usable points
  kSingular,       ///< the normal equations could not be solved for any trial Tb
};

struct FitResult {
  ModelParams params{};  ///< fitted parameters (zero for terms not fitted or clamped at 0)
  double cost = 0.0;     ///< weighted sum of squared residuals at the optimum (final weights)
  double rms_rel = 0.0;  ///< RMS of (model/measured - 1) of ADEV over the used points
  std::size_t n_points = 0;  ///< points inside the range and usable
  std::uint32_t evaluations = 0;  ///< NNLS solves performed
  /// A fitted correlation time lies within 1 % of the search range's end: the data do not
  /// determine it (e.g. the example's data over [Ts, 100 s] only see the GM's rising part, where
  /// AVAR ~ Sb tau / 3 depends on Sb alone). The fitted curve is still valid over the range.
  bool tb_at_bound = false;
  FitStatus status = FitStatus::kBadOptions;
};

/// Fit the selected terms to `points` (e.g. from OnlineAdev::snapshot). Preconditions: points
/// has n entries (any order). Returns the result with its status; params are meaningful only
/// for kOk.
[[nodiscard]] FitResult fit(const AdevPoint* points, std::size_t n, const FitOptions& options);

}  // namespace imu

#endif  // IMU_MODEL_FIT_HPP

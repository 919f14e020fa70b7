// Synthetic channels for the analysis tests: the first-order model (white N + one GM)
// simulated by fw ModelSimulator, plus, on request, each effect the analysis must find.
// Stochastic terms (quantization Q, rate random walk K) are simulated as model states; the
// deterministic ones are added to the output: ramp R (t - T/2), A sin(2 pi f t + phase), a bias
// step of `step_size` from `step_time_s` on, and `n_outliers` isolated spikes of
// +-outlier_size at random positions at least 100 samples apart. Deterministic in `seed`.
// Cost: O(n) (a few hundred ns per sample for a 3-state model). Host only.
#ifndef IMU_ANALYZE_SYNTH_HPP
#define IMU_ANALYZE_SYNTH_HPP

#include <cstddef>
#include <cstdint>
#include <vector>

namespace imu::analyze {

struct SynthSpec {
  double fs_hz = 100.0;
  std::size_t samples = 1000000;
  double n = 3.3e-3;    ///< example: N [unit/sqrt(Hz)]
  double b = 9e-4;      ///< example: B [unit]
  double tp_s = 300.0;  ///< example: Tp [s]
  double q = 0.0;       ///< quantization Q [unit s]
  double k = 0.0;       ///< rate random walk K [unit/sqrt(s)]
  double ramp_r = 0.0;  ///< [unit/s]
  double sin_a = 0.0;
  double sin_f_hz = 0.0;
  double step_time_s = 0.0;
  double step_size = 0.0;  ///< 0: no step
  std::size_t n_outliers = 0;
  double outlier_size = 0.0;
  double offset = 0.0;  ///< constant added (e.g. gravity)
  /// Bias instability B (IEEE Std 952 flicker, two-sided PSD (B^2 / 2 pi) / f): Kasdin's
  /// fractional integration of white noise (N. J. Kasdin, "Discrete simulation of colored
  /// noise and stochastic processes and 1/f^alpha power law noise generation", Proc. IEEE
  /// 83(5), 1995, eqn. 116 with alpha = 1: h_0 = 1, h_k = h_{k-1} (k - 1/2) / k) at period
  /// flicker_dt_s (0: the sample period), white variance B^2 (so S(f) ~ B^2 / (2 pi f)), held
  /// between its samples. Independent of the analysis's GM-bank realisation.
  double flicker_b = 0.0;
  double flicker_dt_s = 0.0;
  /// Not a term of the analysis (for "unexplained" tests): a random walk of the drift rate,
  /// d^2 b / dt^2 = w, PSD(w) = drift_walk^2 [unit / s^1.5]; AVAR ~ tau^3.
  double drift_walk = 0.0;
  /// Narrowband oscillation R(t) = osc_sigma^2 e^(-osc_beta |t|) cos(2 pi osc_f0 t), generated
  /// by its exact sampled recursion (a damped rotation of a 2-vector driven by white noise of
  /// variance osc_sigma^2 (1 - rho^2), rho = e^(-beta Ts)), written here independently of the
  /// analysis's Van Loan path.
  double osc_sigma = 0.0;
  double osc_f0_hz = 0.0;
  double osc_beta_per_s = 0.0;
  /// Logger dropouts: nan_gaps runs of nan_gap_len NaN samples at random positions.
  std::size_t nan_gaps = 0;
  std::size_t nan_gap_len = 0;
  std::uint64_t seed = 1;
};

/// Returns the samples (empty if the model could not be built: bad parameters).
[[nodiscard]] std::vector<double> synthesize(const SynthSpec& s);

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_SYNTH_HPP

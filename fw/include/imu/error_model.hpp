// Stochastic error models of one IMU channel: the first-order Gauss-Markov conversion,
// general fixed-capacity continuous models built from terms, exact (Van Loan) discretisation and
// the analytic Allan variance of every term (../shared/docs/MODELS.md).
//
// Continuous model:  x' = F x + w,  E[w(t) w(s)^T] = Qc delta(t - s),  z = H x + n + q,
//   n: white measurement noise of PSD Sn = N^2 (velocity/angle random walk N),
//   q: quantization noise Q, white in the INTEGRAL of z (AVAR 3 Q^2 / tau^2). Sampled at Ts it is
//      the first difference q_k = Q (u_k - u_{k-1}) / Ts of unit white noise u (an MA(1)
//      sequence): the simulator produces exactly that. The Kalman filters do NOT model the MA(1)
//      correlation: they treat it as extra white measurement variance 2 Q^2 / Ts^2
//      (DiscreteModel::r_filter()), a documented approximation that overstates the short-term
//      noise and is harmless when Q^2/Ts << N^2 (true for the ADIS16405 and the example).
// Terms and their states (appended in call order, kMaxStates in total):
//   white N (no state), quantization Q (no state),
//   white N through the sensor's first-order output filter of time constant Tf: 1 GM state
//           (Sb = N^2 / Tf^2, Tb = Tf; observe it with discretize_averaged),
//   first-order GM (Sb, Tb): 1 state, b' = -b/Tb + w, PSD(w) = Sb, prior Pss = Sb Tb / 2,
//   rate random walk K: 1 state, r' = w, PSD(w) = K^2, prior variance 0 (starts at 0),
//   ramp R: 2 states (d, s): d' = s, s' = 0, H picks d; prior var(s) = R^2 so that
//           E[AVAR] = R^2 tau^2 / 2,
//   sinusoid A sin(2 pi f0 t + random phase): 2-state undamped oscillator, prior A^2/2 per state
//           (a second one, e.g. a harmonic, with sin2_a / sin2_f0_hz),
//   bias instability B (flicker, IEEE Std 952: two-sided PSD (B^2 / 2 pi) / f, ADEV floor
//           0.664 B): realised over [bi_tau_lo_s, bi_tau_hi_s] by a bank of first-order GMs
//           (flicker_bank(): one per decade of Tb, drive PSDs in fixed ratio), one state each.
//   narrowband oscillation (sigma, f0, beta): a randomly driven, damped oscillator, the
//           "exponentially correlated cosine" R(t) = sigma^2 e^(-beta |t|) cos(2 pi f0 t)
//           (Brown & Hwang, Introduction to Random Signals and Applied Kalman Filtering, 4th
//           ed., table 2.1 / problem 3.x): a vibration mode or resonance, a peak of half-power
//           width beta / pi Hz in the PSD (a sinusoid is its limit beta -> 0). 2 states (a, b):
//           [a; b]' = [[-beta, -w], [w, -beta]] [a; b] + w, PSD(w) = 2 beta sigma^2 each,
//           H picks a, prior sigma^2 per state (stationary).
// Analytic AVAR: sum of the MODELS.md formulas (model_avar). For the sampled model the white,
// quantization and ramp formulas are exact at tau = m Ts; the GM, RRW and sinusoid formulas are
// the continuous-time ones (their sampled values differ by O(Ts/tau), < 1e-3 relative for
// tau >= 10 Ts on the first-order model).
//
// Cost: model_avar O(number of terms), a few exp(); discretize() O((2n)^3 log) once per model,
// never per sample. No heap, re-entrant.
#ifndef IMU_ERROR_MODEL_HPP
#define IMU_ERROR_MODEL_HPP

#include <cstddef>
#include <cstdint>

#include "imu/linalg.hpp"

namespace imu {

enum class ModelStatus : std::uint8_t {
  kOk = 0,
  kBadParameter,  ///< a parameter is negative, zero where it must be positive, or not finite
  kCapacity,      ///< the term does not fit in kMaxStates (or kMaxGmTerms)
  kNumerical,     ///< the matrix exponential or a factorisation failed
};

/// ADEV peak of a first-order GM: 0.4365 sqrt(Sb Tb) at tau = 1.89 Tb (MODELS.md, CSM eqn. 62).
inline constexpr double kGmPeakAdevFactor = 0.4365;
inline constexpr double kGmPeakTauFactor = 1.89;

/// The first-order model (MODELS.md "From ASD parameters to the first-order model").
struct FirstOrderGm {
  // inputs
  double n;      ///< velocity random walk N [unit/sqrt(Hz)]
  double b;      ///< bias instability B [unit]
  double tp_s;   ///< delay of the model's ADEV peak [s]
  double fs_hz;  ///< sample rate [Hz]
  // continuous model
  double tb_s;      ///< correlation time Tb = Tp / 1.89 [s]
  double mu_per_s;  ///< 1 / Tb [1/s]
  double sn;        ///< PSD of the white measurement noise, N^2
  double sb;        ///< PSD of the bias drive, B^2 / (0.4365^2 Tb)
  double pss;       ///< steady-state bias variance Sb / (2 mu)
  // discrete model (Ts = 1 / fs)
  double ts_s;
  double phi;    ///< exp(-mu Ts)
  double qn;     ///< measurement noise variance Sn Fs
  double qw;     ///< bias process noise variance (Van Loan, = (1 - phi^2) Sb / (2 mu))
  double pss_d;  ///< Qw / (1 - phi^2)
};

/// Conversion N, B, Tp, Fs -> continuous and discrete first-order model (Farrell's
/// ASD-to-state-space example). Qw is computed by Van Loan (expm), not by the closed form, so the
/// test of the closed form is independent.
/// Returns kBadParameter unless every input is finite and > 0 and every derived quantity is
/// usable by a filter: phi in [0, 1), Qw, Qn, Sb, Pss and Pss_d finite and > 0 (e.g. Tp = 1e300
/// gives phi = 1, N = 1e300 an infinite Qn: both refused).
[[nodiscard]] ModelStatus first_order_gm_from_asd(double n, double b, double tp_s, double fs_hz,
                                                  FirstOrderGm& out);

inline constexpr std::size_t kMaxGmTerms = 2;

/// Bias instability (flicker) as a sum of first-order GMs with correlation times spaced by a
/// fixed ratio (the classic sum-of-Lorentzians approximation of a 1/f spectrum: Keshner, "1/f
/// noise", Proc. IEEE 70(3), 1982, sec. V; Kasdin, Proc. IEEE 83(5), 1995). A GM of drive PSD Sb
/// and time Tb has the PSD Sb Tb^2 / (1 + (2 pi f Tb)^2); with Tb_i spaced by the ratio r and
/// Sb_i = 2 ln(r) B^2 / (pi Tb_i) the sum approaches (B^2 / 2 pi) / f between 1/(2 pi Tb_max)
/// and 1/(2 pi Tb_min). Bank: Tb_0 = tau_lo / 6, Tb_{i+1} = 10 Tb_i until Tb >= tau_hi. Its
/// ADEV is within -4.6 % / +0.8 % of the exact flicker floor sqrt(2 ln 2 / pi) B = 0.664 B on
/// [tau_lo, tau_hi] for a 3-decade range (5 states; test_error_model checks it on a grid),
/// and it falls off outside (white-like above, GM-like below): one state per decade + 2.
inline constexpr std::size_t kMaxFlickerGm = 8;
inline constexpr double kFlickerTbRatio = 10.0;
inline constexpr double kFlickerFirstTbDivisor = 6.0;
/// ADEV of ideal flicker: sqrt(2 ln 2 / pi) B = 0.6643 B (IEEE Std 952 annex C).
inline constexpr double kFlickerAdevFactor = 0.66428;

struct GmParam {
  double sb;    ///< drive PSD [unit^2 / s]
  double tb_s;  ///< correlation time [s]
};

/// Physical parameters of a model (the fit's output). A zero parameter means "term absent".
struct ModelParams {
  double n = 0.0;  ///< white noise N [unit/sqrt(Hz)], AVAR N^2/tau
  /// Time constant of the sensor's output filter the white noise is seen through [s] (0: none):
  /// a first-order low-pass, i.e. N realised as a GM of Tb = n_filter_s, Sb = N^2 / Tb^2 (same
  /// N at long tau; AVAR avar_white_filtered). Typically below Ts.
  double n_filter_s = 0.0;
  double q = 0.0;  ///< quantization Q [unit s], AVAR 3 Q^2/tau^2
  std::size_t n_gm = 0;
  GmParam gm[kMaxGmTerms] = {};
  double k = 0.0;          ///< rate random walk K [unit/sqrt(s)], AVAR K^2 tau/3
  double r = 0.0;          ///< ramp R [unit/s], AVAR R^2 tau^2/2
  double sin_a = 0.0;      ///< sinusoid amplitude A [unit]
  double sin_f0_hz = 0.0;  ///< sinusoid frequency f0 [Hz]
  double sin2_a = 0.0;      ///< a second sinusoid (e.g. a harmonic of the first) [unit]
  double sin2_f0_hz = 0.0;  ///< its frequency [Hz]
  /// The sampling period of the record each sinusoid's amplitude was measured on [s]: a line
  /// in a record's samples has the AVAR of sample means (avar_sinusoid_sampled). 0:
  /// continuous averages. Not a filter parameter.
  double sin_ts_s = 0.0;
  double sin2_ts_s = 0.0;
  double bi = 0.0;          ///< bias instability B [unit] (flicker), AVAR ~ (0.664 B)^2
  double bi_tau_lo_s = 0.0;  ///< tau range over which the flicker bank realises B
  double bi_tau_hi_s = 0.0;
  double osc_sigma = 0.0;       ///< narrowband oscillation: std of the process [unit]
  double osc_f0_hz = 0.0;       ///< its centre frequency [Hz]
  double osc_beta_per_s = 0.0;  ///< its damping rate [1/s] (PSD half-power width beta/pi Hz)
  /// The sampling period of the record the oscillation was fitted on [s]: its AVAR is that of
  /// sample means (avar_oscillation_sampled). 0: continuous averages. Not a filter parameter.
  double osc_ts_s = 0.0;
  /// How long the deterministic terms (ramp, sinusoids) are known to hold [s] (0: for ever).
  /// The record they were measured on establishes them over its own length only, so a filter
  /// that runs for longer lets them wander over this time: the ramp's slope a random walk of
  /// drive PSD R^2 / memory (its slope changes by about R over that time) and each sinusoid a
  /// damped oscillator of rate 1 / memory and variance A^2 / 2 per state (a line over the
  /// record, the narrowband oscillation's limit). Driven, their gain settles (KalmanFilter's and
  /// AveragedKf's steady state); undriven, it decays for ever. The AVAR formulas are the
  /// constant terms'. Not a fit parameter.
  double signal_memory_s = 0.0;
};

/// The flicker bank for B over [tau_lo_s, tau_hi_s] (see kMaxFlickerGm). Returns the number of
/// GMs written to out (0: a bad argument, or a range wider than kMaxFlickerGm decades allow).
[[nodiscard]] std::size_t flicker_bank(double b, double tau_lo_s, double tau_hi_s,
                                       GmParam (&out)[kMaxFlickerGm]);

// AVAR of each term at tau_s > 0 (MODELS.md table).
[[nodiscard]] double avar_white(double n, double tau_s);
[[nodiscard]] double avar_quantization(double q, double tau_s);
/// White noise N seen through a first-order low-pass of time constant tf_s (the sensor's output
/// filter): a GM of Sb = N^2 / tf^2, Tb = tf, i.e. N^2 / tau (1 - (3 - 4 e^-x + e^-2x) / 2x),
/// x = tau / tf: N^2 / tau - 1.5 N^2 tf / tau^2 for tau >> tf. tf_s <= 0: avar_white.
[[nodiscard]] double avar_white_filtered(double n, double tf_s, double tau_s);
/// First-order GM; accurate for every tau/Tb (series for tau/Tb < 1e-3, expm1 above).
[[nodiscard]] double avar_gauss_markov(double sb, double tb_s, double tau_s);
[[nodiscard]] double avar_rrw(double k, double tau_s);
[[nodiscard]] double avar_ramp(double r, double tau_s);
[[nodiscard]] double avar_sinusoid(double a, double f0_hz, double tau_s);
/// A sinusoid of amplitude a in samples taken every ts_s, at tau_s = m ts_s: the mean of m
/// samples has amplitude a sin(pi f0 tau) / (m sin(pi f0 ts)) (the continuous average's
/// a sin(pi f0 tau) / (pi f0 tau) times x / sin x, x = pi f0 ts), so the AVAR is
/// avar_sinusoid's times (x / sin x)^2 at every m. ts_s <= 0, or tau_s off the sample grid:
/// avar_sinusoid.
[[nodiscard]] double avar_sinusoid_sampled(double a, double f0_hz, double ts_s, double tau_s);
/// Narrowband oscillation: sigma^2 Re{2 g(x) / x}, x = (beta - i 2 pi f0) tau, g(x) =
/// 1 - (3 - 4 e^-x + e^-2x) / (2x) (the GM's bracket at a complex rate; beta > 0, f0 >= 0);
/// a power series for |x| < 0.5, where the closed form cancels.
[[nodiscard]] double avar_oscillation(double sigma, double f0_hz, double beta_per_s,
                                      double tau_s);
/// The same process sampled every ts_s: the AVAR of means of m = tau_s / ts_s samples, which is
/// what the ADEV of a record measures (exact; R(d) = sigma^2 e^(-beta d Ts) cos(2 pi f0 d Ts)).
/// It exceeds the continuous average's by about ((pi f0 Ts) / sin(pi f0 Ts))^2: 7 % at
/// f0 = fs / 5. A tau_s that is not a whole number of samples, or ts_s = 0: avar_oscillation.
[[nodiscard]] double avar_oscillation_sampled(double sigma, double f0_hz, double beta_per_s,
                                              double ts_s, double tau_s);
/// Ideal flicker floor (2 ln 2 / pi) B^2 (for reference; the model uses the bank's own AVAR).
[[nodiscard]] double avar_flicker_ideal(double b);
/// AVAR of flicker_bank(b, tau_lo_s, tau_hi_s) at tau_s (0 for a bad range).
[[nodiscard]] double avar_flicker_bank(double b, double tau_lo_s, double tau_hi_s, double tau_s);
/// Sum of the terms present in p, over the term registry (imu/terms.hpp): every instance of
/// every kind, in the registry's order.
[[nodiscard]] double model_avar(const ModelParams& p, double tau_s);

/// Continuous model with at most kMaxStates states. Terms are appended; a term that does not fit
/// or has a bad parameter returns an error and leaves the model unchanged.
/// States of the largest model the host tools and the node build: 2 GMs, a 7-member flicker
/// bank, RRW, ramp (2) and two sinusoids (4) = 16.
inline constexpr std::size_t kModelMaxStates = 16;

template <std::size_t kMaxStates = 6>
struct ContinuousModel {
  static_assert(kMaxStates >= 1 && kMaxStates <= 16, "kMaxStates must be 1..16");
  static constexpr std::size_t kCapacity = kMaxStates;
  using Square = Mat<double, kMaxStates, kMaxStates>;

  std::size_t n_states = 0;
  Square f{};   ///< dynamics F
  Square qc{};  ///< process noise spectral density (G Q G^T)
  Square p0{};  ///< state covariance at t = 0
  Mat<double, 1, kMaxStates> h{};
  double sn = 0.0;      ///< white measurement PSD N^2
  double q = 0.0;       ///< quantization Q
  ModelParams params{};  ///< the same terms as physical parameters (for the analytic AVAR)

  [[nodiscard]] ModelStatus add_white(double n);
  /// White noise N through the sensor's first-order output filter of time constant tf_s: one
  /// GM state (Sb = N^2 / tf^2, Tb = tf), no measurement white noise. Its sampled AVAR is
  /// avar_white_filtered only through discretize_averaged (point samples of a filter much
  /// faster than Ts are nearly uncorrelated, of variance N^2 / 2 tf instead of N^2 / Ts).
  [[nodiscard]] ModelStatus add_filtered_white(double n, double tf_s);
  [[nodiscard]] ModelStatus add_quantization(double q_units_s);
  [[nodiscard]] ModelStatus add_gauss_markov(double sb, double tb_s);
  /// prior_var: variance of the random-walk state at t = 0 (0: starts at zero).
  [[nodiscard]] ModelStatus add_rrw(double k, double prior_var = 0.0);
  /// A ramp of slope r (|r| is used: its sign is the realisation's, not the model's). slope_drive:
  /// PSD of a random walk on the slope [unit^2/s^3] (0: a constant slope).
  [[nodiscard]] ModelStatus add_ramp(double r, double slope_drive = 0.0);
  /// A sinusoid (at most two per model). beta_per_s > 0: damped at that rate and driven so that
  /// each state keeps the variance a^2 / 2 (ModelParams::signal_memory_s); 0: undamped.
  [[nodiscard]] ModelStatus add_sinusoid(double a, double f0_hz, double beta_per_s = 0.0);
  /// Bias instability B realised by flicker_bank over [tau_lo_s, tau_hi_s].
  [[nodiscard]] ModelStatus add_flicker(double b, double tau_lo_s, double tau_hi_s);
  /// A narrowband oscillation (at most one per model).
  [[nodiscard]] ModelStatus add_oscillation(double sigma, double f0_hz, double beta_per_s);

  [[nodiscard]] double avar(double tau_s) const { return model_avar(params, tau_s); }
};

/// Build a continuous model from parameters: terms in the order white (filtered when
/// n_filter_s > 0), quantization, GMs,
/// flicker bank, RRW, ramp, sinusoids, oscillation; zero parameters are skipped.
template <std::size_t kMaxStates>
[[nodiscard]] ModelStatus build_model(const ModelParams& p, ContinuousModel<kMaxStates>& out);

/// Exact discrete equivalent at period ts_s: x_{k+1} = Phi x_k + w_k, cov(w_k) = Qd,
/// z_k = H x_k + n_k + q_k, var(n_k) = Sn / Ts, q_k = Q (u_k - u_{k-1}) / Ts.
template <std::size_t kMaxStates = 6>
struct DiscreteModel {
  using Square = Mat<double, kMaxStates, kMaxStates>;
  std::size_t n_states = 0;
  double ts_s = 0.0;
  Square phi{};
  Square qd{};
  Square p0{};
  Mat<double, 1, kMaxStates> h{};
  double r_white = 0.0;  ///< var(n_k) = Sn / Ts
  double q = 0.0;        ///< quantization Q (phase noise std) [unit s]
  ModelParams params{};

  /// Measurement variance the Kalman filters use: white part plus the quantization MA(1)
  /// variance 2 Q^2 / Ts^2 treated as white (see the file comment).
  [[nodiscard]] double r_filter() const { return r_white + 2.0 * q * q / (ts_s * ts_s); }
};

/// Van Loan: expm([[-F, Qc], [0, F^T]] Ts) = [[., M12], [0, M22]], Phi = M22^T, Qd = Phi M12,
/// on each block of coupled states alone (each term is independent of the others: at most
/// 2 states, so matrices of at most 6 x 6 whatever the model's size; the whole model at once if
/// a block is larger). Returns kBadParameter for ts_s <= 0 or an empty model, kNumerical if
/// expm fails (out then has n_states 0).
template <std::size_t kMaxStates>
[[nodiscard]] ModelStatus discretize(const ContinuousModel<kMaxStates>& c, double ts_s,
                                     DiscreteModel<kMaxStates>& out);

/// The same model seen through an averaging sampler: each sample is the mean of H x over its
/// interval (t - Ts, t], plus the white and quantization noise. A sensor that low-pass filters
/// and decimates internally (the ADIS16405 averages its 819.2 Hz samples) delivers this, and the
/// AVAR formulas of every term (model_avar) are exactly the AVAR of this sequence at tau = m Ts:
/// a filter for a model fitted to the ADEV must observe it this way. Point samples (discretize)
/// differ where a correlation time is comparable with Ts: a GM of Tb = Ts / 4 next to white
/// noise, fitted to a gyro's first ADEV points, gives a lag-1 correlation of 0.17 as averages
/// (the record's is 0.17) and of 0.02 as point samples, and a filter that assumes the latter
/// leaves its innovations correlated (whiteness and CUSUM fire on a correct model).
/// The mean is one extra state, appended last: J' = H x / Ts over a step, reset at every sample
/// (Phi(J, J) = 0); Phi, Qd by Van Loan on the augmented model; H picks J; P0 is the joint
/// covariance after one step from (P0, J = 0). Needs c.n_states + 1 <= kMaxStates (kCapacity).
/// A model without white measurement noise (all of it filtered, add_filtered_white) gets
/// r_white = 1e-4 Qd(J, J): filters need R > 0 (and the analysis' steady-state Riccati
/// solution a well-conditioned R); it changes the innovation variance by 1e-4.
template <std::size_t kMaxStates>
[[nodiscard]] ModelStatus discretize_averaged(const ContinuousModel<kMaxStates>& c, double ts_s,
                                              DiscreteModel<kMaxStates>& out);

}  // namespace imu

#endif  // IMU_ERROR_MODEL_HPP

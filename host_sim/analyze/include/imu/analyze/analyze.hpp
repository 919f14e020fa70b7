// imu-sim analyze: close the loop between a recorded channel and its error model.
//
// Pipeline (analyze()):
//  1. counts = round(y / lsb); online ADEV (fw OnlineAdev<8,22>) of the raw record.
//  2. "before": the first-order model (white + one GM) fitted over [Ts, 100 s]
//     (fw model_fit), its bias filter run over the record (NIS mean) and the covariance check.
//  3. Time domain, on the bias filter's normalised innovations nu: outliers are |nu| above the
//     Bonferroni gate (family-wise false-alarm rate `alpha` over the record) after scaling nu by
//     its robust spread (1.4826 MAD); they are replaced by the filter's prediction. Bias steps:
//     fw StepDetector at scales tau = 8 B Ts (B = 2^p), each normalised by the data's own AVAR at
//     that tau, threshold Bonferroni over the effectively independent positions of every scale;
//     the strongest excursion is one step, removed, and the search repeats (at most 3); an
//     excursion within one window of a step already found is a transient and ends the search.
//  4. ADEV residual, over every tau up to T/10 (T = record length), of the cleaned record: the
//     base family (white + GM, the GM's ADEV peak bounded to T/20 so that a GM cannot stand in
//     for a rate random walk) is refitted over that range, then terms are added greedily
//     (quantization Q, rate random walk K, ramp R, sinusoid A, f0, and a second GM that is
//     reported in the notes, not as an effect): a term is accepted when
//     (a) the current model leaves a significant run (>= min_run consecutive taus with |z| >
//     z_run, or one |z| above the Bonferroni level), and (b) the drop of the cost sum(z^2)
//     exceeds cost_factor * chi2_{1-alpha}(1) (cost_factor accounts for the correlation of
//     neighbouring overlapping estimates). A ramp must also leave no walk in the detrended
//     record by the likelihood test of long_memory.hpp (else the RRW is taken). The
//     sinusoid's frequency comes from the bump (f ~ 0.371 / tau_peak) refined by a periodogram
//     and a golden-section search of the DTFT of block means, its amplitude from the
//     least-squares fit at that frequency. Without K at the end of the search, the record's
//     likelihood test (GMs with the same bound vs GMs + K, 2 ln LR > chi2_{1-alpha}(1)) may
//     still add it: the ADEV up to T/10 cannot tell a GM peaking near T/10 from a walk.
//  5. "after": the joint fit of the base family plus the accepted terms over [Ts, T/10] (GM
//     bounded as above, every effect found kept), its filter NIS mean and covariance check on
//     the cleaned record ("before" again when no ADEV term was accepted).
// Errors: RMS and max of |ADEV_model / ADEV_data - 1| over every tau in [Ts, T/10] and over
// [Ts, 100 s]; "before" against the raw record's ADEV, "after" against the cleaned record's
// ADEV (the same taus; they are the same numbers when no step or outlier was found).
//
// Cost: O(n) passes over the record (ADEV twice or thrice, two filters, step detectors), fits of
// ~100 points; about 1-2 s for 1e6 samples on one core. Host only (std::vector, std::string).
#ifndef IMU_ANALYZE_ANALYZE_HPP
#define IMU_ANALYZE_ANALYZE_HPP

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "imu/error_model.hpp"
#include "imu/online_adev.hpp"

namespace imu::analyze {

/// The range of the sensor's output filter on the white noise, in sample periods: the analysis
/// searches it there (model_after.n_filter_s), and the node's tuning keeps it there
/// (node_tuning.hpp).
inline constexpr double kMinOutputFilterPerTs = 1.0 / 16.0;
inline constexpr double kMaxOutputFilterPerTs = 2.0;

struct Options {
  double fs_hz = 100.0;
  double lsb = 0.0;           ///< physical value of one count; <= 0: derived (see lsb_note)
  double alpha = 0.01;        ///< family-wise false-alarm rate of each detector
  double cost_factor = 4.0;   ///< ADEV cost-drop inflation for correlated taus (tuned, see README)
  double cost_alpha = 0.01;   ///< the ADEV cost-drop test's level (tuned with cost_factor)
  /// An unexplained run must also miss the data by more than this relative ADEV error.
  double unexplained_min_rel = 0.05;
  double z_run = 2.0;         ///< |z| above this is outside the 68 % interval by 2 sigma
  std::size_t min_run = 4;    ///< consecutive taus (one octave at 4 taus per octave)
  double example_tau_max_s = 100.0;  ///< the example's fit range [Ts, 100 s]
  double tau_max_fraction = 0.1;  ///< residuals over taus up to this fraction of the record
  int max_steps = 3;
};

struct ErrorStats {
  double adev_rms_rel = 0.0;  ///< over [tau_min_s, tau_max_s]
  double adev_max_rel = 0.0;
  double tau_min_s = 0.0;
  double tau_max_s = 0.0;
  std::size_t n_taus = 0;
  double example_rms_rel = 0.0;  ///< over [Ts, 100 s]
  double example_max_rel = 0.0;
  double example_tau_max_s = 0.0;
  double cost = 0.0;           ///< sum of z^2 over [tau_min_s, tau_max_s]
  double cov_ratio = 0.0;      ///< robust std / predicted std of the integral at T_int (0: n/a)
  double nis_mean = 0.0;       ///< mean NIS of the bias filter
  /// Fraction of 1000-update blocks of the normalised innovations flagged by the fw monitors:
  /// NIS mean outside its 99 % chi-square band, Box-Pierce (4 lags) above its 95 % bound. For a
  /// correct model about 0.01 and 0.05.
  double nis_flagged_fraction = 0.0;
  double whiteness_flagged_fraction = 0.0;
  std::size_t filter_states = 0;
};

/// The 95 % interval of one reported parameter. Model terms: from the ADEV fit's Gauss-Newton
/// covariance of the log-parameters, c s^2 (J^T J)^-1 (J the Jacobian of the residual z over
/// [Ts, T/10], s^2 = max(1, sum z^2 / (points - parameters)), c = Options::cost_factor for the
/// correlation of neighbouring overlapping estimates), lo/hi = value exp(-+1.96 sd). A step's
/// size: size -+ 1.96 |size| / |z| (its detector's z is the size over its standard error).
/// hi = +inf: the record does not determine the parameter (a note says so).
struct ParamInterval {
  std::string name;  ///< the parameter's JSON key ("k", "freq_hz", "sigma", ...)
  double lo = 0.0;
  double hi = 0.0;
};
struct Effect {
  /// Terms of model_after beyond white noise and its first GM: quantization, rate_random_walk,
  /// ramp, sinusoid, bias_instability, oscillation (a narrowband random oscillation:
  /// error_model.hpp), gauss_markov (a second first-order GM). Cleaning of the record, not model
  /// terms: bias_step, outliers.
  std::string type;
  double b = 0.0;          ///< bias instability B [unit] (ADEV floor 0.664 B)
  double q = 0.0;          ///< quantization Q [unit s]
  double k = 0.0;          ///< rate random walk K [unit / sqrt(s)]
  double r = 0.0;          ///< ramp R [unit / s]
  double freq_hz = 0.0;    ///< sinusoid; oscillation: centre frequency
  double amplitude = 0.0;  ///< sinusoid [unit]; oscillation: the process's std sigma [unit]
  double bandwidth_hz = 0.0;  ///< oscillation: half-power width of its PSD peak (beta / pi)
  double tb_s = 0.0;       ///< gauss_markov: correlation time Tb [s] (amplitude: its sigma)
  double time_s = 0.0;     ///< bias step: time of the first sample after it
  double time_lo_s = 0.0;  ///< bias step: 95 % interval of time_s: from
  double time_hi_s = 0.0;  ///< to
  double size = 0.0;       ///< bias step [unit]
  std::uint64_t count = 0; ///< outliers
  std::vector<double> times_s;  ///< outliers: times of the first 100 [s]
  double statistic = 0.0;  ///< evidence: cost drop (ADEV terms), |z| (step), max |nu| (outliers)
  double threshold = 0.0;  ///< the threshold the statistic passed
  std::vector<ParamInterval> ci95;  ///< 95 % intervals of its parameters (not outliers)
};

struct UnexplainedRun {
  double tau_min_s = 0.0;
  double tau_max_s = 0.0;
  double max_abs_z = 0.0;
  int sign = 0;  ///< +1: the model lies above the data there, -1: below
  /// A part of the record where it is not stationary (t_max_s > t_min_s; else the run is one of
  /// the ADEV's taus over the whole record): what was seen there (e.g. the white noise's level
  /// changes, a level shift undone, an excursion at the start).
  double t_min_s = 0.0;
  double t_max_s = 0.0;
  std::string what;
};

/// A record longer than the analysis holds (host_sim/analyze/src/cli.cpp: 2^20 samples) is
/// analysed on block means of `block` samples for the whole record, and at full rate on its
/// first `samples` samples (the head), for the taus and effects the means cannot resolve.
/// merge_full_rate_head() says how the two are joined.
struct FullRateHead {
  std::uint64_t samples = 0;  ///< 0: none (the record was analysed at full rate)
  double fs_hz = 0.0;
  std::uint64_t block = 0;    ///< the record's block means: block samples each
  ModelParams model_before{};  ///< the head's own analysis
  ModelParams model_after{};
  ErrorStats error_before{};   ///< over the head's taus [Ts, T_head/10]
  ErrorStats error_after{};
  /// The record's model after the merge, scored on the head's cleaned full-rate ADEV (relative
  /// errors over the same taus as error_after).
  ErrorStats error_record_model{};
  std::vector<Effect> effects;  ///< every effect the head's analysis named
  std::vector<UnexplainedRun> unexplained;
  bool merged = false;          ///< the record's model took the head's fast terms
};

struct Report {
  std::string channel;
  std::string sensor;  ///< "accelerometer", "gyroscope" or "" (declared or from the name)
  std::string unit;    ///< the analysed numbers' unit: m/s^2, rad/s ("" : from the name)
  double fs_hz = 0.0;
  std::uint64_t samples = 0;
  double lsb = 0.0;
  std::string lsb_note;  ///< where the LSB came from
  std::vector<AdevPoint> adev;        ///< raw record
  std::vector<AdevPoint> adev_clean;  ///< after removing steps and outliers
  ModelParams model_before{};
  ModelParams model_after{};
  /// 95 % intervals of model_after's white noise "n" and first GM ("gm_sigma", "gm_tb_s").
  std::vector<ParamInterval> model_after_ci95;
  ErrorStats error_before{};
  ErrorStats error_after{};
  std::vector<Effect> effects;
  /// Tau ranges where the final model still leaves a significant run of residuals (what no
  /// term explains, rather than a wrong name); empty when nothing remains.
  std::vector<UnexplainedRun> unexplained;
  std::uint64_t gap_samples = 0;  ///< missing samples: non-finite, or a frozen output's repeats
  std::uint64_t gap_runs = 0;     ///< runs of consecutive missing samples
  std::vector<std::string> notes;  ///< warnings and decisions, one line each
  FullRateHead head;               ///< a long record's full-rate head (samples 0: none)
  double seconds = 0.0;            ///< wall time of analyze()
  double cpu_seconds = 0.0;        ///< CPU time of the thread that ran analyze()
};

/// Analyze one channel (physical units). Fails (returns false, `error` set to one line) on an
/// empty or too short record (< 1000 samples), non-finite samples, bad fs or LSB, or a fit that
/// does not converge.
[[nodiscard]] bool analyze(const std::vector<double>& y, const std::string& channel,
                           const Options& options, Report& out, std::string& error);

/// The same analysis, consuming the record: its storage becomes the analysis' working copy (one
/// record-length vector fewer in flight; `y` is left empty).
[[nodiscard]] bool analyze(std::vector<double>&& y, const std::string& channel,
                           const Options& options, Report& out, std::string& error);

/// LSB for data without one (non-finite values ignored): the step of the lattice the values lie
/// on from the smallest (values within 1e-9 of max |y| are one value: floating-point residue of
/// scaling or differencing), taken as the least-squares slope of the distinct levels on their
/// step counts from the smallest difference, when every value lies on it within 2 % of a step
/// (the residue of an offset added in floating point or of a six-digit print) and the span fits
/// int32 counts; one level only: 1e-9 of max |y|; else max(robust std / 4096, span / 2^30),
/// and the note says why.
[[nodiscard]] double derive_lsb(const std::vector<double>& y, std::string& note);

/// Non-finite samples of y are gaps: marked in gap (1), each run filled by the straight line
/// between the means of the finite samples on either side (as many as the run is long, >= 100;
/// one side at the ends). samples/runs count them. gap is left empty when there is none.
/// Returns false if no sample is finite.
[[nodiscard]] bool fill_gaps(std::vector<double>& y, std::vector<std::uint8_t>& gap,
                             std::uint64_t& samples, std::uint64_t& runs);

/// Errors of model m against ADEV points (relative errors as ErrorStats; cost = sum z^2 with the
/// points' own EDF) over [tau_min_s, tau_max_s]; the filter figures are left 0.
[[nodiscard]] ErrorStats score_model(const std::vector<AdevPoint>& pts, const ModelParams& m,
                                     const Options& o, double tau_min_s, double tau_max_s);

/// Join a long record's report (`record`, analysed on block means of `block` samples at rate
/// fs / block) with the full-rate analysis of its head (`head`, rate fs). The means cannot
/// resolve taus below block / fs, quantisation, or anything faster than their Nyquist
/// fs / (2 block) (which they alias). The candidate model is the record's, with
///   * the head's white noise N and quantization Q,
///   * the record's GMs whose ADEV peak (1.89 Tb) is at or above 4 block / fs, and the head's
///     below it (a GM at the means' shortest taus stands in for the faster terms),
///   * the head's sinusoids and oscillation above fs / (2 block); the record's sinusoid or
///     oscillation at the alias of one of them is dropped (it was the alias, a wrong name),
///   * the record's slow terms (K, R, bias instability) as they are.
/// It replaces the record's model only if it is no worse (RMS and max relative ADEV error) than
/// the first-order model on both the record's taus and the head's; then the head's quantization,
/// fast sinusoids and oscillation become effects of the record, the record's quantization and
/// alias effects are removed, and the head's unexplained runs below the record's first tau are
/// added. Either way `record.head` holds the head's findings and each decision is a note.
/// Cost: a few model evaluations per ADEV point.
void merge_full_rate_head(Report& record, Report&& head, std::uint64_t block, const Options& o);

/// The report tells one story: every term of model_after beyond white noise and its first GM is
/// a named effect of that type carrying the model's parameter (a second GM is gauss_markov, with
/// sigma = sqrt(Sb Tb / 2) and Tb), every named model effect is a term of model_after, and the
/// text lists exactly the effects (bias_step and outliers are cleaning of the record, not model
/// terms), and every effect's statistic passes the threshold its line states. False with the
/// first disagreement in `why`. analyze() removes from the model a term
/// it does not name, so this holds for every report it writes; tests check it.
[[nodiscard]] bool report_consistent(const Report& r, std::string& why);

/// The model after holds, in a rate random walk's place, the first-order model's own GM slower
/// than the record resolves: no walk named, no K, one GM whose Tb's 95 % interval is open above
/// (the record bounds Tb from below only). Over the record such a GM is a walk of K^2 = Sb; the
/// record does not tell which (analyze.cpp slow_gm_for_walk; its note gives 2 ln LR).
[[nodiscard]] bool gm_stands_in_for_walk(const Report& r);

[[nodiscard]] std::string to_json(const Report& r);
[[nodiscard]] std::string to_text(const Report& r);
/// CSV always (DIR/STEM_adev.csv), the gnuplot script (DIR/STEM_adev.gp) and, if gnuplot is
/// found, DIR/STEM_{before,after}.{svg,png}. `stem` is made one safe file-name component
/// (imu::cli::safe_component; callers with several channels pass imu::cli::safe_components'
/// distinct names). Every write is checked: false with the reason (a full disk, gnuplot
/// failing); message says what was written.
[[nodiscard]] bool write_plots(const Report& r, const std::string& dir, const std::string& stem,
                               std::string& message);
/// One figure per sensor (the reports whose `sensor` is accelerometer, then gyroscope), as
/// MATLAB's allanvar examples and allan_variance_ros draw them: every axis's ADEV with its 68 %
/// interval and the IEEE Std 952 lines read off it as MATLAB's allanvar example does (the line
/// of slope -1/2, +1/2 or 0 through the point where the data's log-log slope is nearest it,
/// within 0.25): N / sqrt(tau) (white noise, N read at tau = 1 s), K sqrt(tau / 3) (rate random
/// walk, K read at tau = 3 s), the flat 0.664 B (bias instability), each read-off point marked.
/// These are the plot's graphical read-offs, not the analysis's model (its terms are in
/// analyze_NAME_after). DIR/analyze_SENSOR.{csv,gp,svg,png};
/// without gnuplot the CSV and script only. False with message on a failed write or render;
/// message lists the files.
[[nodiscard]] bool write_sensor_plots(const std::vector<Report>& reports, const std::string& dir,
                                      std::string& message);
/// Kalibr's imu.yaml (accelerometer/gyroscope noise density and random walk, update_rate,
/// rostopic) from the reports of one IMU's channels (Report::sensor accelerometer and gyroscope, at
/// least one of each; numbers in SI, as the reading converted them):
/// per sensor the largest axis of the white + walk model fitted to each after-model's ADEV;
/// per-axis values, bias instability and the full models as extra keys and comments. False
/// with err if a sensor is missing. source: named in the header comment.
[[nodiscard]] bool kalibr_yaml(const std::vector<Report>& reports, const std::string& source,
                               std::string& yaml, std::string& err);

/// `analyze FILE.mat --channel NAME [--fs HZ] [--json OUT] [--plots DIR]` (argv[0] = "analyze").
/// Prints the text report on stdout; returns 0, or 1 (run-time error) / 2 (command-line error)
/// with a one-line error on stderr (imu/cli/args.hpp). -h / --help prints the usage.
int cli_main(int argc, char** argv);

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_ANALYZE_HPP

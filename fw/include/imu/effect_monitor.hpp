// On-target detectors of effects the first-order model lacks, fixed memory, no heap.
// A co-processor runs them next to the bias filter and raises its alarm line on their flags;
// the host analysis (host_sim/analyze) calls the same code.
//
// * OutlierGate: |nu| > threshold on a normalised deviation nu (e.g. a bias-filter innovation
//   divided by a robust scale). Counts gated samples; the caller skips the filter update for
//   them. Threshold from the statistics: two_sided_normal_threshold(alpha / n_samples) keeps the
//   family-wise false-alarm rate at alpha over a record of n_samples (Bonferroni).
// * StepDetector<kMaxBlocks>: two adjacent windows of W blocks of B samples each (tau = W B Ts).
//   After every block, d = mean(last W blocks) - mean(W blocks before) in counts. Under any
//   stationary-increment noise, E[d^2] = 2 AVAR(tau) exactly (that is the Allan variance), so
//   z = d / sqrt(2 AVAR_ref(tau)) is ~N(0,1) when AVAR_ref is the channel's AVAR at tau (the
//   OnlineAdev snapshot at af = W B, or a model's AVAR). A bias step of size s at sample k0 makes
//   |d| a triangle peaking at s when the window boundary sits at k0: an excursion of |z| above
//   the threshold is one event, located at the boundary of its peak. Events are kept in a fixed
//   array (the first kMaxEvents; further ones are counted).
// * AdevResidualCheck: z_i = ln(ADEV_model / ADEV_data) / h_i over snapshot points, with
//   h_i = ln(ci_hi / ci_lo) / 2 the relative half-width of the 68.3 % interval (~ one sigma of
//   ln ADEV). Neighbouring overlapping estimates are strongly correlated and there are many
//   taus, so one |z| > threshold means little: the check reports runs of consecutive points
//   with |z| > threshold and one sign, and flags a run of at least min_run points (or a shorter
//   one holding a |z| above z_single, for very precise estimates at the shortest taus).
//
// Cost: OutlierGate O(1) per sample; StepDetector O(1) per sample plus O(1) per block (running
// window sums); AdevResidualCheck O(n) per snapshot, a few log() per point. Not re-entrant on one
// instance; instances are independent.
#ifndef IMU_EFFECT_MONITOR_HPP
#define IMU_EFFECT_MONITOR_HPP

#include <cstddef>
#include <cstdint>

#include "imu/error_model.hpp"
#include "imu/online_adev.hpp"

namespace imu {

enum class EffectStatus : std::uint8_t {
  kOk = 0,
  kBadConfig,  ///< a parameter is out of range (non-finite, <= 0, or over a capacity)
};

/// z > 0 with P(|N(0,1)| > z) = p, for 0 < p < 1 (imu::normal_quantile of p / 2).
/// Returns 0 for p outside (0, 1).
[[nodiscard]] double two_sided_normal_threshold(double p);

struct OutlierGateStats {
  std::uint64_t samples = 0;
  std::uint64_t outliers = 0;
  std::uint64_t rejected_nonfinite = 0;  ///< non-finite nu: counted as an outlier too
  double max_abs = 0.0;                  ///< largest finite |nu| seen
};

class OutlierGate {
 public:
  /// threshold (in units of nu) > 0 and finite. Resets the counters.
  [[nodiscard]] EffectStatus configure(double threshold);
  /// One normalised deviation. Returns true when it is gated (an outlier). Constant time.
  bool push(double nu);
  [[nodiscard]] double threshold() const { return threshold_; }
  [[nodiscard]] const OutlierGateStats& stats() const { return stats_; }

 private:
  double threshold_ = 6.0;
  OutlierGateStats stats_{};
};

/// One detected step: the window boundary at the peak of |z| of one excursion.
struct StepEvent {
  std::uint64_t sample_index = 0;  ///< first sample after the step (counted from configure())
  double size_counts = 0.0;        ///< d at the peak [counts] (mean after - mean before)
  double z = 0.0;                  ///< d / sqrt(2 AVAR_ref) at the peak
};

struct StepDetectorStats {
  std::uint64_t samples = 0;
  std::uint64_t blocks = 0;
  std::uint32_t events = 0;          ///< excursions above the threshold (all of them)
  std::uint32_t events_dropped = 0;  ///< events beyond kMaxEvents (counted, not stored)
  double max_abs_z = 0.0;
};

template <std::size_t kMaxBlocks = 64, std::size_t kMaxEvents = 4>
class StepDetector {
  static_assert(kMaxBlocks >= 2 && kMaxBlocks <= 4096, "kMaxBlocks must be 2..4096");
  static_assert(kMaxEvents >= 1 && kMaxEvents <= 64, "kMaxEvents must be 1..64");

 public:
  /// block_len B >= 1 samples, window W >= 1 blocks with 2 W <= kMaxBlocks, avar_ref > 0
  /// [counts^2] (AVAR at tau = W B Ts), threshold > 0 (in sigma). Resets everything.
  [[nodiscard]] EffectStatus configure(std::uint32_t block_len, std::uint32_t window_blocks,
                                       double avar_ref_counts2, double threshold);
  /// Replace AVAR_ref (e.g. from a newer OnlineAdev snapshot). kBadConfig if not > 0.
  [[nodiscard]] EffectStatus set_reference_avar(double avar_ref_counts2);
  /// One sample in counts. O(1).
  void push(std::int32_t counts);
  /// Close an excursion still open at the end of the record (call once at the end).
  void finish();
  /// Latest z (0 until 2 W blocks are in).
  [[nodiscard]] double z() const { return z_; }
  /// |z| above the threshold right now (the alarm line).
  [[nodiscard]] bool alarm() const { return in_excursion_; }
  [[nodiscard]] std::size_t n_events() const {
    return stats_.events < kMaxEvents ? stats_.events : kMaxEvents;
  }
  [[nodiscard]] const StepEvent& event(std::size_t i) const { return events_[i]; }
  [[nodiscard]] const StepDetectorStats& stats() const { return stats_; }

 private:
  void close_excursion();

  std::uint32_t block_len_ = 1;
  std::uint32_t window_ = 1;
  double sigma_d_ = 1.0;  // sqrt(2 AVAR_ref)
  double threshold_ = 5.0;
  std::int64_t block_sum_ = 0;
  std::uint32_t in_block_ = 0;
  std::int64_t ring_[kMaxBlocks] = {};  // block sums, ring of the last 2 W blocks
  std::size_t head_ = 0;                // next slot to write
  std::size_t filled_ = 0;
  std::int64_t sum_new_ = 0;  // sum of the last W block sums
  std::int64_t sum_old_ = 0;  // sum of the W block sums before
  double z_ = 0.0;
  bool in_excursion_ = false;
  StepEvent peak_{};
  StepEvent events_[kMaxEvents] = {};
  StepDetectorStats stats_{};
};

struct AdevRun {
  std::size_t first = 0;  ///< index of the first point of the run (in the checked order)
  std::size_t count = 0;  ///< number of consecutive points
  int sign = 0;           ///< +1: model above data, -1: model below data
  double sum_z = 0.0;     ///< sum of z over the run
  double max_abs_z = 0.0; ///< largest |z| in the run
};

struct AdevCheckOptions {
  double tau_min_s = 0.0;     ///< points outside [tau_min_s, tau_max_s] are not checked
  double tau_max_s = 1e300;
  double threshold = 2.0;     ///< |z| above this is "outside the interval"
  std::size_t min_run = 4;    ///< consecutive points needed for a significant run
  /// A shorter run is also significant when one of its |z| exceeds this (e.g. a Bonferroni
  /// threshold over the number of points); 0 disables it.
  double z_single = 0.0;
};

template <std::size_t kMaxRuns = 8>
struct AdevCheckResult {
  std::size_t n_checked = 0;   ///< points inside the range with a valid interval
  double max_abs_z = 0.0;
  double rms_rel = 0.0;        ///< RMS of |ADEV_model / ADEV_data - 1| over the checked points
  double max_rel = 0.0;        ///< max of the same
  std::size_t n_runs = 0;      ///< significant runs stored (the longest kMaxRuns, by count)
  std::size_t runs_dropped = 0;
  AdevRun runs[kMaxRuns] = {};
  [[nodiscard]] bool alarm() const { return n_runs > 0; }
};

/// Compare the model AVAR with the snapshot points (in increasing tau order, as snapshot()
/// gives them). z_out (may be null) receives z for each of the n points (0 for unchecked ones).
/// Runs are formed over checked points only. O(n).
template <std::size_t kMaxRuns>
[[nodiscard]] EffectStatus check_adev_residual(const AdevPoint* points, std::size_t n,
                                               const ModelParams& model,
                                               const AdevCheckOptions& options,
                                               AdevCheckResult<kMaxRuns>& out, double* z_out);

}  // namespace imu

#endif  // IMU_EFFECT_MONITOR_HPP

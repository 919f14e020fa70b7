// Residual monitors of the bias filter on target: fixed memory, float arithmetic, results are
// plain numbers and flags the caller reads (telemetry, an alarm GPIO line).
//
// Input of every monitor: one normalised innovation nu = e / sqrt(S) per filter UPDATE (not per
// sample: predictions without a measurement have no innovation). Under a correct model nu is
// N(0, 1) and white.
//
// * NisMonitor: mean of nu^2 over consecutive blocks of `window` updates. For a correct model
//   window * mean ~ chi-square(window); the block is flagged when the mean is outside
//   [chi2_{(1-c)/2}(window), chi2_{(1+c)/2}(window)] / window (bounds computed once with
//   imu::chi2_quantile at configure()). Also a running (current block) mean.
// * WhitenessMonitor<kLags>: sample autocorrelation r_l = sum nu_k nu_{k-l} / sum nu_k^2 at lags
//   1..kLags over the same kind of blocks. Per-lag flag when |r_l| > 2 / sqrt(window) (the
//   usual 95 % band), and a Box-Pierce portmanteau Q = window * sum r_l^2 against
//   chi2_c(kLags) (one combined flag with the stated false-alarm rate 1 - c).
// * Cusum: two-sided CUSUM for a step in the mean of nu: g+ = max(0, g+ + nu - k),
//   g- = max(0, g- - nu - k); alarm when either exceeds h. The alarm latches until reset(), so
//   over a record of n updates the false-alarm probability is ~1 - exp(-n / ARL0): h is sized
//   from a stated in-control average run length ARL0, not picked by hand. Design: Siegmund's
//   approximation (D. Siegmund, "Sequential Analysis", Springer 1985; also in Basseville &
//   Nikiforov, "Detection of Abrupt Changes", 1993): for N(mu, 1) input one side has
//     ARL(mu) ~ (exp(-2 D b) + 2 D b - 1) / (2 D^2),  D = mu - k,  b = h + 1.166
//   (b^2 when D = 0; 1.166 = 2 x 0.583 is the Gaussian overshoot correction), and the two sides
//   combine as 1/ARL = 1/ARL+ + 1/ARL-. cusum_threshold_for_arl0() inverts this at configure().
//   Defaults: ARL0 = 1e8 updates (~11.6 days at 100 Hz; 100x a 1e6-update record, i.e. a ~1 %
//   false-alarm probability over such a record) and k = 0.025, half the smallest persistent mean
//   shift worth detecting, delta = 0.05 sd: the innovation mean of a bias estimate that is off by
//   ~2 of the filter's own standard deviations (sqrt(P/S) = 0.022 for the example's accelerometer
//   model at 100 Hz). That is the scale of a wrong model: a missing random walk or a too short
//   Gauss-Markov time pulls the estimate by a few hundredths of an sd for minutes, which a
//   k = 0.5 CUSUM cannot tell from noise. Then h = 247.4, b = 248.6, and the mean delays are
//   (same formula): 0.05 sd ~9100 updates, 0.1 sd ~3200, 0.6 sd ~430, 1 sd ~250 (k = 0.5 with
//   the same ARL0: h = 17.25, 1 sd in ~35 updates but 0.05 sd in ~4e7; a fast step detector
//   would be a second instance with its own share of the false-alarm budget). The design
//   assumes white N(0, 1) innovations (a correct model); the whiteness monitor says whether
//   they are. The estimated step time is the update index at which the alarming sum last left
//   zero.
// Cost per update: NIS 3 flops, whiteness kLags + 3 multiply-adds, CUSUM 4 flops; end of block
// O(kLags). No heap, not re-entrant on one instance.
#ifndef IMU_RESIDUAL_MONITOR_HPP
#define IMU_RESIDUAL_MONITOR_HPP

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "imu/edf.hpp"

namespace imu {

enum class MonitorStatus : std::uint8_t { kOk = 0, kBadConfig };

class NisMonitor {
 public:
  /// window >= 2 updates per block, confidence in (0, 1). Resets the monitor.
  [[nodiscard]] MonitorStatus configure(std::uint32_t window = 1000, double confidence = 0.99) {
    if (window < 2 || !(confidence > 0.0 && confidence < 1.0)) {
      return MonitorStatus::kBadConfig;
    }
    window_ = window;
    const double dof = static_cast<double>(window);
    lo_ = static_cast<float>(chi2_quantile((1.0 - confidence) / 2.0, dof) / dof);
    hi_ = static_cast<float>(chi2_quantile((1.0 + confidence) / 2.0, dof) / dof);
    reset();
    return MonitorStatus::kOk;
  }
  void reset() {
    sum_ = 0.0F;
    count_ = 0;
    last_mean_ = 0.0F;
    block_mean_sum_ = 0.0F;
    blocks_ = 0;
    flagged_blocks_ = 0;
    flag_ = false;
  }
  /// Push one normalised innovation.
  void push(float nu) {
    sum_ += nu * nu;
    ++count_;
    if (count_ >= window_) {
      last_mean_ = sum_ / static_cast<float>(count_);
      block_mean_sum_ += last_mean_;
      flag_ = last_mean_ < lo_ || last_mean_ > hi_;
      ++blocks_;
      flagged_blocks_ += flag_ ? 1U : 0U;
      sum_ = 0.0F;
      count_ = 0;
    }
  }
  [[nodiscard]] float running_mean() const {
    return count_ > 0 ? sum_ / static_cast<float>(count_) : 0.0F;
  }
  [[nodiscard]] float last_block_mean() const { return last_mean_; }
  /// Mean over every update since reset() (complete blocks and the current one); 0 before the
  /// first. Kept as a sum of block means (float, one add per block), not of 10^8 squares.
  [[nodiscard]] float overall_mean() const {
    const float w = static_cast<float>(window_);
    const float n = static_cast<float>(blocks_) * w + static_cast<float>(count_);
    return n > 0.0F ? (block_mean_sum_ * w + sum_) / n : 0.0F;
  }
  [[nodiscard]] float bound_lo() const { return lo_; }
  [[nodiscard]] float bound_hi() const { return hi_; }
  /// The last complete block was outside the bounds.
  [[nodiscard]] bool flag() const { return flag_; }
  [[nodiscard]] std::uint32_t blocks() const { return blocks_; }
  [[nodiscard]] std::uint32_t flagged_blocks() const { return flagged_blocks_; }

 private:
  std::uint32_t window_ = 1000;
  float lo_ = 0.0F;
  float hi_ = 0.0F;
  float sum_ = 0.0F;
  std::uint32_t count_ = 0;
  float last_mean_ = 0.0F;
  float block_mean_sum_ = 0.0F;
  std::uint32_t blocks_ = 0;
  std::uint32_t flagged_blocks_ = 0;
  bool flag_ = false;
};

template <std::size_t kLags = 4>
class WhitenessMonitor {
  static_assert(kLags >= 1 && kLags <= 16, "kLags must be 1..16");

 public:
  [[nodiscard]] MonitorStatus configure(std::uint32_t window = 1000, double confidence = 0.95) {
    if (window < 4 * kLags || !(confidence > 0.0 && confidence < 1.0)) {
      return MonitorStatus::kBadConfig;
    }
    window_ = window;
    band_ = static_cast<float>(2.0 / std::sqrt(static_cast<double>(window)));
    q_bound_ = static_cast<float>(chi2_quantile(confidence, static_cast<double>(kLags)));
    reset();
    return MonitorStatus::kOk;
  }
  void reset() {
    for (std::size_t l = 0; l < kLags; ++l) {
      hist_[l] = 0.0F;
      lag_sum_[l] = 0.0F;
      r_[l] = 0.0F;
      lag_flag_[l] = false;
    }
    sum_sq_ = 0.0F;
    count_ = 0;
    q_ = 0.0F;
    flag_ = false;
    blocks_ = 0;
    flagged_blocks_ = 0;
  }
  void push(float nu) {
    sum_sq_ += nu * nu;
    // hist_[l] holds nu_{k-1-l}; products only within the block (count_ > l).
    for (std::size_t l = 0; l < kLags; ++l) {
      if (count_ > l) {
        lag_sum_[l] += nu * hist_[l];
      }
    }
    for (std::size_t l = kLags - 1; l > 0; --l) {
      hist_[l] = hist_[l - 1];
    }
    hist_[0] = nu;
    ++count_;
    if (count_ >= window_) {
      close_block();
    }
  }
  /// Autocorrelation at lag l (1..kLags) of the last complete block.
  [[nodiscard]] float autocorrelation(std::size_t lag) const {
    return lag >= 1 && lag <= kLags ? r_[lag - 1] : 0.0F;
  }
  [[nodiscard]] bool lag_flag(std::size_t lag) const {
    return lag >= 1 && lag <= kLags ? lag_flag_[lag - 1] : false;
  }
  [[nodiscard]] float box_pierce() const { return q_; }
  [[nodiscard]] float box_pierce_bound() const { return q_bound_; }
  /// box_pierce() / box_pierce_bound(): above 1 when the last block failed (telemetry's figure).
  [[nodiscard]] float box_pierce_ratio() const { return q_ / q_bound_; }
  /// Box-Pierce statistic of the last complete block above its bound.
  [[nodiscard]] bool flag() const { return flag_; }
  [[nodiscard]] std::uint32_t blocks() const { return blocks_; }
  [[nodiscard]] std::uint32_t flagged_blocks() const { return flagged_blocks_; }

 private:
  void close_block() {
    float q = 0.0F;
    for (std::size_t l = 0; l < kLags; ++l) {
      r_[l] = sum_sq_ > 0.0F ? lag_sum_[l] / sum_sq_ : 0.0F;
      lag_flag_[l] = std::fabs(r_[l]) > band_;
      q += r_[l] * r_[l];
      lag_sum_[l] = 0.0F;
    }
    q_ = static_cast<float>(window_) * q;
    flag_ = q_ > q_bound_;
    ++blocks_;
    flagged_blocks_ += flag_ ? 1U : 0U;
    sum_sq_ = 0.0F;
    count_ = 0;
  }

  std::uint32_t window_ = 1000;
  float band_ = 0.0F;
  float q_bound_ = 0.0F;
  float hist_[kLags] = {};
  float lag_sum_[kLags] = {};
  float r_[kLags] = {};
  bool lag_flag_[kLags] = {};
  float sum_sq_ = 0.0F;
  std::uint32_t count_ = 0;
  float q_ = 0.0F;
  bool flag_ = false;
  std::uint32_t blocks_ = 0;
  std::uint32_t flagged_blocks_ = 0;
};

/// Siegmund's approximation of the average run length of ONE side of a CUSUM with slack k >= 0
/// and threshold h > 0 (units of the input's sd) for N(mean_shift, 1) input (header comment).
/// Not finite (inf) when it overflows a double. Constant time.
[[nodiscard]] inline double cusum_arl_one_sided(double mean_shift, double slack,
                                                double threshold) {
  const double b = threshold + 1.166;
  const double d = mean_shift - slack;
  if (std::fabs(d) < 1e-9) {
    return b * b;  // the limit D -> 0 of the expression below
  }
  return (std::exp(-2.0 * d * b) + 2.0 * d * b - 1.0) / (2.0 * d * d);
}

/// In-control (mean 0) average run length of the two-sided CUSUM: 1 / (1/ARL+ + 1/ARL-), both
/// sides equal by symmetry.
[[nodiscard]] inline double cusum_arl0_two_sided(double slack, double threshold) {
  return 0.5 * cusum_arl_one_sided(0.0, slack, threshold);
}

/// The threshold h at which the two-sided in-control ARL equals arl0_updates, for slack k.
/// k in [0, 4], arl0_updates in [10, 1e15]; kBadConfig otherwise. Bisection on the monotone
/// ARL(h) to 1e-9 relative in h: ~40 evaluations, once per configure(), not per update.
[[nodiscard]] inline MonitorStatus cusum_threshold_for_arl0(double slack, double arl0_updates,
                                                            double& threshold) {
  if (!(slack >= 0.0 && slack <= 4.0) || !(arl0_updates >= 10.0 && arl0_updates <= 1e15)) {
    return MonitorStatus::kBadConfig;
  }
  double lo = 1e-3;  // ARL(lo) < 10 for every k in range
  double hi = 1e-3;
  while (cusum_arl0_two_sided(slack, hi) < arl0_updates) {
    hi *= 2.0;  // ARL grows at least like h^2 / 2: a few doublings (k = 0: h ~ 4.5e7 max)
    if (hi > 1e9) {
      return MonitorStatus::kBadConfig;
    }
  }
  for (int i = 0; i < 200 && hi - lo > 1e-9 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cusum_arl0_two_sided(slack, mid) < arl0_updates ? lo : hi) = mid;
  }
  threshold = hi;
  return MonitorStatus::kOk;
}

class Cusum {
 public:
  static constexpr float kDefaultSlack = 0.025F;
  /// Default in-control two-sided ARL (updates): see the header comment.
  static constexpr double kDefaultArl0Updates = 1e8;

  /// The design configuration: slack k (sd units) and the in-control two-sided average run
  /// length ARL0 (updates) the threshold is sized for. Resets the monitor.
  [[nodiscard]] MonitorStatus configure(float slack = kDefaultSlack,
                                        double arl0_updates = kDefaultArl0Updates) {
    double h = 0.0;
    if (!std::isfinite(slack) ||
        cusum_threshold_for_arl0(static_cast<double>(slack), arl0_updates, h) !=
            MonitorStatus::kOk) {
      return MonitorStatus::kBadConfig;
    }
    return configure_threshold(slack, static_cast<float>(h));
  }
  /// An explicit threshold h > 0 (sd units) instead of an ARL0 (e.g. a short-ARL test).
  [[nodiscard]] MonitorStatus configure_threshold(float slack, float threshold) {
    if (!(slack >= 0.0F) || !(threshold > 0.0F) || !std::isfinite(slack + threshold)) {
      return MonitorStatus::kBadConfig;
    }
    k_ = slack;
    h_ = threshold;
    n_ = 0;  // before reset(), which starts the step search at the current count
    reset();
    return MonitorStatus::kOk;
  }
  /// Re-arm after an alarm (keeps the update counter running).
  void reset() {
    gp_ = 0.0F;
    gm_ = 0.0F;
    start_p_ = n_;
    start_m_ = n_;
    alarm_ = false;
    direction_ = 0;
    step_index_ = 0;
  }
  /// Push one normalised innovation. Returns true while in alarm.
  bool push(float nu) {
    ++n_;
    if (alarm_) {
      return true;  // latched until reset()
    }
    gp_ += nu - k_;
    if (gp_ <= 0.0F) {
      gp_ = 0.0F;
      start_p_ = n_;
    }
    gm_ += -nu - k_;
    if (gm_ <= 0.0F) {
      gm_ = 0.0F;
      start_m_ = n_;
    }
    if (gp_ > h_ || gm_ > h_) {
      alarm_ = true;
      direction_ = gp_ > h_ ? 1 : -1;
      step_index_ = gp_ > h_ ? start_p_ : start_m_;
    }
    return alarm_;
  }
  [[nodiscard]] bool alarm() const { return alarm_; }
  /// +1 upward step, -1 downward, 0 no alarm.
  [[nodiscard]] int direction() const { return direction_; }
  /// Updates counted from configure(); the step is estimated to start right after update
  /// number step_index() (valid while alarm()).
  [[nodiscard]] std::uint64_t step_index() const { return step_index_; }
  [[nodiscard]] std::uint64_t updates() const { return n_; }
  [[nodiscard]] float slack() const { return k_; }
  [[nodiscard]] float threshold() const { return h_; }

 private:
  float k_ = kDefaultSlack;
  float h_ = 247.4F;  // configure() sizes it; this is the default design's value
  float gp_ = 0.0F;
  float gm_ = 0.0F;
  std::uint64_t n_ = 0;
  std::uint64_t start_p_ = 0;
  std::uint64_t start_m_ = 0;
  std::uint64_t step_index_ = 0;
  bool alarm_ = false;
  int direction_ = 0;
};

/// Where a level shift that the CUSUM detected began, and how large it is: the generalised
/// likelihood ratio for a step of unknown size in N(0, 1) input, maximised over the starts on
/// a grid of kBlockUpdates updates within the last kBlocks blocks (and the current part block):
/// start tau maximises (sum_{k > tau} nu_k)^2 / (n - tau), the size is that sum's mean (in sd).
/// The CUSUM's own estimate, where the alarming sum last was zero, is no use for the size: with
/// a small slack the sum wanders above zero for thousands of updates before a step, and the mean
/// since then dilutes the step. Memory kBlocks floats; cost per update an addition and a
/// compare, plus a store per block; locate() O(kBlocks), at an alarm only.
template <std::size_t kBlocks = 32, std::uint32_t kBlockUpdates = 16>
class StepLocator {
  static_assert(kBlocks >= 1 && kBlockUpdates >= 1, "an empty step locator");

 public:
  struct Estimate {
    float mean = 0.0F;          ///< mean nu after the start (sd units, signed)
    std::uint32_t updates = 0;  ///< updates after the start, up to the current one; 0: none
  };

  /// Forget every block.
  void reset() {
    head_ = 0;
    count_ = 0;
    part_sum_ = 0.0F;
    part_n_ = 0;
  }
  /// One normalised innovation.
  void push(float nu) {
    part_sum_ += nu;
    if (++part_n_ == kBlockUpdates) {
      sum_[head_] = part_sum_;
      head_ = head_ + 1 == kBlocks ? 0 : head_ + 1;
      count_ = count_ < kBlocks ? count_ + 1 : count_;
      part_sum_ = 0.0F;
      part_n_ = 0;
    }
  }
  /// The most likely start of a step in `direction` (+1 up, -1 down) at most `max_updates`
  /// back (the CUSUM's window), and the step's mean.
  [[nodiscard]] Estimate locate(int direction, std::uint64_t max_updates) const {
    Estimate best{};
    float best_stat = -1.0F;
    float tail = part_sum_;  // sum of nu after the candidate start
    std::uint32_t n = part_n_;
    std::size_t idx = head_;  // one past the newest block not yet in the tail
    for (std::size_t i = 0; i <= count_; ++i) {
      if (n > 0 && n <= max_updates && (direction > 0 ? tail > 0.0F : tail < 0.0F)) {
        const float stat = tail * tail / static_cast<float>(n);
        if (stat > best_stat) {
          best_stat = stat;
          best = Estimate{tail / static_cast<float>(n), n};
        }
      }
      if (i == count_) {
        break;
      }
      idx = idx == 0 ? kBlocks - 1 : idx - 1;
      tail += sum_[idx];
      n += kBlockUpdates;
    }
    return best;
  }

 private:
  float sum_[kBlocks] = {};
  std::size_t head_ = 0;
  std::size_t count_ = 0;
  float part_sum_ = 0.0F;
  std::uint32_t part_n_ = 0;
};

/// The three monitors of one channel, fed from the filter's step result, and the locator of
/// the steps the CUSUM detects.
template <std::size_t kLags = 4>
struct ResidualMonitors {
  NisMonitor nis;
  WhitenessMonitor<kLags> whiteness;
  Cusum cusum;
  StepLocator<> locator;

  [[nodiscard]] MonitorStatus configure(std::uint32_t window = 1000) {
    if (nis.configure(window) != MonitorStatus::kOk ||
        whiteness.configure(window) != MonitorStatus::kOk ||
        cusum.configure() != MonitorStatus::kOk) {
      return MonitorStatus::kBadConfig;
    }
    locator.reset();
    return MonitorStatus::kOk;
  }
  /// innovation and its variance S (> 0) of one update.
  void push(float innovation, float innovation_var) {
    if (!(innovation_var > 0.0F)) {
      return;
    }
    const float nu = innovation / std::sqrt(innovation_var);
    nis.push(nu);
    whiteness.push(nu);
    (void)cusum.push(nu);
    locator.push(nu);
  }
  /// In CUSUM alarm: the detected step's start and mean (StepLocator::Estimate), located within
  /// the CUSUM's window, or anywhere in the locator's ring when that window is shorter than one
  /// of its blocks (a step of many sd). Re-arms the CUSUM.
  [[nodiscard]] StepLocator<>::Estimate take_step() {
    const int dir = cusum.direction();
    StepLocator<>::Estimate est = locator.locate(dir, cusum.updates() - cusum.step_index());
    if (est.updates == 0) {
      est = locator.locate(dir, UINT64_MAX);
    }
    cusum.reset();
    return est;
  }
  /// Any monitor fires (the "alarm" output line).
  [[nodiscard]] bool any_alarm() const { return nis.flag() || whiteness.flag() || cusum.alarm(); }
};

}  // namespace imu

#endif  // IMU_RESIDUAL_MONITOR_HPP

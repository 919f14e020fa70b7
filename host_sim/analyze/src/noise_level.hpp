// A change of the white noise's level part way through a record (internal to the analysis).
#ifndef IMU_ANALYZE_NOISE_LEVEL_HPP
#define IMU_ANALYZE_NOISE_LEVEL_HPP

#include <cstddef>
#include <cstdint>
#include <vector>

namespace imu::analyze {

/// One change point of the white noise's level, found on the record's first differences (the
/// white noise dominates them; bias terms, steps and slow lines hardly move them): per block of
/// samples the mean of the squared differences (clipped at 25 x the blocks' median, so that
/// spikes and steps do not count), and a CUSUM of the blocks' log-levels against their mean.
/// Under a constant level the CUSUM is a Brownian bridge: max |S_k| / (sigma sqrt J) exceeds x
/// with probability about 2 exp(-2 x^2) (Kolmogorov), sigma from successive blocks' differences
/// (robust to the change itself). Reported only if that probability is below alpha and the
/// first differences' std changes by at least `min_ratio` (1.1: a 10 % change) between the two
/// parts. That std holds the quantization's and the other terms' share as well as the white
/// noise's: where quantization's AVAR at Ts is 8 x the white noise's, a white std doubling
/// moves it by 15 %.
struct NoiseLevelChange {
  bool found = false;
  std::size_t at = 0;       ///< first sample of the second part
  double std_ratio = 1.0;   ///< white std after / before
  double statistic = 0.0;   ///< max |S_k| / (sigma sqrt J)
  double threshold = 0.0;   ///< x at alpha
  std::size_t blocks = 0;
  std::size_t block_len = 0;
};

/// The median of v (the upper one of an even count); 0 for an empty v.
double median_of(std::vector<double> v);

/// y: the record (gaps marked in `gap`, 1 = missing; may be empty); alpha: the false-alarm rate.
NoiseLevelChange find_noise_level_change(const std::vector<double>& y,
                                         const std::vector<std::uint8_t>& gap, double alpha,
                                         double min_ratio = 1.1);

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_NOISE_LEVEL_HPP

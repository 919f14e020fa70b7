// Loading a sensor recording from a MAT-file and converting it to counts (host code).
#ifndef IMU_SIM_DATA_HPP
#define IMU_SIM_DATA_HPP

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common.hpp"

namespace imu::sim {

struct ChannelData {
  bool present = false;
  std::vector<double> values;   ///< channel units, as stored in the file
  double lsb = 0.0;             ///< value of one count
  bool lsb_from_file = false;   ///< acc_lsb / gyro_lsb read from the file
  std::uint64_t saturated = 0;  ///< samples clipped by quantize()
  std::uint64_t off_grid = 0;   ///< samples that are not an integer multiple of lsb (> 1e-6 lsb)
};

// NOLINTNEXTLINE(bugprone-reserved-identifier): '__i0' is the compiler's implicit array copy loop
struct SensorData {
  std::string path;
  double fs_hz = 0.0;
  std::size_t n_samples = 0;  ///< length of the present channels (all equal)
  ChannelData ch[kNumChannels];
};

/// Read `fs` and the wanted channels (want[c]; a wanted channel that is absent is an error only
/// if required[c]). LSB: lsb_override[c] if > 0, else the file's acc_lsb / gyro_lsb, else
/// default_lsb(c). fs: fs_override if > 0, else the file's `fs`. err is one line naming the
/// file. Cost: one inflate per channel read.
[[nodiscard]] bool load_sensor(const std::string& path, const bool (&want)[kNumChannels],
                               const bool (&required)[kNumChannels],
                               const double (&lsb_override)[kNumChannels], double fs_override,
                               SensorData& out, std::string& err);

/// Counts of one channel (imu::quantize with its LSB); counts saturated / off the LSB grid.
void to_counts(ChannelData& ch, std::vector<std::int32_t>& counts);

}  // namespace imu::sim

#endif  // IMU_SIM_DATA_HPP

// Internal helpers of imu-sim / imu-fw: option parsing, channel names, timing, text output.
// Host code (allocates). Not installed.
#ifndef IMU_SIM_COMMON_HPP
#define IMU_SIM_COMMON_HPP

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "imu/hal/codec.hpp"

namespace imu::sim {

inline constexpr std::size_t kNumChannels = imu::hal::kChannels;
/// MAT-file variable of each protocol channel (hal SampleRecord::counts order).
extern const char* const kChannelNames[kNumChannels];

/// Channel index of a name (acc_x .. gyro_z); false if unknown.
[[nodiscard]] bool channel_index(const std::string& name, std::size_t& out);
/// "m/s^2" for acc_*, "rad/s" for gyro_*.
[[nodiscard]] const char* channel_unit(std::size_t c);
/// Default LSB when a file has none: 1e-6 m/s^2 / 1e-7 rad/s (finer than any IMU noise).
[[nodiscard]] double default_lsb(std::size_t c);

/// One option of a subcommand.
struct OptSpec {
  const char* name;  ///< "--bus"
  bool has_value;
};

/// Parsed command line: options by name, positionals in order. parse() fails on an unknown
/// option, a missing value, or more positionals than allowed, with a one-line error.
class Args {
 public:
  [[nodiscard]] bool parse(int argc, char** argv, int first, const std::vector<OptSpec>& specs,
                           std::size_t max_positional, std::string& err);
  [[nodiscard]] bool has(const std::string& name) const { return opts_.count(name) != 0; }
  [[nodiscard]] std::string get(const std::string& name, const std::string& def = "") const;
  /// Numeric option: def if absent; false (with err) if present but not a finite number.
  [[nodiscard]] bool number(const std::string& name, double def, double& out,
                            std::string& err) const;
  [[nodiscard]] const std::vector<std::string>& positional() const { return pos_; }

 private:
  std::map<std::string, std::string> opts_;
  std::vector<std::string> pos_;
};

/// Monotonic seconds.
[[nodiscard]] double now_s();

/// printf appended to a std::string (any length).
__attribute__((format(printf, 2, 3))) void appendf(std::string& out, const char* fmt, ...);

/// Create a directory and its parents; false with err on failure.
[[nodiscard]] bool make_dirs(const std::string& path, std::string& err);
/// Write a whole file; false with err on failure.
[[nodiscard]] bool write_file(const std::string& path, const std::string& text, std::string& err);

/// Print "imu-sim <cmd>: <msg>" on stderr and return the status (1 or 2).
int fail(const char* cmd, const std::string& msg, int status = 1);

}  // namespace imu::sim

#endif  // IMU_SIM_COMMON_HPP

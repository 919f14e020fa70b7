// Internal helpers of imu-sim / imu-fw: channel names, timing, text output, failures.
// Host code (allocates). Not installed.
#ifndef IMU_SIM_COMMON_HPP
#define IMU_SIM_COMMON_HPP

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/cli/args.hpp"
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

/// The shared parser and exit codes (host_sim/cli): one parser for every subcommand.
using imu::cli::Args;
using imu::cli::kExitOk;
using imu::cli::kExitRuntime;
using imu::cli::kExitUsage;
using imu::cli::OptSpec;

/// Monotonic seconds.
[[nodiscard]] double now_s();

/// printf appended to a std::string (any length).
__attribute__((format(printf, 2, 3))) void appendf(std::string& out, const char* fmt, ...);

/// Create a directory and its parents; false with err on failure.
[[nodiscard]] bool make_dirs(const std::string& path, std::string& err);
/// Write a whole file under a temporary name and rename it: a failure leaves no partial file
/// (imu::cli::write_file_atomic). False with err on failure.
[[nodiscard]] bool write_file(const std::string& path, const std::string& text, std::string& err);

/// Print "imu-sim <cmd>: <msg>" on stderr and return the status (1 or 2).
int fail(const char* cmd, const std::string& msg, int status = 1);

}  // namespace imu::sim

#endif  // IMU_SIM_COMMON_HPP

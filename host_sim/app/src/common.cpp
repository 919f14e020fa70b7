// Internal helpers of imu-sim / imu-fw (see common.hpp).
#include "common.hpp"

#include <sys/stat.h>
#include <time.h>

#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdlib>
#include <cstring>

#include "imu/cli/args.hpp"
#include "imu/cli/file_out.hpp"

namespace imu::sim {

const char* const kChannelNames[kNumChannels] = {"acc_x",  "acc_y",  "acc_z",
                                                 "gyro_x", "gyro_y", "gyro_z"};

bool channel_index(const std::string& name, std::size_t& out) {
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    if (name == kChannelNames[c]) {
      out = c;
      return true;
    }
  }
  return false;
}

const char* channel_unit(std::size_t c) { return c < 3 ? "m/s^2" : "rad/s"; }

double default_lsb(std::size_t c) {
  return c < 3 ? imu::hal::kFineAccLsb_mps2 : imu::hal::kFineGyroLsb_rps;
}

double now_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void appendf(std::string& out, const char* fmt, ...) {
  char buf[1024];
  va_list ap;
  va_start(ap, fmt);
  va_list again;
  va_copy(again, ap);
  // NOLINTNEXTLINE(clang-analyzer-valist.Uninitialized): ap is started above
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  if (n > 0 && static_cast<std::size_t>(n) < sizeof buf) {
    out.append(buf, static_cast<std::size_t>(n));
  } else if (n > 0) {  // longer than the stack buffer: format again into the string itself
    const std::size_t old = out.size();
    out.resize(old + static_cast<std::size_t>(n) + 1);
    (void)std::vsnprintf(&out[old], static_cast<std::size_t>(n) + 1, fmt, again);
    out.resize(old + static_cast<std::size_t>(n));
  }
  va_end(again);
}

bool make_dirs(const std::string& path, std::string& err) {
  return imu::cli::make_dirs(path, err);
}

bool write_file(const std::string& path, const std::string& text, std::string& err) {
  return imu::cli::write_file_atomic(path, text, err);
}

int fail(const char* cmd, const std::string& msg, int status) {
  std::fprintf(stderr, "%s: %s\n", cmd, imu::cli::term_safe(imu::cli::with_suggestion(msg)).c_str());
  return status;
}

}  // namespace imu::sim

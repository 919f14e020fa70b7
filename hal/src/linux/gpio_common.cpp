// Parts of GpioLine shared by the libgpiod and the "unavailable" backends.
#include <cstdio>
#include <cstring>

#include "imu/hal/linux/gpio_line.hpp"

namespace imu::hal {

const char* to_string(GpioStatus s) {
  switch (s) {
    case GpioStatus::kOk: return "ok";
    case GpioStatus::kUnavailable: return "unavailable";
    case GpioStatus::kNoSuchChip: return "no-such-chip";
    case GpioStatus::kNoSuchLine: return "no-such-line";
    case GpioStatus::kLineBusy: return "line-busy";
    case GpioStatus::kNotOpen: return "not-open";
    case GpioStatus::kWrongDirection: return "wrong-direction";
    case GpioStatus::kTimeout: return "timeout";
    case GpioStatus::kBadArgument: return "bad-argument";
    case GpioStatus::kSysError: return "system-error";
  }
  return "?";
}

GpioStatus GpioLine::fail(GpioStatus s, int err, const char* what) {
  if (err != 0) {
    std::snprintf(error_, sizeof error_, "gpio: %s (chip '%s', line '%s'): %s", what, chip_name_,
                  line_name_, std::strerror(err));
  } else {
    std::snprintf(error_, sizeof error_, "gpio: %s (chip '%s', line '%s')", what, chip_name_,
                  line_name_);
  }
  return s;
}

GpioLine::~GpioLine() { close(); }

GpioLine::GpioLine(GpioLine&& other) noexcept
    : chip_(other.chip_), line_(other.line_), mode_(other.mode_) {
  std::memcpy(chip_name_, other.chip_name_, sizeof chip_name_);
  std::memcpy(line_name_, other.line_name_, sizeof line_name_);
  std::memcpy(error_, other.error_, sizeof error_);
  other.chip_ = nullptr;
  other.line_ = nullptr;
}

GpioLine& GpioLine::operator=(GpioLine&& other) noexcept {
  if (this != &other) {
    close();
    chip_ = other.chip_;
    line_ = other.line_;
    mode_ = other.mode_;
    std::memcpy(chip_name_, other.chip_name_, sizeof chip_name_);
    std::memcpy(line_name_, other.line_name_, sizeof line_name_);
    std::memcpy(error_, other.error_, sizeof error_);
    other.chip_ = nullptr;
    other.line_ = nullptr;
  }
  return *this;
}

}  // namespace imu::hal

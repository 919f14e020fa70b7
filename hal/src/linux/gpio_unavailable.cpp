// GpioLine when the build has no libgpiod (chosen by hal/CMakeLists.txt): every open() fails
// with kUnavailable and a message, so the rest of the program builds and runs without GPIO.
#include <cstdio>

#include "imu/hal/linux/gpio_line.hpp"

namespace imu::hal {

bool GpioLine::available() { return false; }

void GpioLine::close() {
  line_ = nullptr;
  chip_ = nullptr;
}

GpioStatus GpioLine::open(const LineConfig& cfg) {
  std::snprintf(chip_name_, sizeof chip_name_, "%s", cfg.chip != nullptr ? cfg.chip : "");
  std::snprintf(line_name_, sizeof line_name_, "%s", cfg.line != nullptr ? cfg.line : "");
  return fail(GpioStatus::kUnavailable, 0, "this build has no libgpiod");
}

GpioStatus GpioLine::read(bool& active) {
  active = false;
  return GpioStatus::kNotOpen;
}

GpioStatus GpioLine::write(bool /*active*/) { return GpioStatus::kNotOpen; }

int GpioLine::event_fd() const { return -1; }

GpioStatus GpioLine::wait_edge(int /*timeout_ms*/, EdgeEvent& out) {
  out = EdgeEvent{};
  return GpioStatus::kNotOpen;
}

}  // namespace imu::hal

// GpioLine over the libgpiod 1.6 C API (Debian 12: libgpiod 1.6.3). The C++ bindings of
// libgpiod throw and allocate; the C API returns -1/NULL with errno, mapped here to GpioStatus.
#include <gpiod.h>
#include <poll.h>

#include <cerrno>
#include <cstdio>

#include "imu/hal/linux/gpio_line.hpp"

namespace imu::hal {

bool GpioLine::available() { return true; }

void GpioLine::close() {
  if (line_ != nullptr) {
    gpiod_line_release(line_);
    line_ = nullptr;
  }
  if (chip_ != nullptr) {
    gpiod_chip_close(chip_);
    chip_ = nullptr;
  }
}

GpioStatus GpioLine::open(const LineConfig& cfg) {
  close();
  error_[0] = '\0';
  std::snprintf(chip_name_, sizeof chip_name_, "%s", cfg.chip != nullptr ? cfg.chip : "");
  std::snprintf(line_name_, sizeof line_name_, "%s", cfg.line != nullptr ? cfg.line : "");
  if (chip_name_[0] == '\0' || line_name_[0] == '\0') {
    return fail(GpioStatus::kBadArgument, 0, "chip and line names are required");
  }
  errno = 0;
  chip_ = gpiod_chip_open_lookup(chip_name_);
  if (chip_ == nullptr) {
    const int err = errno != 0 ? errno : ENOENT;
    return fail(err == ENOENT || err == ENODEV || err == ENOTTY ? GpioStatus::kNoSuchChip
                                                                : GpioStatus::kSysError,
                err, "chip not found");
  }
  errno = 0;
  line_ = gpiod_chip_find_line(chip_, line_name_);
  if (line_ == nullptr) {
    const int err = errno != 0 ? errno : ENOENT;
    close();
    return fail(err == ENOENT ? GpioStatus::kNoSuchLine : GpioStatus::kSysError, err,
                "line not found on chip");
  }
  const int flags = cfg.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
  const char* consumer = cfg.consumer != nullptr ? cfg.consumer : "imu-hal";
  int rc = -1;
  switch (cfg.mode) {
    case LineMode::kInput:
      rc = gpiod_line_request_input_flags(line_, consumer, flags);
      break;
    case LineMode::kOutput:
      rc = gpiod_line_request_output_flags(line_, consumer, flags, cfg.initial_active ? 1 : 0);
      break;
    case LineMode::kEdges:
      rc = gpiod_line_request_both_edges_events_flags(line_, consumer, flags);
      break;
  }
  if (rc != 0) {
    const int err = errno;
    line_ = nullptr;  // not requested: nothing to release
    close();
    return fail(err == EBUSY ? GpioStatus::kLineBusy : GpioStatus::kSysError, err,
                "line request failed");
  }
  mode_ = cfg.mode;
  return GpioStatus::kOk;
}

GpioStatus GpioLine::read(bool& active) {
  if (line_ == nullptr) {
    return GpioStatus::kNotOpen;
  }
  const int v = gpiod_line_get_value(line_);
  if (v < 0) {
    return fail(GpioStatus::kSysError, errno, "read");
  }
  active = v != 0;
  return GpioStatus::kOk;
}

GpioStatus GpioLine::write(bool active) {
  if (line_ == nullptr) {
    return GpioStatus::kNotOpen;
  }
  if (mode_ != LineMode::kOutput) {
    return fail(GpioStatus::kWrongDirection, 0, "write on an input line");
  }
  if (gpiod_line_set_value(line_, active ? 1 : 0) != 0) {
    return fail(GpioStatus::kSysError, errno, "write");
  }
  return GpioStatus::kOk;
}

int GpioLine::event_fd() const {
  if (line_ == nullptr || mode_ != LineMode::kEdges) {
    return -1;
  }
  return gpiod_line_event_get_fd(line_);
}

GpioStatus GpioLine::wait_edge(int timeout_ms, EdgeEvent& out) {
  if (line_ == nullptr) {
    return GpioStatus::kNotOpen;
  }
  if (mode_ != LineMode::kEdges) {
    return fail(GpioStatus::kWrongDirection, 0, "edge wait on a line without edge events");
  }
  pollfd p{gpiod_line_event_get_fd(line_), POLLIN, 0};
  const int pr = poll(&p, 1, timeout_ms);
  if (pr == 0) {
    return GpioStatus::kTimeout;
  }
  if (pr < 0) {
    return errno == EINTR ? GpioStatus::kTimeout : fail(GpioStatus::kSysError, errno, "poll");
  }
  gpiod_line_event ev{};
  if (gpiod_line_event_read(line_, &ev) != 0) {
    return fail(GpioStatus::kSysError, errno, "event read");
  }
  out.rising = ev.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
  out.time_ns = static_cast<std::uint64_t>(ev.ts.tv_sec) * 1'000'000'000ULL +
                static_cast<std::uint64_t>(ev.ts.tv_nsec);
  return GpioStatus::kOk;
}

}  // namespace imu::hal

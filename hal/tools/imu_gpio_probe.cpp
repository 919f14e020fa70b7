// imu-gpio-probe: open one GPIO line by chip and line name and read it, drive it, or wait for
// edges. For bring-up and the gpio-sim VM test.
//   imu-gpio-probe --chip gpiochip0 --line static                 # prints "value=0|1"
//   imu-gpio-probe --chip gpiochip0 --line alarm --set 1 [--hold-ms 500]
//   imu-gpio-probe --chip gpiochip0 --line drdy --edges 3 --timeout-ms 2000
// Options: --active-low. Exit: 0 ok, 1 runtime error or timeout, 2 usage, 3 chip/line missing.
#include <poll.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "imu/hal/linux/gpio_line.hpp"

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: imu-gpio-probe --chip NAME --line NAME [--active-low]\n"
               "                      [--set 0|1 [--hold-ms MS]] [--edges N [--timeout-ms MS]]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  imu::hal::LineConfig cfg;
  cfg.consumer = "imu-gpio-probe";
  int set_value = -1;
  int hold_ms = 0;
  int edges = 0;
  int timeout_ms = 1000;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const bool has_value = i + 1 < argc;
    if (std::strcmp(a, "--chip") == 0 && has_value) {
      cfg.chip = argv[++i];
    } else if (std::strcmp(a, "--line") == 0 && has_value) {
      cfg.line = argv[++i];
    } else if (std::strcmp(a, "--set") == 0 && has_value) {
      set_value = std::atoi(argv[++i]) != 0 ? 1 : 0;
    } else if (std::strcmp(a, "--hold-ms") == 0 && has_value) {
      hold_ms = std::atoi(argv[++i]);
    } else if (std::strcmp(a, "--edges") == 0 && has_value) {
      edges = std::atoi(argv[++i]);
    } else if (std::strcmp(a, "--timeout-ms") == 0 && has_value) {
      timeout_ms = std::atoi(argv[++i]);
    } else if (std::strcmp(a, "--active-low") == 0) {
      cfg.active_low = true;
    } else {
      return usage();
    }
  }
  if (cfg.chip == nullptr || cfg.line == nullptr || (set_value >= 0 && edges > 0)) {
    return usage();
  }
  cfg.mode = set_value >= 0 ? imu::hal::LineMode::kOutput
                            : (edges > 0 ? imu::hal::LineMode::kEdges : imu::hal::LineMode::kInput);
  cfg.initial_active = set_value == 1;
  imu::hal::GpioLine line;
  const imu::hal::GpioStatus s = line.open(cfg);
  if (s != imu::hal::GpioStatus::kOk) {
    std::fprintf(stderr, "imu-gpio-probe: %s [%s]\n", line.error(), imu::hal::to_string(s));
    return s == imu::hal::GpioStatus::kNoSuchChip || s == imu::hal::GpioStatus::kNoSuchLine ||
                   s == imu::hal::GpioStatus::kUnavailable
               ? 3
               : 1;
  }
  if (set_value >= 0) {
    if (line.write(set_value == 1) != imu::hal::GpioStatus::kOk) {
      std::fprintf(stderr, "imu-gpio-probe: %s\n", line.error());
      return 1;
    }
    std::printf("set=%d\n", set_value);
    std::fflush(stdout);
    if (hold_ms > 0) {
      poll(nullptr, 0, hold_ms);  // keep the line requested (and driven) for a while
    }
    return 0;
  }
  if (edges > 0) {
    for (int k = 0; k < edges; ++k) {
      imu::hal::EdgeEvent e{};
      const imu::hal::GpioStatus w = line.wait_edge(timeout_ms, e);
      if (w != imu::hal::GpioStatus::kOk) {
        std::fprintf(stderr, "imu-gpio-probe: edge %d: %s\n", k, imu::hal::to_string(w));
        return 1;
      }
      std::printf("edge=%s t_ns=%llu\n", e.rising ? "rising" : "falling",
                  static_cast<unsigned long long>(e.time_ns));
    }
    return 0;
  }
  bool v = false;
  if (line.read(v) != imu::hal::GpioStatus::kOk) {
    std::fprintf(stderr, "imu-gpio-probe: %s\n", line.error());
    return 1;
  }
  std::printf("value=%d\n", v ? 1 : 0);
  return 0;
}

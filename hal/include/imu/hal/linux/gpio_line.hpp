// GPIO lines for the IMU node: the "static" input (bias filter updates while active), the
// "alarm" output (set while a residual monitor fires) and an optional data-ready / sync input
// with kernel edge timestamps. Chip and line names are configuration (LineConfig), never
// constants; a missing chip or line is reported at open() with a message naming both.
//
// Linux backend of the digital-line port (imu/hal/digital_line.hpp: DigitalInput,
// DigitalOutput): GpioLine (libgpiod 1.6 C API, RAII). The simulation backend is MemoryLine
// (imu/hal/sim/memory_line.hpp).
// The GpioLine backend is chosen by CMake: with libgpiod found it uses it; without (e.g. a
// cross build lacking the arm64 libgpiod) every open() returns kUnavailable with a message.
// No exceptions cross this boundary; every call returns a GpioStatus.
#ifndef IMU_HAL_LINUX_GPIO_LINE_HPP
#define IMU_HAL_LINUX_GPIO_LINE_HPP

#include <cstdint>

#include "imu/hal/digital_line.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace imu::hal {

[[nodiscard]] const char* to_string(GpioStatus s);

enum class LineMode : std::uint8_t {
  kInput,   ///< level input (e.g. "static")
  kOutput,  ///< level output (e.g. "alarm")
  kEdges,   ///< input with both-edge events and kernel timestamps (e.g. "drdy")
};

struct LineConfig {
  const char* chip = nullptr;      ///< "gpiochip0", "0", "/dev/gpiochip0" or a chip label
  const char* line = nullptr;      ///< line name as in the device tree / gpio-sim configfs
  const char* consumer = "imu-hal";
  LineMode mode = LineMode::kInput;
  bool active_low = false;         ///< "active" means electrically low
  bool initial_active = false;     ///< output value at request time
};

/// One edge. time_ns is the kernel's event timestamp (CLOCK_MONOTONIC on Debian 12's kernel).
struct EdgeEvent {
  bool rising;  ///< towards active (after active_low inversion)
  std::uint64_t time_ns;
};

/// A line requested through libgpiod. Move-only; releases the line and closes the chip when
/// destroyed. Each call is one ioctl (read/write) or one read() (edges).
class GpioLine final : public DigitalInput, public DigitalOutput {
 public:
  GpioLine() = default;
  ~GpioLine() override;
  GpioLine(const GpioLine&) = delete;
  GpioLine& operator=(const GpioLine&) = delete;
  GpioLine(GpioLine&& other) noexcept;
  GpioLine& operator=(GpioLine&& other) noexcept;

  /// False when this build has no libgpiod (every open() then returns kUnavailable).
  [[nodiscard]] static bool available();

  /// Find the chip and the line by name and request it in cfg.mode. On failure error() says
  /// which chip or line, e.g. "gpio: chip 'gpiochip7' not found: No such file or directory".
  [[nodiscard]] GpioStatus open(const LineConfig& cfg);
  void close();

  [[nodiscard]] GpioStatus read(bool& active) override;   ///< kInput, kOutput or kEdges
  [[nodiscard]] GpioStatus write(bool active) override;   ///< kOutput only
  /// kEdges only: wait up to timeout_ms (-1 forever) for one edge. kTimeout if none.
  [[nodiscard]] GpioStatus wait_edge(int timeout_ms, EdgeEvent& out);
  /// kEdges only: descriptor to poll together with the CAN socket; -1 otherwise.
  [[nodiscard]] int event_fd() const;

  [[nodiscard]] const char* error() const { return error_; }
  [[nodiscard]] bool is_open() const { return line_ != nullptr; }

 private:
  GpioStatus fail(GpioStatus s, int err, const char* what);

  gpiod_chip* chip_ = nullptr;
  gpiod_line* line_ = nullptr;
  LineMode mode_ = LineMode::kInput;
  char chip_name_[64] = {};
  char line_name_[64] = {};
  char error_[192] = {};
};

}  // namespace imu::hal

#endif  // IMU_HAL_LINUX_GPIO_LINE_HPP

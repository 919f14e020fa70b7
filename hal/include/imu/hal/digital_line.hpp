// HAL port: digital lines. DigitalInput (e.g. the "static" input), DigitalOutput (e.g. the
// "alarm" output) and their status. Interfaces only: the firmware node is written against these.
// Backends: GpioLine (Linux, libgpiod: imu/hal/linux/gpio_line.hpp) and MemoryLine (simulation
// and tests: imu/hal/sim/memory_line.hpp). No exceptions cross this boundary; every call
// returns a GpioStatus.
#ifndef IMU_HAL_DIGITAL_LINE_HPP
#define IMU_HAL_DIGITAL_LINE_HPP

#include <cstdint>

namespace imu::hal {

enum class GpioStatus : std::uint8_t {
  kOk,
  kUnavailable,     ///< built without libgpiod
  kNoSuchChip,
  kNoSuchLine,
  kLineBusy,        ///< requested by another consumer
  kNotOpen,
  kWrongDirection,  ///< write() on an input, read of edges on a non-edge line, ...
  kTimeout,
  kBadArgument,
  kSysError,
};

class DigitalInput {
 public:
  virtual ~DigitalInput() = default;
  [[nodiscard]] virtual GpioStatus read(bool& active) = 0;
};

class DigitalOutput {
 public:
  virtual ~DigitalOutput() = default;
  [[nodiscard]] virtual GpioStatus write(bool active) = 0;
};

}  // namespace imu::hal

#endif  // IMU_HAL_DIGITAL_LINE_HPP

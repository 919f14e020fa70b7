// Simulation backend of the digital-line port (imu/hal/digital_line.hpp): an in-memory line for
// simulation, tests and targets without GPIO. Header-only, no OS, no heap.
#ifndef IMU_HAL_SIM_MEMORY_LINE_HPP
#define IMU_HAL_SIM_MEMORY_LINE_HPP

#include <cstdint>

#include "imu/hal/digital_line.hpp"

namespace imu::hal {

/// In-memory line: reads what was last written or set by set(). For simulation and tests of
/// code that takes a DigitalInput / DigitalOutput.
class MemoryLine final : public DigitalInput, public DigitalOutput {
 public:
  [[nodiscard]] GpioStatus read(bool& active) override {
    active = value_;
    return GpioStatus::kOk;
  }
  [[nodiscard]] GpioStatus write(bool active) override {
    value_ = active;
    ++writes_;
    return GpioStatus::kOk;
  }
  void set(bool active) { value_ = active; }
  [[nodiscard]] std::uint64_t writes() const { return writes_; }

 private:
  bool value_ = false;
  std::uint64_t writes_ = 0;
};

}  // namespace imu::hal

#endif  // IMU_HAL_SIM_MEMORY_LINE_HPP

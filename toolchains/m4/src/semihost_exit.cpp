// The test images' exit and fault handling (imu/hal/mcu/startup.hpp): through semihosting, so
// QEMU exits with the program's status, or 3 on a processor fault.
#include <cstdint>

#include "imu/hal/mcu/startup.hpp"
#include "semihost.hpp"

extern "C" void imu_m4_exit(int rc) { imu::m4::semihost_exit(static_cast<std::uint32_t>(rc)); }

extern "C" void imu_m4_fault() {
  imu::m4::semihost_write0("IMU-M4 FAULT: processor exception\n");
  imu::m4::semihost_exit(3);
}

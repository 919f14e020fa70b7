// Minimal Arm semihosting for the bare-metal program (no newlib stdio, no heap).
// Works on QEMU with `-semihosting-config enable=on,target=native` and on a debugger that
// implements semihosting; on real hardware without a debugger `bkpt 0xAB` faults, which is the
// documented behaviour of semihosting, so this is for test images only.
// Cost: one trap to the host per call (slow: milliseconds under a debugger).
#ifndef IMU_M4_SEMIHOST_HPP
#define IMU_M4_SEMIHOST_HPP

#include <cstdint>

namespace imu::m4 {

/// SYS_WRITE0: writes a NUL-terminated string to the host console. Not re-entrant.
void semihost_write0(const char* text);

/// SYS_EXIT_EXTENDED with ADP_Stopped_ApplicationExit and `code`: QEMU exits with `code`.
[[noreturn]] void semihost_exit(std::uint32_t code);

}  // namespace imu::m4

#endif  // IMU_M4_SEMIHOST_HPP

// What the startup code exposes to the program (the stack high-water mark) and what it needs
// from the image (exit and fault handling).
#ifndef IMU_M4_STARTUP_HPP
#define IMU_M4_STARTUP_HPP

#include <cstddef>

extern "C" {
/// After imu_m4_main() returns, with its value. Provided by the image (never returns).
[[noreturn]] void imu_m4_exit(int rc);
/// From every fault and unused exception vector. Provided by the image (never returns).
[[noreturn]] void imu_m4_fault();
}

namespace imu::m4 {

/// Bytes of the stack section ever written since reset (painted-pattern scan). O(stack size).
std::size_t stack_high_water_bytes();
/// Size of the stack section (linker symbol IMU_M4_STACK_SIZE).
std::size_t stack_size_bytes();

}  // namespace imu::m4

#endif  // IMU_M4_STARTUP_HPP

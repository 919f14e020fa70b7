// What the startup code exposes to the program: the stack high-water mark.
#ifndef IMU_M4_STARTUP_HPP
#define IMU_M4_STARTUP_HPP

#include <cstddef>

namespace imu::m4 {

/// Bytes of the stack section ever written since reset (painted-pattern scan). O(stack size).
std::size_t stack_high_water_bytes();
/// Size of the stack section (linker symbol IMU_M4_STACK_SIZE).
std::size_t stack_size_bytes();

}  // namespace imu::m4

#endif  // IMU_M4_STARTUP_HPP

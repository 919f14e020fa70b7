// Bare-metal MCU backend: the Cortex-M4F startup of a board folder (hal/src/mcu/boards/<board>/
// startup.cpp), what it exposes to the program (the stack's size and high-water mark) and what it
// needs from the image (the program, its exit and the fault handling).
//
// Reset: FPU on, .data copied, .bss zeroed, the stack painted, static constructors run, then
// imu_m4_exit(imu_m4_main()). Every fault and unused core exception calls imu_m4_fault(). The
// program above the HAL defines imu_m4_main (the node's main loop, fw/node/src/mcu_main.cpp, or
// a test image's); the image's exit policy defines imu_m4_exit and imu_m4_fault (the
// production images: the board's imu_board_fault, boards/<board>/board_hooks.cpp; the test
// images: semihosting).
#ifndef IMU_HAL_MCU_STARTUP_HPP
#define IMU_HAL_MCU_STARTUP_HPP

#include <cstddef>

extern "C" {
/// The program, called once by the reset handler after the C++ runtime is set up. Provided by
/// the image. (A function of its own because ISO C++ forbids calling main().)
int imu_m4_main();
/// After imu_m4_main() returns, with its value. Provided by the image (never returns).
[[noreturn]] void imu_m4_exit(int rc);
/// From every fault and unused exception vector. Provided by the image (never returns).
[[noreturn]] void imu_m4_fault();
}

namespace imu::hal::mcu {

/// Bytes of the stack section ever written since reset (painted-pattern scan). O(stack size).
std::size_t stack_high_water_bytes();
/// Size of the stack section (linker symbol IMU_M4_STACK_SIZE).
std::size_t stack_size_bytes();

}  // namespace imu::hal::mcu

#endif  // IMU_HAL_MCU_STARTUP_HPP

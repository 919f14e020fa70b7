// The board hooks of mps2-an386 (imu/hal/mcu/board_hooks.hpp) for the production node images,
// and their exit and fault policy (imu/hal/mcu/startup.hpp). QEMU's mps2-an386 has no CAN
// controller, so every hook is the contract's default, defined weak: a board shim linked into
// the same image (the QEMU smoke variant, toolchains/m4/src/prod_smoke_board.cpp) replaces any
// of them. A board with a CAN controller defines them in its own folder's board_hooks.cpp.
// The test images do not link this file: they exit through semihosting.
#include <cstdint>

#include "imu/hal/mcu/board_hooks.hpp"
#include "imu/hal/mcu/startup.hpp"

namespace {

constexpr std::uintptr_t kScbAircr = 0xE000ED0CU;
constexpr std::uint32_t kAircrSysReset = 0x05FA0004U;  // VECTKEY | SYSRESETREQ

}  // namespace

__attribute__((weak)) void imu_board_init() {}
__attribute__((weak)) void imu_board_can_init() {}
__attribute__((weak)) bool imu_board_can_send(const imu::hal::CanFrame& /*f*/) { return false; }
__attribute__((weak)) std::uint32_t imu_board_millis() { return 0; }

__attribute__((weak)) void imu_board_fault() {
  asm volatile("dsb" ::: "memory");
  *reinterpret_cast<volatile std::uint32_t*>(kScbAircr) =  // NOLINT: SCB register
      kAircrSysReset;
  asm volatile("dsb" ::: "memory");
  for (;;) {
    asm volatile("wfi");
  }
}

// The node's main loop returns only if the node refused its configuration: a fault.
extern "C" void imu_m4_exit(int /*rc*/) { imu_board_fault(); }
extern "C" void imu_m4_fault() { imu_board_fault(); }

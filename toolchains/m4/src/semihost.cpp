// Semihosting calls: operation in r0, argument in r1, `bkpt 0xAB` (M-profile), result in r0.
#include "semihost.hpp"

namespace imu::m4 {
namespace {

constexpr std::uint32_t kSysWrite0 = 0x04;
constexpr std::uint32_t kSysExitExtended = 0x20;
constexpr std::uint32_t kAdpStoppedApplicationExit = 0x20026;

std::uint32_t semihost_call(std::uint32_t op, const void* arg) {
  std::uint32_t result = 0;
  // Explicit moves instead of `register ... asm("r0")` variables, which C++17 forbids.
  asm volatile(
      "mov r0, %1\n\t"
      "mov r1, %2\n\t"
      "bkpt 0xAB\n\t"
      "mov %0, r0"
      : "=r"(result)
      : "r"(op), "r"(arg)
      : "r0", "r1", "memory");
  return result;
}

}  // namespace

void semihost_write0(const char* text) { static_cast<void>(semihost_call(kSysWrite0, text)); }

void semihost_exit(std::uint32_t code) {
  const std::uint32_t block[2] = {kAdpStoppedApplicationExit, code};
  static_cast<void>(semihost_call(kSysExitExtended, block));
  for (;;) {  // not reached when semihosting is enabled
  }
}

}  // namespace imu::m4

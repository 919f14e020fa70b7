// Bare-metal program (imu_m4_main, called by the board's reset handler, imu/hal/mcu/startup.hpp):
// runs the demo workload, prints through semihosting, reports the stack high-water mark,
// returns 0 (QEMU exit code) when every line was complete.
#include "demo.hpp"
#include "imu/hal/mcu/startup.hpp"
#include "line.hpp"
#include "semihost.hpp"

namespace {

void write_semihost(const char* text, void* /*ctx*/) { imu::m4::semihost_write0(text); }

}  // namespace

extern "C" int imu_m4_main() {
  const imu::m4::DemoStatus st = imu::m4::run_demo(write_semihost, nullptr);
  imu::m4::Line<> line;
  line.str("IMU-M4 STACK used=").u64(imu::hal::mcu::stack_high_water_bytes());
  line.str(" of=").u64(imu::hal::mcu::stack_size_bytes()).str("\n");
  imu::m4::semihost_write0(line.c_str());
  return st == imu::m4::DemoStatus::kOk ? 0 : 1;
}

// imu/hal/gpio_line.hpp. There is no GPIO chip on the build machines: these tests cover the
// start-up errors (missing chip or line must be a clear error naming it) and the interfaces.
// Requesting real lines is tested in the VM against gpio-sim (imu-gpio-probe).
#include "imu/hal/linux/gpio_line.hpp"
#include "imu/hal/sim/memory_line.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>

namespace {

using imu::hal::GpioLine;
using imu::hal::GpioStatus;
using imu::hal::LineConfig;
using imu::hal::LineMode;

TEST(GpioLine, MissingChipIsAClearErrorNamingChipAndLine) {
  GpioLine line;
  LineConfig cfg;
  cfg.chip = "imu-no-such-chip";
  cfg.line = "static";
  const GpioStatus s = line.open(cfg);
  if (!GpioLine::available()) {
    EXPECT_EQ(s, GpioStatus::kUnavailable);
  } else {
    EXPECT_EQ(s, GpioStatus::kNoSuchChip);
  }
  const std::string msg = line.error();
  EXPECT_NE(msg.find("imu-no-such-chip"), std::string::npos) << msg;
  EXPECT_NE(msg.find("static"), std::string::npos) << msg;
  EXPECT_FALSE(line.is_open());
}

TEST(GpioLine, MissingChipByPathAndNumberToo) {
  GpioLine line;
  LineConfig cfg;
  cfg.chip = "/dev/gpiochip-imu-absent";
  cfg.line = "alarm";
  cfg.mode = LineMode::kOutput;
  const GpioStatus s = line.open(cfg);
  EXPECT_TRUE(s == GpioStatus::kNoSuchChip || s == GpioStatus::kUnavailable)
      << imu::hal::to_string(s) << ": " << line.error();
  cfg.chip = "97";  // gpiochip97
  const GpioStatus s2 = line.open(cfg);
  EXPECT_TRUE(s2 == GpioStatus::kNoSuchChip || s2 == GpioStatus::kUnavailable)
      << imu::hal::to_string(s2) << ": " << line.error();
}

TEST(GpioLine, NamesAreRequired) {
  if (!GpioLine::available()) {
    GTEST_SKIP() << "built without libgpiod";
  }
  GpioLine line;
  LineConfig cfg;
  EXPECT_EQ(line.open(cfg), GpioStatus::kBadArgument);
  cfg.chip = "gpiochip0";
  EXPECT_EQ(line.open(cfg), GpioStatus::kBadArgument);
}

TEST(GpioLine, CallsOnAClosedLineReturnNotOpen) {
  GpioLine line;
  bool v = true;
  EXPECT_EQ(line.read(v), GpioStatus::kNotOpen);
  EXPECT_EQ(line.write(true), GpioStatus::kNotOpen);
  imu::hal::EdgeEvent e{};
  EXPECT_EQ(line.wait_edge(0, e), GpioStatus::kNotOpen);
  EXPECT_EQ(line.event_fd(), -1);
  GpioLine moved(std::move(line));
  EXPECT_FALSE(moved.is_open());
}

TEST(GpioLine, MemoryLineServesBothInterfaces) {
  imu::hal::MemoryLine m;
  imu::hal::DigitalOutput& out = m;
  imu::hal::DigitalInput& in = m;
  bool v = true;
  ASSERT_EQ(in.read(v), GpioStatus::kOk);
  EXPECT_FALSE(v);
  ASSERT_EQ(out.write(true), GpioStatus::kOk);
  ASSERT_EQ(in.read(v), GpioStatus::kOk);
  EXPECT_TRUE(v);
  m.set(false);
  ASSERT_EQ(in.read(v), GpioStatus::kOk);
  EXPECT_FALSE(v);
  EXPECT_EQ(m.writes(), 1U);
}

}  // namespace

// imu-fw as a process against a loopback peer that never comes, falls silent or dies:
// it must end on its own, promptly, with one line on stderr when the peer is gone.
// The peer is this test process (hal::CanSocket on the same loopback name).
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "fw_process.hpp"
#include "imu/hal/codec.hpp"
#include "imu/hal/linux/can_socket.hpp"
#include "sim_test_util.hpp"

namespace {
using fwtest::FwProcess;
using fwtest::send_stream;
using fwtest::unique_bus;
using fwtest::wait_listening;

// Start-up check: these passed (first_order_gm_from_asd gave kOk with phi = 1, a NaN or an
// infinite Qn) and imu-fw ran with filters never configured. Now exit 2, one line, at once.
TEST(ImuFwPeer, AbsurdModelOptionsAreRefusedAtStart) {
  SKIP_IF_EMULATED();
  const std::vector<std::vector<std::string>> cases = {
      {"--Tp", "1e-300"}, {"--Tp", "1e300"}, {"--N", "1e300"}, {"--gyro-B", "1e-300"}};
  for (const auto& opt : cases) {
    FwProcess fw({"--bus", unique_bus("model"), opt[0], opt[1], "--quiet"});
    ASSERT_TRUE(fw.wait(5.0)) << opt[0] << " " << opt[1] << ": imu-fw still running";
    EXPECT_EQ(fw.status(), 2) << opt[0] << " " << opt[1];
    EXPECT_EQ(simtest::count_lines(fw.err()), 1U) << fw.err();
    EXPECT_NE(fw.err().find("node configuration rejected"), std::string::npos) << fw.err();
  }
}

// No peer ever comes: before --peer-timeout-s imu-fw waited forever (there was no such option:
// exit 2 on the unknown option).
TEST(ImuFwPeer, NoPeerAtAllEndsWithStatusOneAndOneLine) {
  SKIP_IF_EMULATED();
  FwProcess fw({"--bus", unique_bus("none"), "--peer-timeout-s", "1", "--quiet"});
  ASSERT_TRUE(fw.wait(10.0)) << "imu-fw still running after 10 s";
  EXPECT_EQ(fw.status(), 1) << fw.err();
  EXPECT_EQ(simtest::count_lines(fw.err()), 1U) << fw.err();
  EXPECT_NE(fw.err().find("imu-fw: no frame from the peer"), std::string::npos) << fw.err();
  // 1 s timeout, checked at each 200 ms idle poll: 1.0 .. ~1.5 s; 5 s for a loaded machine.
  EXPECT_GE(fw.elapsed_s(), 1.0);
  EXPECT_LT(fw.elapsed_s(), 5.0);
}

// The peer sends a stream, then stays connected and silent (hung): the same exit.
TEST(ImuFwPeer, SilentPeerEndsWithStatusOne) {
  SKIP_IF_EMULATED();
  const std::string bus = unique_bus("silent");
  FwProcess fw({"--bus", bus, "--peer-timeout-s", "1", "--quiet"});
  ASSERT_TRUE(wait_listening(bus, 5.0));
  imu::hal::CanSocket peer;
  ASSERT_EQ(peer.open(bus.c_str()), imu::hal::IoStatus::kOk);
  send_stream(peer, 150);
  ASSERT_TRUE(fw.wait(10.0)) << "imu-fw still running after 10 s";
  EXPECT_EQ(fw.status(), 1) << fw.err();
  EXPECT_EQ(simtest::count_lines(fw.err()), 1U) << fw.err();
  EXPECT_NE(fw.out().find("150 samples"), std::string::npos) << fw.out();
}

// The peer dies after a stream (its socket closes): the loopback end of stream, exit 0. The
// final telemetry has nowhere to go; imu-fw used to wait 2 s in accept() for each of its ~130
// frames (minutes). Now the first refused frame stops the rest: one 2 s wait. Bound 8 s.
TEST(ImuFwPeer, DeadPeerEndsPromptly) {
  SKIP_IF_EMULATED();
  const std::string bus = unique_bus("dead");
  FwProcess fw({"--bus", bus, "--quiet"});
  ASSERT_TRUE(wait_listening(bus, 5.0));  // imu-fw listens: after the peer, it waits in accept()
  {
    imu::hal::CanSocket peer;
    ASSERT_EQ(peer.open(bus.c_str()), imu::hal::IoStatus::kOk);
    send_stream(peer, 300);
  }  // closed: the peer is gone
  ASSERT_TRUE(fw.wait(8.0)) << "imu-fw still running 8 s after its peer died: " << fw.err();
  std::printf("imu-fw ended %.2f s after start (peer died after 300 samples)\n", fw.elapsed_s());
  EXPECT_EQ(fw.status(), 0) << fw.err();
  EXPECT_NE(fw.out().find("stream ended (link-down): 300 samples"), std::string::npos)
      << fw.out();
}

}  // namespace

// Long test (label long): the 1,000,000-sample ADIS16405 acc_z channel through imu-sim run at
// --rate max over the loopback bus (in-process node): no frame lost, under 30 s, and the same
// ADEV as imu-sim adev. Skipped when the shared data is absent.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <time.h>

#include <cstdio>
#include <string>

#include "sim_test_util.hpp"

namespace {

double now_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

TEST(SimAdis, RunAtMaxRateOverLoopback) {
  const std::string mat = std::string(IMU_SHARED_DIR) + "/data/adis16405_imu1.mat";
  struct stat st {};
  if (stat(mat.c_str(), &st) != 0) {
    GTEST_SKIP() << "shared data absent: " << mat;
  }
  simtest::TempDir dir;
  const double t0 = now_s();
  auto r = simtest::run({"run", mat, "--channel", "acc_z", "--bus", "loopback",
                         "--rate", "max", "--out", dir.file("run"), "--no-plots", "--quiet"});
  const double t_run = now_s() - t0;
  ASSERT_EQ(r.status, 0) << r.err;
  std::printf("imu-sim run on adis16405_imu1 acc_z (1e6 samples): %.2f s\n", t_run);
  EXPECT_LT(t_run, 30.0) << "the 1,000,000-sample channel in under 30 s";
  const std::string json = simtest::read_text(dir.file("run") + "/report.json");
  const char* node = "node_stats";
  EXPECT_EQ(simtest::json_number_in(json, node, "samples"), 1e6);
  EXPECT_EQ(simtest::json_number_in(json, node, "missing"), 0.0);
  EXPECT_EQ(simtest::json_number_in(json, node, "lost"), 0.0);
  // The recorded acc_z holds steps and a drift the node's first-order filter lacks: its CUSUM
  // fires (the other channels' too, on the node's default models), and the report says so in
  // words next to the raw flags.
  const double flags = simtest::json_number_in(json, "residual_monitors",
                                               "flags");
  const std::string report = simtest::read_text(dir.file("run") + "/report.txt");
  EXPECT_GT(flags, 0.5);
  const std::size_t note = report.find("note: residual monitors: the innovation CUSUM alarm (");
  ASSERT_NE(note, std::string::npos)
      << report.substr(report.size() > 2000 ? report.size() - 2000 : 0);
  const std::string line = report.substr(note, report.find('\n', note) - note);
  EXPECT_NE(line.find("acc_z"), std::string::npos) << line;

  const double t1 = now_s();
  r = simtest::run({"adev", mat, "--channel", "acc_z", "--json", dir.file("adev.json")});
  std::printf("imu-sim adev on adis16405_imu1 acc_z: %.2f s\n", now_s() - t1);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto a = simtest::json_adev(simtest::read_text(dir.file("adev.json")));
  const auto b = simtest::json_adev(json);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 60U);
  for (std::size_t i = 0; i < a.size(); ++i) {
    // float32 telemetry (6e-8) and a different summation order (~1e-13): see test_cli.cpp.
    EXPECT_NEAR(b[i].tau_s, a[i].tau_s, 1e-12 * a[i].tau_s);
    EXPECT_NEAR(b[i].adev, a[i].adev, 3e-7 * a[i].adev) << "tau " << a[i].tau_s;
  }
}

}  // namespace

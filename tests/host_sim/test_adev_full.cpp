// `imu-sim adev --estimator full --taus ...`: the fully overlapping estimator
// against allantools' oadev on the 12 shared channels (../shared/golden, written by allantools,
// not by us) and against GNU Octave's own sum (tests/host_sim/octave), the tau grids, the CSV.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "../golden/golden_csv.hpp"
#include "sim_test_util.hpp"

namespace {

// The "af" of each object of a JSON "adev" list, in order (the writer puts one per line).
std::vector<std::uint64_t> json_af(const std::string& json) {
  std::vector<std::uint64_t> out;
  std::istringstream in(json);
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t p = line.find("\"af\": ");
    if (p != std::string::npos && line.find("\"tau_s\"") != std::string::npos) {
      out.push_back(std::strtoull(line.c_str() + p + 6, nullptr, 10));
    }
  }
  return out;
}

TEST(AdevFull, MatchesAllantoolsOadevOnTheSharedData) {
  const std::string dir = std::string(IMU_SHARED_DIR);
  if (!std::ifstream(dir + "/data/adis16405_imu1.mat").good()) {
    GTEST_SKIP() << "shared data not found in " << dir;
  }
  simtest::TempDir tmp;
  for (const char* imu : {"imu1", "imu2"}) {
    for (const char* ch : {"acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"}) {
      const std::string json = tmp.file("f.json");
      const auto r = simtest::run({"adev", dir + "/data/adis16405_" + imu + ".mat", "--channel",
                                   ch, "--estimator", "full", "--taus", "octave", "--json", json});
      ASSERT_EQ(r.status, 0) << r.err;
      const std::string j = simtest::read_text(json);
      const auto ours = simtest::json_adev(j);
      const auto afs = json_af(j);
      ASSERT_EQ(ours.size(), afs.size());
      std::map<std::uint64_t, imu::test::GoldenRow> gold;
      for (const auto& g : imu::test::read_golden(dir + "/golden/oadev_adis16405_" + imu + "_" +
                                               ch + ".csv")) {
        gold[static_cast<std::uint64_t>(std::llround(g.af))] = g;
      }
      std::size_t matched = 0;
      for (std::size_t i = 0; i < ours.size(); ++i) {
        const auto it = gold.find(afs[i]);
        if (it == gold.end()) {
          continue;
        }
        ++matched;
        // Same estimator, same data: 1e-8 covers the golden file's 11 digits and summation
        // order; the interval, the same EDF formula (white FM), printed to 7 digits: 1e-5.
        EXPECT_NEAR(ours[i].adev, it->second.adev, 1e-8 * it->second.adev)
            << imu << " " << ch << " af " << afs[i];
        EXPECT_NEAR(ours[i].ci_lo, it->second.lo, 1e-5 * it->second.lo) << afs[i];
        EXPECT_NEAR(ours[i].ci_hi, it->second.hi, 1e-5 * it->second.hi) << afs[i];
      }
      EXPECT_GE(matched, 18U) << imu << " " << ch;  // octave taus up to T/4 of 10^6 samples
    }
  }
}

// A whole IMU in one call: `--channel all` gives each of the six channels
// allantools' oadev, in one JSON keyed by channel and one CSV with a channel column; a comma
// list gives those channels, in the order named.
TEST(AdevFull, WholeImuInOneCallMatchesAllantools) {
  const std::string dir = std::string(IMU_SHARED_DIR);
  if (!std::ifstream(dir + "/data/adis16405_imu2.mat").good()) {
    GTEST_SKIP() << "shared data not found in " << dir;
  }
  simtest::TempDir tmp;
  const std::string json = tmp.file("all.json");
  const std::string csv = tmp.file("all.csv");
  const std::vector<std::string> chans = {"acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"};
  auto r = simtest::run({"adev", dir + "/data/adis16405_imu2.mat", "--channel", "all",
                         "--estimator", "full", "--json", json, "--csv", csv});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j = simtest::read_text(json);
  const std::string c = simtest::read_text(csv);
  std::size_t last = 0;
  for (const auto& ch : chans) {
    SCOPED_TRACE(ch);
    const std::size_t at = j.find("\"" + ch + "\": {");
    ASSERT_NE(at, std::string::npos) << j.substr(0, 300);
    EXPECT_GT(at, last);  // in the usual order
    last = at;
    const auto ours = simtest::json_adev(j.substr(at));
    std::map<double, imu::test::GoldenRow> gold;
    std::string golden = dir;
    golden += "/golden/oadev_adis16405_imu2_";
    golden += ch;
    golden += ".csv";
    for (const auto& g : imu::test::read_golden(golden)) {
      gold[g.af] = g;
    }
    std::size_t matched = 0;
    for (const auto& o : ours) {
      const auto it = gold.find(static_cast<double>(std::llround(o.tau_s * 100.0)));
      if (it != gold.end()) {
        ++matched;
        EXPECT_NEAR(o.adev, it->second.adev, 1e-8 * it->second.adev) << o.tau_s;
      }
    }
    EXPECT_GE(matched, 18U);
    EXPECT_NE(c.find("\n" + ch + ",0.01,1,"), std::string::npos);
  }
  EXPECT_EQ(c.rfind("channel,tau_s,af,adev,", 0), 0U) << c.substr(0, 80);
  r = simtest::run({"adev", dir + "/data/adis16405_imu2.mat", "--channel", "gyro_z,acc_x",
                    "--json", json});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string two = simtest::read_text(json);
  EXPECT_LT(two.find("\"gyro_z\": {"), two.find("\"acc_x\": {"));
  EXPECT_EQ(two.find("\"acc_y\""), std::string::npos);
  EXPECT_LT(r.out.find(" gyro_z: "), r.out.find(" acc_x: "));
}

TEST(AdevFull, OctaveFixtureGridsAndCsv) {
  simtest::TempDir tmp;
  const std::string mat = std::string(IMU_OCTAVE_DIR) + "/octave_v7.mat";
  const std::string csv = tmp.file("a.csv");
  auto r = simtest::run({"adev", mat, "--estimator", "full", "--taus", "all", "--csv", csv});
  ASSERT_EQ(r.status, 0) << r.err;
  // Every m from 1 to (2000 - 1) / 2 = 999, one CSV row each, header first.
  const std::string text = simtest::read_text(csv);
  EXPECT_EQ(text.rfind("tau_s,af,adev,ci_lo,ci_hi,edf,n_terms\n", 0), 0U);
  EXPECT_EQ(simtest::count_lines(text), 1U + 999U);
  // Octave's own fully overlapping ADEV at m = 1, 2, 4, 8 (octave_ref.txt): rows 1, 2, 4, 8.
  std::ifstream ref(std::string(IMU_OCTAVE_DIR) + "/octave_ref.txt");
  std::string line;
  std::map<std::uint64_t, double> oct;
  while (std::getline(ref, line)) {
    double tau = 0.0;
    double adev = 0.0;
    if (line[0] != '#' && std::sscanf(line.c_str(), "%lf %lf", &tau, &adev) == 2) {
      oct[static_cast<std::uint64_t>(std::llround(tau * 100.0))] = adev;
    }
  }
  ASSERT_EQ(oct.size(), 4U);
  std::istringstream rows(text);
  std::getline(rows, line);  // header
  while (std::getline(rows, line)) {
    double tau = 0.0;
    unsigned long long af = 0;
    double adev = 0.0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%llu,%lf", &tau, &af, &adev), 3) << line;
    const auto it = oct.find(af);
    if (it != oct.end()) {
      EXPECT_NEAR(adev, it->second, 1e-9 * it->second) << "m " << af;  // %.10g in the CSV
    }
  }
  // Grids as allantools: decade 1, 2, 4, 10, 20, 40, 100, 200, 400 (<= 999).
  const std::string json = tmp.file("d.json");
  r = simtest::run({"adev", mat, "--estimator", "full", "--taus", "decade", "--json", json});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(json_af(simtest::read_text(json)),
            (std::vector<std::uint64_t>{1, 2, 4, 10, 20, 40, 100, 200, 400}));
  // quarter octaves: round(2^(k/4)) without repeats: 1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 13, 16, ..
  r = simtest::run({"adev", mat, "--estimator", "full", "--taus", "quarter", "--json", json});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto q = json_af(simtest::read_text(json));
  ASSERT_GE(q.size(), 12U);
  EXPECT_EQ(std::vector<std::uint64_t>(q.begin(), q.begin() + 12),
            (std::vector<std::uint64_t>{1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 13, 16}));
  // The online estimator on the octave grid keeps its powers of two only.
  r = simtest::run({"adev", mat, "--estimator", "online", "--taus", "octave", "--json", json});
  ASSERT_EQ(r.status, 0) << r.err;
  for (const std::uint64_t af : json_af(simtest::read_text(json))) {
    EXPECT_EQ(af & (af - 1), 0U) << af;
  }
  // Usage errors: an unknown grid or estimator, `all` with the online estimator.
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"adev", mat, "--taus", "weekly"},
        std::vector<std::string>{"adev", mat, "--estimator", "fast"},
        std::vector<std::string>{"adev", mat, "--taus", "all", "--estimator", "online"}}) {
    r = simtest::run(bad);
    EXPECT_EQ(r.status, 2) << bad[2] << " " << bad[3];
  }
}

}  // namespace

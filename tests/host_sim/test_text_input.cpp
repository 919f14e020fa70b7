// Text input (issue 13 item 2): CSV, TSV and blank-separated columns with a header, a time
// column giving the rate, dropped rows as gaps, and the refusals. The ADEV of a text column is
// checked against the fully overlapping sum computed here, independently, over the samples.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "sim_test_util.hpp"

namespace {

// 3000 samples on a 1e-4 lattice (a deterministic pseudo-random sequence), at 50 Hz.
std::vector<double> samples() {
  std::vector<double> v(3000);
  std::uint32_t s = 12345U;
  for (double& x : v) {
    s = s * 1103515245U + 12345U;
    x = static_cast<double>(static_cast<int>((s >> 8U) % 2001U) - 1000) * 1e-4;
  }
  return v;
}

// Rows t, gyro (with the rows [skip_from, skip_to) dropped), separated by sep.
std::string table(char sep, std::size_t skip_from = 0, std::size_t skip_to = 0) {
  const std::vector<double> v = samples();
  std::string s = "# exported by a logger\n";
  s += std::string("t") + sep + "gyro\n";
  char buf[64];
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i >= skip_from && i < skip_to) {
      continue;
    }
    std::snprintf(buf, sizeof buf, "%.2f%c%.4f\n", static_cast<double>(i) * 0.02, sep, v[i]);
    s += buf;
  }
  return s;
}

// Fully overlapping ADEV at m over v, terms touching [gap_from, gap_to) left out.
double oadev(const std::vector<double>& v, std::size_t m, std::size_t gap_from = 0,
             std::size_t gap_to = 0) {
  double sum = 0.0;
  std::size_t terms = 0;
  for (std::size_t i = 0; i + 2 * m <= v.size(); ++i) {
    if (gap_to > gap_from && i < gap_to && i + 2 * m > gap_from) {
      continue;
    }
    double a = 0.0;
    double b = 0.0;
    for (std::size_t k = 0; k < m; ++k) {
      a += v[i + k];
      b += v[i + m + k];
    }
    const double d = (b - a) / static_cast<double>(m);
    sum += d * d;
    ++terms;
  }
  return std::sqrt(sum / (2.0 * static_cast<double>(terms)));
}

double json_adev_at(const std::string& json, double tau) {
  for (const auto& p : simtest::json_adev(json)) {
    if (std::fabs(p.tau_s - tau) < 1e-9) {
      return p.adev;
    }
  }
  return std::nan("");
}

TEST(TextInput, CsvTsvAndBlanksGiveTheColumnsAdevAtTheTimeColumnsRate) {
  simtest::TempDir dir;
  const std::vector<double> v = samples();
  for (const char sep : {',', '\t', ' '}) {
    const std::string f = dir.file("in.txt");
    std::ofstream(f) << table(sep);
    const std::string json = dir.file("a.json");
    const auto r = simtest::run({"adev", f, "--channel", "gyro", "--estimator", "full", "--lsb",
                                 "1e-4", "--json", json});
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string j = simtest::read_text(json);
    EXPECT_EQ(simtest::json_number_in(j, "fs_hz", "fs_hz"), 50.0) << "separator " << int(sep);
    for (const std::size_t m : {1U, 2U, 4U, 8U, 64U}) {
      const double want = oadev(v, m);
      // The JSON's 10 digits; the estimator sums integer counts exactly.
      EXPECT_NEAR(json_adev_at(j, 0.02 * static_cast<double>(m)), want, 1e-8 * want) << m;
    }
  }
}

TEST(TextInput, DroppedRowsAreGapsThatAreCountedAndSkipped) {
  simtest::TempDir dir;
  const std::vector<double> v = samples();
  const std::string f = dir.file("gap.csv");
  std::ofstream(f) << table(',', 1000, 1040);  // 40 rows (0.8 s) missing
  const std::string json = dir.file("a.json");
  auto r = simtest::run({"adev", f, "--channel", "gyro", "--estimator", "full", "--lsb", "1e-4",
                         "--json", json});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("40 non-finite samples"), std::string::npos) << r.out;
  const std::string j = simtest::read_text(json);
  for (const std::size_t m : {1U, 4U, 32U}) {
    const double want = oadev(v, m, 1000, 1040);
    EXPECT_NEAR(json_adev_at(j, 0.02 * static_cast<double>(m)), want, 1e-8 * want) << m;
  }
  // analyze says where the rate and the gaps came from.
  r = simtest::run({"analyze", f, "--channel", "gyro"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("rate 50.000000 Hz from the time column 't'; its steps left 40 samples "
                       "missing"), std::string::npos) << r.out;
}

TEST(TextInput, BadTextIsRefusedWithTheLine) {
  simtest::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"t,gyro\n0,1\n0.02,x\n", "line 3, column gyro: 'x' is not a number"},
      {"t,gyro\n0,1\n0.02,1,2\n", "line 3 has 3 fields, the header 2"},
      {"0,1\n0.02,2\n", "line 1: the first row must name the columns"},
      {"t,gyro\n0,1\n0,2\n", "does not increase at row 2"},
      {"gyro\n1\n2\n", "no --fs and no time column"}};
  for (const auto& [text, why] : cases) {
    const std::string f = dir.file("bad.csv");
    std::ofstream(f) << text;
    const auto r = simtest::run({"adev", f, "--channel", "gyro"});
    EXPECT_EQ(r.status, 1) << text;
    EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
    EXPECT_EQ(simtest::count_lines(r.err), 1U) << r.err;
  }
  std::ofstream(dir.file("ok.csv")) << "t,gyro\n0,1\n0.02,2\n";
  const auto r = simtest::run({"adev", dir.file("ok.csv"), "--channel", "acc"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("no column 'acc'; the columns: t, gyro"), std::string::npos) << r.err;
}

}  // namespace

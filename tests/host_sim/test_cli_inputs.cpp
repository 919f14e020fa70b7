// Tests of what imu-sim does with wrong or hostile input: non-finite samples are gaps,
// never numbers; an LSB or rate that cannot represent the data is refused; files that are not
// regular files, or declare more than the memory budget, are refused with one line; numeric
// options are range-checked before they become sizes or integers; outputs are written whole or
// not at all; every subcommand has --help and the documented exit codes (0 ok, 1 run-time error,
// 2 usage error). Each test states the defect it guards against.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "imu/mat/mat_reader.hpp"
#include "imu/mat/mat_writer.hpp"
#include "sim_test_util.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define IMU_TEST_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IMU_TEST_UNDER_ASAN 1
#endif
#endif
#ifndef IMU_TEST_UNDER_ASAN
#define IMU_TEST_UNDER_ASAN 0
#endif

namespace {

using simtest::count_lines;
using simtest::run;

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// n samples of gravity plus white noise (std sigma), on the 1e-6 grid (what synth writes).
std::vector<double> white(std::size_t n, double mean, double sigma, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  std::vector<double> v(n);
  for (double& x : v) {
    x = std::round((mean + g(rng)) * 1e6) * 1e-6;
  }
  return v;
}

struct Var {
  std::string name;
  std::vector<double> values;
  std::size_t cols = 1;
};

void write_mat(const std::string& path, const std::vector<Var>& vars) {
  imu::mat::MatWriter w(imu::mat::WriterOptions{true, imu::mat::Deflate::fixed_huffman});
  for (const Var& v : vars) {
    const auto st = v.cols == 1 ? w.add_column(v.name, v.values)
                                : w.add_matrix(v.name, v.values.size() / v.cols, v.cols, v.values);
    ASSERT_TRUE(st.ok()) << st.error().message;
  }
  const auto st = w.save(path);
  ASSERT_TRUE(st.ok()) << st.error().message;
}

/// The ADEV at the first tau of an imu-sim JSON file (NaN if none).
double first_adev(const std::string& json) {
  const auto a = simtest::json_adev(json);
  return a.empty() ? std::nan("") : a.front().adev;
}

/// The integer after "key": at top level of a JSON text (-1 if absent).
double json_top(const std::string& json, const std::string& key) {
  const std::size_t k = json.find("\"" + key + "\": ");
  return k == std::string::npos ? -1.0 : std::strtod(json.c_str() + k + key.size() + 4, nullptr);
}

void expect_one_line(const simtest::CliResult& r, int status, const std::string& what,
                     const std::string& label) {
  EXPECT_EQ(r.status, status) << label << ": " << r.err;
  EXPECT_EQ(count_lines(r.err), 1U) << label << ": " << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << label << ": '" << what << "' not in " << r.err;
}

// ---- Non-finite samples ------------------------------------------------------------------------

// Defect: a NaN became 0 counts and +Inf became INT32_MAX, moving ADEV(0.01 s) by 17 % (one
// NaN in 10^6) or 30x (one Inf). Now they are gaps: the ADEV moves only by the two samples that
// are missing, and the JSON says how many there were.
TEST(SimCliInputs, AdevTreatsNonFiniteSamplesAsGaps) {
  simtest::TempDir dir;
  std::vector<double> x = white(100000, 9.81, 0.01, 7);
  write_mat(dir.file("clean.mat"), {{"acc_z", x}, {"fs", {100.0}}});
  x[40000] = kNan;
  x[70000] = kInf;
  write_mat(dir.file("holes.mat"), {{"acc_z", x}, {"fs", {100.0}}});
  auto r = run({"adev", dir.file("clean.mat"), "--json", dir.file("clean.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  r = run({"adev", dir.file("holes.mat"), "--json", dir.file("holes.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("2 non-finite samples (NaN/Inf) treated as gaps"), std::string::npos)
      << r.out;
  const std::string clean = simtest::read_text(dir.file("clean.json"));
  const std::string holes = simtest::read_text(dir.file("holes.json"));
  EXPECT_EQ(json_top(holes, "gaps\": {\"samples"), 2.0);
  EXPECT_EQ(json_top(clean, "gaps\": {\"samples"), 0.0);
  // Two of 100,000 samples (4 of ~200,000 first differences) missing: the estimate moves by
  // about 1e-5 relative; 1e-3 leaves room and is 100x below what one wrong sample did.
  const double a = first_adev(clean);
  const double b = first_adev(holes);
  ASSERT_TRUE(std::isfinite(a) && a > 0.0) << clean;
  EXPECT_NEAR(b / a, 1.0, 1e-3) << "clean " << a << ", with NaN and Inf " << b;
}

// Defect: all-NaN data gave an ADEV of 0 and exit 0.
TEST(SimCliInputs, AllNonFiniteIsAnError) {
  simtest::TempDir dir;
  write_mat(dir.file("nan.mat"), {{"acc_z", std::vector<double>(1000, kNan)}, {"fs", {100.0}}});
  expect_one_line(run({"adev", dir.file("nan.mat")}), 1, "no finite sample", "adev");
  expect_one_line(run({"run", dir.file("nan.mat"), "--out", dir.file("o")}), 1,
                  "no finite sample", "run");
}

// Defect: `run` sent NaN as 0 counts and Inf as INT32_MAX to the node. Now a non-finite sample
// is not sent: the node counts it missing (inside the series) and its ADEV equals `adev`'s, which
// treats the same samples as gaps. Samples before the first / after the last finite one are not
// part of the series in either.
TEST(SimCliInputs, RunSendsNonFiniteSamplesAsGaps) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  std::vector<double> x = white(30000, 9.81, 0.01, 11);
  x[0] = kNan;
  x[10000] = kNan;
  x[20000] = -kInf;
  x[29999] = kNan;
  const std::string mat = dir.file("holes.mat");
  write_mat(mat, {{"acc_z", x}, {"fs", {100.0}}});
  const std::string out = dir.file("run");
  auto r = run({"run", mat, "--out", out, "--no-plots", "--quiet", "--sim-windows", "20",
                "--T-avg", "1", "--T-int", "2", "--N", "1e-3", "--B", "1e-4", "--Tp", "100"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = simtest::read_text(out + "/report.json");
  const char* node = "node_stats";
  EXPECT_EQ(simtest::json_number_in(json, node, "samples"), 29996.0) << json;
  EXPECT_EQ(simtest::json_number_in(json, node, "missing"), 2.0);
  EXPECT_EQ(simtest::json_number_in(json, node, "lost"), 0.0);
  EXPECT_EQ(simtest::json_number_in(json, "sender", "non_finite"), 4.0);
  r = run({"adev", mat, "--estimator", "online", "--json", dir.file("adev.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto a = simtest::json_adev(simtest::read_text(dir.file("adev.json")));
  const auto b = simtest::json_adev(json);
  ASSERT_GT(a.size(), 20U);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    // float32 telemetry (6e-8 relative) and another summation order: 3e-7 (as in test_cli).
    EXPECT_NEAR(b[i].adev, a[i].adev, 3e-7 * a[i].adev) << "tau " << a[i].tau_s;
  }
}

// ---- LSB and rate ------------------------------------------------------------------------------

// Defect: --lsb 1e-9 on acc_z (9.81 / 1e-9 > 2^31 counts) saturated every sample and gave an
// all-zero ADEV with exit 0. An option that does not fit the data is a usage error (2); an LSB
// stored in the file that does not fit is a run-time error (1).
TEST(SimCliInputs, LsbThatOverflowsInt32IsRefused) {
  simtest::TempDir dir;
  const std::vector<double> x = white(2000, 9.81, 0.01, 3);
  write_mat(dir.file("a.mat"), {{"acc_z", x}, {"fs", {100.0}}});
  write_mat(dir.file("b.mat"), {{"acc_z", x}, {"fs", {100.0}}, {"acc_lsb", {1e-9}}});
  expect_one_line(run({"adev", dir.file("a.mat"), "--lsb", "1e-9"}), 2, "int32", "adev --lsb");
  expect_one_line(run({"adev", dir.file("b.mat")}), 1, "int32", "adev acc_lsb");
  expect_one_line(run({"run", dir.file("a.mat"), "--lsb", "1e-9", "--out", dir.file("o")}), 2,
                  "int32", "run --lsb");
}

// Defect: --lsb 1 on a gyro (std 1e-3 rad/s) quantised every sample to the same count and
// reported a zero ADEV. Rule: refused when more than 99 % of the finite samples fall in one count
// while the quantised values' std is under half the values' std. Data already on a coarse grid
// (the sensor's own LSB, same std before and after) is accepted.
TEST(SimCliInputs, LsbThatCollapsesTheDataIsRefused) {
  simtest::TempDir dir;
  write_mat(dir.file("g.mat"), {{"gyro_z", white(5000, 0.0, 1e-3, 5)}, {"fs", {100.0}}});
  expect_one_line(run({"adev", dir.file("g.mat"), "--channel", "gyro_z", "--lsb", "1"}), 2,
                  "one count", "gyro --lsb 1");
  std::vector<double> coarse(5000, 0.0);
  coarse[100] = 0.5;  // one count in 5000 away from zero: the data, not the quantiser
  write_mat(dir.file("c.mat"), {{"gyro_z", coarse}, {"fs", {100.0}}, {"gyro_lsb", {0.5}}});
  const auto r = run({"adev", dir.file("c.mat"), "--channel", "gyro_z"});
  EXPECT_EQ(r.status, 0) << r.err;
}

// Defect: fs = 1e-300 gave taus of 1e298 s; fs = 1e300 threw std::length_error (a crash).
// The rate must be in [1e-3, 1e6] Hz: from --fs a usage error, from the file a run-time error.
// Defect: the same file could get a different LSB from adev and from analyze (two lookups:
// adev read acc_lsb/gyro_lsb only, analyze also NAME_lsb and lsb). One rule now
// (imu::cli::lsb_candidates): <group>_lsb, NAME_lsb, lsb; both commands report the same LSB,
// and a candidate that is not a positive number is an error in both, not skipped.
TEST(SimCliInputs, AdevAndAnalyzeTakeTheSameLsbFromTheFile) {
  simtest::TempDir dir;
  const std::vector<double> x = white(4000, 0.5, 0.01, 11);
  struct Case {
    const char* lsb_var;
    double lsb;
  };
  for (const Case& c : {Case{"acc_z_lsb", 2.5e-6}, Case{"lsb", 4e-6}, Case{"acc_lsb", 1e-6}}) {
    SCOPED_TRACE(c.lsb_var);
    const std::string mat = dir.file(std::string("l_") + c.lsb_var + ".mat");
    write_mat(mat, {{"acc_z", x}, {"fs", {100.0}}, {c.lsb_var, {c.lsb}}});
    const std::string ja = dir.file("a.json");
    const std::string jb = dir.file("b.json");
    auto r = simtest::run({"adev", mat, "--channel", "acc_z", "--json", ja});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("(from the file)"), std::string::npos) << r.out;
    r = simtest::run({"analyze", mat, "--channel", "acc_z", "--json", jb});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(json_top(simtest::read_text(ja), "lsb"), c.lsb);
    EXPECT_EQ(json_top(simtest::read_text(jb), "lsb"), c.lsb);
  }
  const std::string bad = dir.file("bad.mat");
  write_mat(bad, {{"acc_z", x}, {"fs", {100.0}}, {"acc_z_lsb", {-1.0}}});
  for (const char* cmd : {"adev", "analyze"}) {
    expect_one_line(simtest::run({cmd, bad, "--channel", "acc_z"}), 1,
                    "acc_z_lsb is not a positive number", cmd);
  }
}

// adev --channel all --plots DIR (plots per axis): per channel a CSV, a
// gnuplot script that renders from any directory, and its SVG/PNG when gnuplot is there.
TEST(SimCliInputs, AdevPlotsEveryAxis) {
  simtest::TempDir dir;
  const std::string mat = dir.file("two.mat");
  write_mat(mat, {{"acc_x", white(20000, 0.0, 0.01, 3)}, {"gyro_y", white(20000, 0.0, 0.001, 4)},
                  {"fs", {100.0}}});
  const std::string plots = dir.file("plots/sub");  // created
  const auto r = run({"adev", mat, "--channel", "all", "--plots", plots});
  ASSERT_EQ(r.status, 0) << r.err;
  const bool have = std::system("command -v gnuplot >/dev/null 2>&1") == 0;
  for (const char* ch : {"acc_x", "gyro_y"}) {
    const std::string base = plots + "/adev_" + ch;
    EXPECT_EQ(simtest::read_text(base + ".csv").rfind("tau_s,af,adev,", 0), 0U) << ch;
    EXPECT_NE(simtest::read_text(base + ".gp").find(ch), std::string::npos) << ch;
    if (have) {
      EXPECT_NE(simtest::read_text(base + ".svg").find("<svg"), std::string::npos) << ch;
      std::string cmd = "cd / && gnuplot -e \"set terminal svg; set output '";
      cmd += dir.file(std::string(ch) + ".svg");
      cmd += "'\" '";
      cmd += base;
      cmd += ".gp' 2>/dev/null";
      EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    }
  }
  EXPECT_NE(simtest::read_text(plots + "/adev_gyro_y.gp").find("[rad/s]"), std::string::npos);
}

TEST(SimCliInputs, RateOutOfRangeIsRefused) {
  simtest::TempDir dir;
  const std::vector<double> x = white(2000, 9.81, 0.01, 3);
  write_mat(dir.file("tiny.mat"), {{"acc_z", x}, {"fs", {1e-300}}});
  write_mat(dir.file("huge.mat"), {{"acc_z", x}, {"fs", {1e300}}});
  write_mat(dir.file("ok.mat"), {{"acc_z", x}, {"fs", {100.0}}});
  expect_one_line(run({"adev", dir.file("tiny.mat")}), 1, "fs", "file fs 1e-300");
  expect_one_line(run({"adev", dir.file("huge.mat")}), 1, "fs", "file fs 1e300");
  expect_one_line(run({"adev", dir.file("ok.mat"), "--fs", "1e300"}), 2, "--fs", "--fs 1e300");
  expect_one_line(run({"adev", dir.file("ok.mat"), "--fs", "1e-300"}), 2, "--fs", "--fs 1e-300");
  expect_one_line(run({"run", dir.file("huge.mat"), "--out", dir.file("o")}), 1, "fs", "run");
}

// Defect: a file whose rate is named `Fs` (MATLAB's usual capital) was "fs not found".
TEST(SimCliInputs, CapitalFsIsAccepted) {
  simtest::TempDir dir;
  write_mat(dir.file("a.mat"), {{"acc_z", white(2000, 9.81, 0.01, 3)}, {"Fs", {200.0}}});
  const auto r = run({"adev", dir.file("a.mat")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("at 200 Hz"), std::string::npos) << r.out;
}

// ---- What the file holds -----------------------------------------------------------------------

// Defect: an N x 6 matrix named like a channel was silently read as its column 0.
TEST(SimCliInputs, MatrixChannelIsRefusedWithHowToFix) {
  simtest::TempDir dir;
  std::vector<double> m(6 * 1000, 1.0);
  write_mat(dir.file("m.mat"), {{"acc_z", m, 6}, {"fs", {100.0}}});
  const auto r = run({"adev", dir.file("m.mat")});
  expect_one_line(r, 1, "1000x6 matrix", "N x 6");
  EXPECT_NE(r.err.find("--channel acc_z:3"), std::string::npos) << r.err;
}

// Defect: an unknown channel name did not say what the file holds.
TEST(SimCliInputs, UnknownChannelListsTheFilesChannels) {
  simtest::TempDir dir;
  write_mat(dir.file("a.mat"),
            {{"acc_x", white(100, 0, 1, 1)}, {"gyro_y", white(100, 0, 1, 2)}, {"fs", {100.0}}});
  // adev and run read any variable (it takes a slot of the node's six channels in run), so for
  // both 'accz' is a variable the file does not hold: the same usage error, the same list.
  for (const char* cmd : {"run", "adev"}) {
    const auto r = run({cmd, dir.file("a.mat"), "--channel", "accz"});
    expect_one_line(r, 2, "variable 'accz' not found", cmd);
    EXPECT_NE(r.err.find("variables: acc_x, gyro_y, fs"), std::string::npos) << r.err;
  }
}

// ---- Hostile files -----------------------------------------------------------------------------

// Defects: a directory was read with an allocation sized from ftell (crash); /dev/zero and
// /dev/urandom were read until bad_alloc (20 s); a FIFO blocked forever. All are refused from
// stat() before anything is opened.
TEST(SimCliInputs, NonRegularFilesAreRefusedBeforeOpening) {
  simtest::TempDir dir;
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {dir.path(), "is a directory"},
      {fifo, "is a FIFO"},
      {"/dev/zero", "is a device"},
      {"/dev/urandom", "is a device"},
  };
  for (const auto& c : cases) {
    const double t0 = now_s();
    expect_one_line(run({"adev", c.first}), 1, c.second, "adev " + c.first);
    expect_one_line(run({"run", c.first, "--out", dir.file("o")}), 1, c.second,
                    "run " + c.first);
    expect_one_line(run({"analyze", c.first, "--channel", "acc_z"}), 1, c.second,
                    "analyze " + c.first);
    EXPECT_LT(now_s() - t0, 5.0) << c.first;  // refused, not read
  }
}

/// A MAT-file whose one compressed variable `acc_z` declares `declared` bytes of inflated
/// matrix (a consistent double column of declared/8 - 7 elements) but carries only the start of
/// its zlib stream: the header and pad_bytes of zeros (valid stored blocks), no final block.
std::vector<std::uint8_t> huge_claim_file(std::uint32_t declared, std::size_t pad_bytes) {
  std::vector<std::uint8_t> f(128, ' ');
  f[124] = 0x00;
  f[125] = 0x01;
  f[126] = 'I';
  f[127] = 'M';
  auto u32 = [](std::vector<std::uint8_t>& b, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
      b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
  };
  // Inner miMATRIX: flags (16), dims (16), name "acc_z" (16), real part tag (8).
  const std::uint32_t n = (declared - 56U) / 8U;
  std::vector<std::uint8_t> inner;
  u32(inner, 14);
  u32(inner, declared);
  u32(inner, 6);  // miUINT32 flags
  u32(inner, 8);
  u32(inner, 6);  // class double
  u32(inner, 0);
  u32(inner, 5);  // miINT32 dims
  u32(inner, 8);
  u32(inner, n);
  u32(inner, 1);
  u32(inner, 1);  // miINT8 name
  u32(inner, 5);
  for (char c : std::string("acc_z\0\0\0", 8)) {
    inner.push_back(static_cast<std::uint8_t>(c));
  }
  u32(inner, 9);  // miDOUBLE real part
  u32(inner, n * 8U);
  // zlib header + one stored block (not final) holding the inner header; enough compressed
  // bytes after it for the 1032:1 bound of deflate to admit the claim.
  std::vector<std::uint8_t> z = {0x78, 0x01, 0x00};
  const auto len = static_cast<std::uint32_t>(inner.size());
  const std::uint32_t nlen = len ^ 0xFFFFU;
  z.push_back(static_cast<std::uint8_t>(len & 0xFFU));
  z.push_back(static_cast<std::uint8_t>(len >> 8U));
  z.push_back(static_cast<std::uint8_t>(nlen & 0xFFU));
  z.push_back(static_cast<std::uint8_t>(nlen >> 8U));
  z.insert(z.end(), inner.begin(), inner.end());
  // Then stored blocks of zeros (valid, not final) up to pad_bytes more compressed bytes.
  for (std::size_t done = 0; done < pad_bytes; done += 65540U) {
    const std::uint8_t block[5] = {0x00, 0xFF, 0xFF, 0x00, 0x00};  // LEN 65535, NLEN 0
    z.insert(z.end(), block, block + 5);
    z.resize(z.size() + 65535U, 0);
  }
  u32(f, 15);
  u32(f, static_cast<std::uint32_t>(z.size()));
  f.insert(f.end(), z.begin(), z.end());
  return f;
}

// Defect: a 3.9 MB compressed element that consistently declares 4 GB was inflated into a
// buffer growing towards 4 GB (bad_alloc). Now the declared size is checked against the reader's
// budget (256 MiB per variable) before inflating anything.
TEST(SimCliInputs, VariableDeclaringMoreThanTheBudgetIsRefused) {
  simtest::TempDir dir;
  const std::string path = dir.file("claim.mat");
  const std::vector<std::uint8_t> bytes = huge_claim_file(0xFFFFFF00U, 4U << 20U);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), f), bytes.size());
  std::fclose(f);
  const auto r = run({"adev", path, "--fs", "100"});
  expect_one_line(r, 1, "more than the reader's budget", "4 GB claim");
  EXPECT_NE(r.err.find("acc_z"), std::string::npos) << r.err;
}

// ---- Numeric options ---------------------------------------------------------------------------

// Defects: synth --N 1e300 wrote garbage, --duration 1e-9 an empty file, --duration 1e7 threw
// bad_alloc, --seed 1e30 was a float-to-integer overflow (UBSan); run --window 1e30 the same,
// --sim-windows 1e9 / --T-int 1e9 bad_alloc, --T-avg 1e9 hung. Each is now a usage error (2)
// found before anything is allocated or simulated.
TEST(SimCliInputs, NumericOptionsAreRangeChecked) {
  simtest::TempDir dir;
  const std::string mat = dir.file("a.mat");
  write_mat(mat, {{"acc_z", white(3000, 9.81, 0.01, 3)}, {"fs", {100.0}}});
  const std::string o = dir.file("o");
  const std::vector<std::vector<std::string>> cases = {
      {"synth", "--out", dir.file("s1.mat"), "--N", "1e300"},
      {"synth", "--out", dir.file("s2.mat"), "--duration", "1e-9"},
      {"synth", "--out", dir.file("s3.mat"), "--duration", "1e7"},
      {"synth", "--out", dir.file("s4.mat"), "--seed", "1e30"},
      {"synth", "--out", dir.file("s5.mat"), "--seed", "1.5"},
      {"synth", "--out", dir.file("s6.mat"), "--fs", "1e300"},
      {"run", mat, "--out", o, "--window", "1e30"},
      {"run", mat, "--out", o, "--seed", "1e30"},
      {"run", mat, "--out", o, "--sim-windows", "1e9"},
      {"run", mat, "--out", o, "--T-int", "1e9"},
      {"run", mat, "--out", o, "--T-avg", "1e9"},
      {"run", mat, "--out", o, "--timeout", "1e30"},
  };
  for (const auto& c : cases) {
    std::string label;
    for (const auto& s : c) {
      label += s + " ";
    }
    const double t0 = now_s();
    const auto r = run(c);
    EXPECT_EQ(r.status, 2) << label << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1U) << label << ": " << r.err;
    EXPECT_LT(now_s() - t0, 5.0) << label;
  }
  for (const char* f : {"s1.mat", "s2.mat", "s3.mat", "s4.mat", "s5.mat", "s6.mat"}) {
    EXPECT_TRUE(simtest::read_text(dir.file(f)).empty()) << f << " written";
  }
}

// ---- Outputs -----------------------------------------------------------------------------------

constexpr int kEscaped = 98;

/// Run imu-sim in a child process under a resource limit (RLIMIT_FSIZE: a full disk,
/// reproducibly; RLIMIT_AS: a machine out of memory); returns the exit status (-1 if killed by
/// a signal) and the child's stderr.
simtest::CliResult run_limited(const std::vector<std::string>& args, int resource, rlim_t limit,
                               const std::string& err_path) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    (void)dup2(fd, 2);
    (void)freopen("/dev/null", "w", stdout);
    (void)signal(SIGXFSZ, SIG_IGN);  // write() then fails with EFBIG instead of killing us
    std::vector<std::string> store = args;
    store.insert(store.begin(), "imu-sim");
    std::vector<char*> argv;
    argv.reserve(store.size() + 1);
    for (std::string& s : store) {
      argv.push_back(s.data());
    }
    argv.push_back(nullptr);
    const rlimit lim{limit, limit};
    (void)setrlimit(resource, &lim);
    // An exception escaping cli_main is status kEscaped (otherwise gtest's own handler in this
    // forked copy would catch it and run on).
    int st = kEscaped;
    try {
      st = imu::sim::cli_main(static_cast<int>(store.size()), argv.data());
    } catch (...) {
      std::fputs("exception escaped cli_main\n", stderr);
    }
    std::fflush(stderr);
    _exit(st);
  }
  int status = 0;
  (void)waitpid(pid, &status, 0);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, "", simtest::read_text(err_path)};
}

simtest::CliResult run_with_file_limit(const std::vector<std::string>& args,
                                       rlim_t max_file_bytes, const std::string& err_path) {
  return run_limited(args, RLIMIT_FSIZE, max_file_bytes, err_path);
}

/// This process's virtual size (VmSize), bytes.
rlim_t vm_size_bytes() {
  const std::string status = simtest::read_text("/proc/self/status");
  const std::size_t k = status.find("VmSize:");
  return k == std::string::npos ? 0 : static_cast<rlim_t>(std::strtoull(status.c_str() + k + 7, nullptr, 10)) * 1024U;
}

/// Names in a folder other than the given ones (leftover temporary files).
std::vector<std::string> others(const std::string& dir, const std::vector<std::string>& keep) {
  std::vector<std::string> out;
  const std::string cmd = "ls -A '" + dir + "'";
  std::FILE* p = popen(cmd.c_str(), "r");
  char line[512];
  while (p != nullptr && std::fgets(line, sizeof line, p) != nullptr) {
    std::string s = line;
    s.pop_back();
    bool kept = false;
    for (const auto& k : keep) {
      kept = kept || s == k;
    }
    if (!kept) {
      out.push_back(s);
    }
  }
  if (p != nullptr) {
    pclose(p);
  }
  return out;
}

// Defect: a failed write (full disk) left a partial file: synth's MAT-file, adev/analyze --json,
// run's CSV files. Every output is written to a temporary name and renamed when complete.
TEST(SimCliInputs, FailedWritesLeaveNoPartialFile) {
  SKIP_IF_EMULATED();  // the RLIMIT_FSIZE child under qemu-user hangs here (measured)
  simtest::TempDir dir;
  const std::string mat = dir.file("in.mat");
  write_mat(mat, {{"acc_z", white(20000, 9.81, 0.01, 3)}, {"fs", {100.0}}});
  const std::string outs = dir.file("outs");
  ASSERT_EQ(mkdir(outs.c_str(), 0700), 0);
  const std::string err = dir.file("err.txt");
  auto r = run_with_file_limit({"synth", "--out", outs + "/s.mat", "--duration", "1000"}, 4096,
                               err);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(count_lines(r.err), 1U) << r.err;
  r = run_with_file_limit({"adev", mat, "--json", outs + "/a.json"}, 1000, err);
  EXPECT_EQ(r.status, 1) << r.err;
  r = run_with_file_limit({"analyze", mat, "--channel", "acc_z", "--json", outs + "/z.json"},
                          1000, err);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(others(outs, {}), std::vector<std::string>{});
  // The same commands without the limit write their files (the limit was the cause).
  EXPECT_EQ(run({"synth", "--out", outs + "/s.mat", "--duration", "1000"}).status, 0);
  EXPECT_EQ(run({"adev", mat, "--json", outs + "/a.json"}).status, 0);
  EXPECT_EQ(others(outs, {}), (std::vector<std::string>{"a.json", "s.mat"}));
}

// Defect: an allocation failure escaped as std::bad_alloc (abort, core dump). It is caught at the
// top of every command: one line, exit 1. Here a 2^25-sample channel (256 MiB of doubles) meets
// an address space of 64 MiB more than the process already uses: synth writes it in chunks,
// so it succeeds; analyze, which reads it in chunks but analyses 2^20 block means (about 30 MB
// whatever the record's length), given 16 MiB more, fails in one line.
TEST(SimCliInputs, AllocationFailureIsOneLineAndExit1) {
  SKIP_IF_EMULATED();  // an RLIMIT_AS limit starves qemu-user itself, not the program
#if IMU_TEST_UNDER_ASAN
  GTEST_SKIP() << "ASan's allocator aborts on out-of-memory instead of throwing, and its shadow "
                  "memory makes an address-space limit meaningless";
#endif
  simtest::TempDir dir;
  const rlim_t vm = vm_size_bytes();
  ASSERT_GT(vm, 0U);
  const auto w = run_limited({"synth", "--out", dir.file("big.mat"), "--duration", "335544"},
                             RLIMIT_AS, vm + (64U << 20U), dir.file("err.txt"));
  EXPECT_EQ(w.status, 0) << w.err;
  const auto r = run_limited({"analyze", dir.file("big.mat"), "--channel", "acc_z"}, RLIMIT_AS,
                             vm + (16U << 20U), dir.file("err2.txt"));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(r.err, "imu-sim analyze: out of memory\n");
}

// A record longer than 2^20 samples is analysed on block means (read from the
// stream, the file never whole), so analyze's memory stops growing with the record. 12.5 h at
// 25 Hz, 1.125e6 samples of the synth model (white N + GM + rate random walk K = 4e-4, which
// meets the white noise at 200 s), become 562500 means of 2 at 12.5 Hz: the report says so, and
// the model found is still the synthesised one (N within 2 %, the walk's power within a factor
// 1.5), and the one the full-rate analysis finds on the same realisation's first 1.048e6
// samples (N within 1 %, the walk's power within 10 %: the means add no bias). The walk here
// dominates the GM at every tau the GM would show, so the record does not tell it from the
// first-order model's GM slower than it resolves: the walk is named (K), or that GM stands in
// for it with its drive Sb = K^2 (the walk's power at tau << Tb) and a note says so.
// The walk's power in an analysis JSON: K where the walk is named; where the first-order
// model's GM stands in for it (no K; "not named: rate_random_walk" in the notes), sqrt of that
// GM's drive Sb, the walk's K^2 at tau << Tb. NaN if neither.
double walk_power(const std::string& j) {
  const double k = simtest::json_number_in(j, "model_after", "k");
  if (k > 0.0) {
    EXPECT_NE(j.find("\"rate_random_walk\""), std::string::npos);
    return k;
  }
  if (j.find("not named: rate_random_walk") == std::string::npos) {
    return std::nan("");
  }
  return std::sqrt(simtest::json_number_in(j, "model_after", "sb"));
}

TEST(SimCliInputs, LongRecordIsAnalysedOnBlockMeans) {
  SKIP_IF_EMULATED();  // 1.125e6 samples under qemu-user: minutes
  simtest::TempDir dir;
  const std::string mat = dir.file("long.mat");
  auto r = run({"synth", "--out", mat, "--fs", "25", "--duration", "45000", "--N", "3.3e-3",
                "--K", "4e-4",
                "--B", "9e-4", "--Tp", "300", "--seed", "11"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = dir.file("long.json");
  r = run({"analyze", mat, "--channel", "acc_z", "--json", json});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("long record: its 1125000 samples analysed as 562500 means of 2 samples "
                       "(rate 12.5 Hz)"),
            std::string::npos)
      << r.out;
  const std::string j = simtest::read_text(json);
  EXPECT_EQ(simtest::json_number_in(j, "channel", "n_samples"), 562500.0);
  EXPECT_EQ(simtest::json_number_in(j, "channel", "fs_hz"), 12.5);
  const double n = simtest::json_number_in(j, "model_after", "n");
  const double k = walk_power(j);
  std::printf("block means of 2: N = %.4e (synth 3.3e-3), K = %.4e (synth 4e-4)\n", n, k);
  EXPECT_NEAR(n, 3.3e-3, 0.02 * 3.3e-3);
  EXPECT_GT(k, 4e-4 / 1.5);
  EXPECT_LT(k, 4e-4 * 1.5);

  const std::string prefix = dir.file("prefix.mat");
  r = run({"synth", "--out", prefix, "--fs", "25", "--duration", "41920", "--N", "3.3e-3",
           "--K", "4e-4",
           "--B", "9e-4", "--Tp", "300", "--seed", "11"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json_full = dir.file("prefix.json");
  r = run({"analyze", prefix, "--channel", "acc_z", "--json", json_full});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.find("long record"), std::string::npos) << "1.048e6 samples: full rate";
  const std::string jf = simtest::read_text(json_full);
  const double n_full = simtest::json_number_in(jf, "model_after", "n");
  const double k_full = walk_power(jf);
  std::printf("full rate, first 1.048e6 samples: N = %.4e, K = %.4e\n", n_full, k_full);
  EXPECT_NEAR(n / n_full, 1.0, 0.01);
  EXPECT_NEAR(k / k_full, 1.0, 0.10);
}

// The same for a text file (analyze streams text too, never the table): a text
// record past 2^20 samples is held as block means, found while it streams (the length is not
// known in advance: B doubles, merging pairs of blocks). 1.05e6 samples give 525000 means of 2,
// and the analysis of the text is the MAT-file's, number for number (means of 2 are the same
// sums whichever way they are formed).
TEST(SimCliInputs, LongTextIsAnalysedOnTheMatFilesBlockMeans) {
  SKIP_IF_EMULATED();  // 1.05e6 text rows under qemu-user: minutes
  simtest::TempDir dir;
  const std::string mat = dir.file("long.mat");
  auto r = run({"synth", "--out", mat, "--duration", "10500", "--N", "2.1e-3", "--K", "9e-5",
                "--B", "6e-4", "--Tp", "200", "--seed", "23"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto col = imu::mat::read_column(mat, "acc_z");
  ASSERT_TRUE(col.ok()) << col.error().message;
  const std::string csv = dir.file("long.csv");
  {
    std::FILE* f = std::fopen(csv.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("acc_z\n", f);
    for (const double v : col.value()) {
      std::fprintf(f, "%.17g\n", v);  // round-trips the double exactly
    }
    ASSERT_EQ(std::fclose(f), 0);
  }
  const std::string jm = dir.file("mat.json");
  const std::string jt = dir.file("text.json");
  r = run({"analyze", mat, "--channel", "acc_z", "--lsb", "1e-6", "--json", jm});
  ASSERT_EQ(r.status, 0) << r.err;
  r = run({"analyze", csv, "--channel", "acc_z", "--fs", "100", "--lsb", "1e-6", "--json", jt});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("long record: its 1050000 samples analysed as 525000 means of 2 samples "
                       "(rate 50 Hz)"),
            std::string::npos)
      << r.out;
  // Every line of the two reports but the timings.
  const auto lines = [](const std::string& text) {
    std::vector<std::string> out;
    std::size_t a = 0;
    while (a < text.size()) {
      const std::size_t b = std::min(text.find('\n', a), text.size());
      const std::string line = text.substr(a, b - a);
      // The timings and the input's name differ; nothing else may.
      if (line.find("timing_s") == std::string::npos &&
          line.find("\"source\": ") == std::string::npos) {
        out.push_back(line);
      }
      a = b + 1;
    }
    return out;
  };
  const std::vector<std::string> from_mat = lines(simtest::read_text(jm));
  const std::vector<std::string> from_text = lines(simtest::read_text(jt));
  EXPECT_GT(from_mat.size(), 20U);
  ASSERT_EQ(from_text.size(), from_mat.size());
  std::size_t differ = 0;
  std::string first;
  for (std::size_t i = 0; i < from_mat.size(); ++i) {
    if (from_text[i] != from_mat[i] && differ++ == 0) {
      first = "text: " + from_text[i] + "\nMAT:  " + from_mat[i];
    }
  }
  EXPECT_EQ(differ, 0U) << first;
}

// ---- One command line --------------------------------------------------------------------------

// Defect: only analyze had --help; `adev --help` was "unknown option", `adev -h` opened a file
// named -h. Every subcommand prints its usage on stdout and exits 0.
TEST(SimCliInputs, EverySubcommandHasHelp) {
  for (const char* cmd : {"synth", "model", "adev", "run", "analyze"}) {
    for (const char* h : {"--help", "-h"}) {
      const auto r = run({cmd, h});
      EXPECT_EQ(r.status, 0) << cmd << " " << h << ": " << r.err;
      EXPECT_NE(r.out.find(std::string("usage: imu-sim ") + cmd), std::string::npos)
          << cmd << " " << h << ": " << r.out;
      EXPECT_TRUE(r.err.empty()) << cmd << ": " << r.err;
    }
  }
}

// Defect: run took --mat FILE where the others take FILE; analyze exited 2 for run-time errors.
TEST(SimCliInputs, FilePositionalAndExitCodesAreTheSameEverywhere) {
  simtest::TempDir dir;
  const std::string missing = dir.file("missing.mat");
  for (const char* cmd : {"adev", "run", "analyze"}) {
    expect_one_line(run({cmd, missing, "--channel", "acc_z"}), 1, "missing.mat", cmd);
    expect_one_line(run({cmd, missing, "--bogus"}), 2, "unknown option '--bogus'", cmd);
    expect_one_line(run({cmd, missing, "extra.mat", "--channel", "acc_z"}), 2,
                    "unexpected argument 'extra.mat'", cmd);
  }
  // --mat stays as an alias of the positional FILE.
  expect_one_line(run({"run", "--mat", missing, "--out", dir.file("o")}), 1, "missing.mat",
                  "run --mat");
}

}  // namespace

// imu::analyze::cli_main on a synthetic MAT file: text report, JSON keys, plots, bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "imu/analyze/analyze.hpp"
#include "imu/analyze/synth.hpp"
#include "imu/mat/mat_writer.hpp"

namespace {

// ctest runs each test in its own process, several at once: the pid keeps one test's input
// from being rewritten by another's SetUp while the streamed reader is still inside it.
std::string tmp_path(const std::string& name) {
  return std::string(::testing::TempDir()) + "imu_analyze_" + std::to_string(::getpid()) + "_" +
         name;
}

int call(std::vector<std::string> args) {
  std::vector<char*> argv;
  argv.reserve(args.size());
  for (auto& a : args) {
    argv.push_back(a.data());
  }
  return imu::analyze::cli_main(static_cast<int>(argv.size()), argv.data());
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A MAT file with one channel and fs = 100 Hz; false if it could not be written.
bool write_channel(const std::string& path, const std::string& name, const std::vector<double>& y) {
  imu::mat::MatWriter w;
  if (!w.add_column(name, y).ok() || !w.add_scalar("fs", 100.0).ok()) {
    return false;
  }
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(w.bytes().data()),
          static_cast<std::streamsize>(w.bytes().size()));
  return f.good();
}

// The number after `key` at or after position `from` of a JSON text (NaN if absent).
double number_after(const std::string& j, std::size_t from, const std::string& key) {
  const std::size_t p = from == std::string::npos ? from : j.find(key, from);
  return p == std::string::npos ? std::nan("") : std::strtod(j.c_str() + p + key.size(), nullptr);
}

class AnalyzeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    imu::analyze::SynthSpec s;
    s.samples = 200000;  // 2000 s: short enough for a unit test
    s.seed = 7;
    s.n_outliers = 10;
    s.outlier_size = 0.4;
    const std::vector<double> y = imu::analyze::synthesize(s);
    ASSERT_EQ(y.size(), s.samples);
    // Stored as exact multiples of an LSB, like the ADIS16405 files.
    constexpr double kLsb = 1e-4;
    std::vector<double> q(y.size());
    for (std::size_t i = 0; i < y.size(); ++i) {
      q[i] = std::round(y[i] / kLsb) * kLsb;
    }
    imu::mat::MatWriter w;
    ASSERT_TRUE(w.add_column("acc_x", q).ok());
    ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
    ASSERT_TRUE(w.add_scalar("acc_lsb", kLsb).ok());
    mat_ = tmp_path("in.mat");
    std::ofstream f(mat_, std::ios::binary);
    f.write(reinterpret_cast<const char*>(w.bytes().data()),
            static_cast<std::streamsize>(w.bytes().size()));
    ASSERT_TRUE(f.good());
  }
  void TearDown() override { std::remove(mat_.c_str()); }
  std::string mat_;
};

TEST_F(AnalyzeCli, WritesJsonWithTheFixedKeys) {
  const std::string json = tmp_path("out.json");
  ASSERT_EQ(call({"analyze", mat_, "--channel", "acc_x", "--json", json}), 0);
  const std::string j = slurp(json);
  for (const char* key : {"\"channel\"", "\"fs_hz\"", "\"n_samples\"", "\"adev\"", "\"model_before\"",
                          "\"error_before\"", "\"effects\"", "\"model_after\"", "\"error_after\"",
                          "\"tau_s\"", "\"edf\"", "\"ci_lo\"", "\"ci_hi\"", "\"adev_rms_rel\"",
                          "\"adev_max_rel\"", "\"tau_min_s\"", "\"tau_max_s\"", "\"nis_mean\"",
                          "\"covariance_ratio\"", "\"whiteness_flagged_fraction\""}) {
    EXPECT_NE(j.find(key), std::string::npos) << key;
  }
  EXPECT_NE(j.find("\"n_samples\": 200000"), std::string::npos);
  // The 10 spikes of 0.4 (12 sigma of the white noise) are the only effect.
  EXPECT_NE(j.find("{\"type\": \"outliers\", \"count\": 10, \"times_s\": ["), std::string::npos) << j;
  EXPECT_NE(j.find("LSB from the file"), std::string::npos);
}

TEST_F(AnalyzeCli, WritesCsvPlot) {
  // --plots DIR is created (a missing folder was an error); the CSV has the model's terms.
  const std::string dir = tmp_path("plots/sub");
  ASSERT_EQ(call({"analyze", mat_, "--channel", "acc_x", "--plots", dir}), 0);
  const std::string csv = slurp(dir + "/analyze_acc_x_adev.csv");
  EXPECT_EQ(csv.rfind("tau_s,adev_raw,", 0), 0U);
  EXPECT_NE(csv.find(",after_white,"), std::string::npos);
  EXPECT_NE(csv.find(",before_gauss_markov_1,"), std::string::npos);
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "gnuplot not installed: the SVG/PNG part is not checked";
  }
  // SVG and PNG of both figures; the script's paths are absolute (it runs from anywhere), the
  // titles noenhanced (acc_x is no subscript), the axis has the unit.
  for (const char* f : {"analyze_acc_x_before.svg", "analyze_acc_x_after.svg",
                        "analyze_acc_x_before.png", "analyze_acc_x_after.png"}) {
    EXPECT_TRUE(std::ifstream(dir + "/" + f).good()) << f;
  }
  const std::string gp = slurp(dir + "/analyze_acc_x_adev.gp");
  EXPECT_NE(gp.find("plot '/"), std::string::npos) << gp;
  EXPECT_NE(gp.find("noenhanced"), std::string::npos);
  EXPECT_NE(gp.find("Allan deviation [m/s^2]"), std::string::npos);
  EXPECT_NE(gp.find("fitted range"), std::string::npos);
}

TEST_F(AnalyzeCli, BadInputGivesNonZeroExit) {
  EXPECT_NE(call({"analyze"}), 0);
  EXPECT_NE(call({"analyze", mat_}), 0);  // no --channel
  EXPECT_NE(call({"analyze", mat_, "--channel", "nope"}), 0);
  EXPECT_NE(call({"analyze", tmp_path("missing.mat"), "--channel", "acc_x"}), 0);
  EXPECT_NE(call({"analyze", mat_, "--channel", "acc_x", "--fs", "-3"}), 0);
  EXPECT_NE(call({"analyze", mat_, "--channel", "acc_x", "--bogus"}), 0);
}

// A logger dropout (NaN samples) is a gap, counted and reported, not a refusal.
TEST_F(AnalyzeCli, NanDropoutsAreGapsNotARefusal) {
  imu::analyze::SynthSpec sp;
  sp.samples = 200000;
  sp.seed = 11;
  sp.nan_gaps = 3;
  sp.nan_gap_len = 500;
  const std::vector<double> y = imu::analyze::synthesize(sp);
  const std::string mat = tmp_path("nan.mat");
  ASSERT_TRUE(write_channel(mat, "acc_x", y));
  const std::string json = tmp_path("nan.json");
  ASSERT_EQ(call({"analyze", mat, "--channel", "acc_x", "--json", json}), 0);
  const std::string j = slurp(json);
  EXPECT_NE(j.find("\"gaps\": {\"samples\": 1500, \"runs\": 3}"), std::string::npos) << j;
  EXPECT_NE(j.find("\"unexplained\": ["), std::string::npos);
  EXPECT_NE(j.find("\"bias_instability\": {\"b\": "), std::string::npos);
  EXPECT_NE(j.find("\"n_states\": "), std::string::npos);
}

// Integrated delta-velocity differentiated back (multiples of one step up to
// floating-point residue) gives that step, not 1e-9; an LSB that would overflow int32 counts
// falls back and says so.
TEST(AnalyzeInputs, LsbToleratesFloatingPointResidueAndNeverOverflows) {
  constexpr double kStep = 0.0012345;  // m/s^2 per count after scaling
  std::vector<double> v(20000);
  double vel = 0.0;  // integrated delta-velocity, in steps
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double prev = vel * kStep;
    vel += static_cast<double>(static_cast<int>(i * 7919 % 13) - 6);
    v[i] = (vel * kStep - prev) * 100.0 / 100.0;  // a difference of two scaled integrals
  }
  std::string note;
  const double lsb = imu::analyze::derive_lsb(v, note);
  EXPECT_NEAR(lsb, kStep, 1e-9 * kStep) << note;
  EXPECT_NE(note.find("lattice"), std::string::npos) << note;

  // 9.81 +- tiny noise on a 1e-12 grid: the span / 2^30 rule keeps the counts inside int32.
  std::vector<double> g(5000);
  for (std::size_t i = 0; i < g.size(); ++i) {
    g[i] = 9.81 + 1e-3 * static_cast<double>(static_cast<int>(i * 104729 % 2001) - 1000) / 1000.0;
  }
  const double lsb2 = imu::analyze::derive_lsb(g, note);
  double lo = g[0];
  double hi = g[0];
  for (const double x : g) {
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  EXPECT_LT((hi - lo) / lsb2, 2147483647.0) << note;
  EXPECT_GT(lsb2, 0.0);
}

// A delta-velocity record on a lattice of step q offset by gravity, its values printed to six
// significant digits (as a text log holds them): each value is then off the exact lattice by up
// to 5e-6, a few 1e-3 of the coarsest step. The step is still found (before: the smallest
// difference, off by twice that residue, was taken for the step, the check of every value
// against it within 1e-3 of a step failed, and the LSB fell back to robust std / 4096).
TEST(AnalyzeInputs, LatticeWithAnOffsetAndPrintResidueGivesTheStep) {
  for (const double q : {0.0024525, 1e-3, 3.3e-4}) {
    for (const double offset : {9.80665, -9.81}) {
      std::vector<double> v(20000);
      for (std::size_t i = 0; i < v.size(); ++i) {
        const double k = static_cast<double>(static_cast<int>(i * 7919 % 41) - 20);
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.6g", k * q + offset);
        v[i] = std::strtod(buf, nullptr);
      }
      std::string note;
      const double lsb = imu::analyze::derive_lsb(v, note);
      EXPECT_NEAR(lsb, q, 0.01 * q) << "offset " << offset << ": " << note;
      EXPECT_NE(note.find("lattice"), std::string::npos) << note;
    }
  }
}

// White noise + a GM (Tb 10 s), quantised to q and offset by gravity in floating point (the
// residue of k q + offset): a report, the step as the LSB, and no effect the record does not hold.
TEST(AnalyzeInputs, QuantisedRecordWithAnOffsetGetsAReportAndItsStep) {
  for (const double q : {0.0024525, 1e-3, 3.3e-4}) {
    constexpr double kFs = 100.0;
    std::mt19937_64 rng(8801);
    std::normal_distribution<double> g(0.0, 1.0);
    const double a = std::exp(-1.0 / (kFs * 10.0));
    const double gm_sd = q * std::sqrt(1.0 - a * a);
    double b = 0.0;
    std::vector<double> y(360000);  // 1 h
    for (double& v : y) {
      b = a * b + gm_sd * g(rng);
      v = std::round((b + 2.0 * q * g(rng)) / q) * q + 9.80665;
    }
    imu::analyze::Report r;
    std::string err;
    ASSERT_TRUE(imu::analyze::analyze(y, "acc_z", imu::analyze::Options{}, r, err))
        << "q " << q << ": " << err;
    std::string why;
    EXPECT_TRUE(imu::analyze::report_consistent(r, why)) << "q " << q << ": " << why;
    EXPECT_NEAR(r.lsb, q, 0.01 * q) << r.lsb_note;
    EXPECT_TRUE(r.effects.empty()) << "q " << q << "\n" << imu::analyze::to_text(r);
  }
}

// A record whose noise never reaches half a step: every value the same level. No ADEV point
// is nonzero, so the white + GM fit and the white-only fit fail; the analysis still reports
// (before: "the first-order fit over [Ts, 100 s] failed", no report, exit 1), with the model's
// fallback said in a note and nothing named.
TEST(AnalyzeInputs, FailedFitsFallBackToASimplerModelWithANote) {
  std::vector<double> y(360000, 3.0 * 0.0024525 + -9.81);
  const std::string csv = tmp_path("one_level.csv");
  {
    std::ofstream f(csv);
    f << "t,acc_z\n";
    char buf[64];
    for (std::size_t i = 0; i < y.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%.2f,%.17g\n", static_cast<double>(i) / 100.0, y[i]);
      f << buf;
    }
  }
  imu::analyze::Report r;
  std::string err;
  ASSERT_TRUE(imu::analyze::analyze(y, "acc_z", imu::analyze::Options{}, r, err)) << err;
  EXPECT_TRUE(r.effects.empty()) << imu::analyze::to_text(r);
  std::string why;
  EXPECT_TRUE(imu::analyze::report_consistent(r, why)) << why;
  EXPECT_GT(r.model_before.n, 0.0);
  EXPECT_EQ(r.model_before.n_gm, 0U);
  bool noted = false;
  for (const std::string& n : r.notes) {
    noted = noted || n.find("white-only fits over [Ts, 100 s] failed") != std::string::npos;
  }
  EXPECT_TRUE(noted) << imu::analyze::to_text(r);
  const std::string text = imu::analyze::to_text(r);
  EXPECT_NE(text.find("white noise only"), std::string::npos);
  // No NaN reaches the report's text (a note printed a cost drop of -nan).
  EXPECT_EQ(text.find("-nan"), std::string::npos) << text;
  EXPECT_EQ(text.find(" nan "), std::string::npos) << text;
  // Through the command line: exit 0 and a report.
  const std::string json = tmp_path("one_level.json");
  EXPECT_EQ(call({"analyze", csv, "--channel", "acc_z", "--json", json}), 0);
  EXPECT_NE(slurp(json).find("\"channel\": \"acc_z\""), std::string::npos);
}

}  // namespace

namespace {

// A number after `key: ` in a YAML text (NaN if absent).
double yaml_number(const std::string& y, const std::string& key) {
  const std::size_t p = y.find("\n" + key + ": ");
  return p == std::string::npos ? std::nan("") : std::strtod(y.c_str() + p + key.size() + 3, nullptr);
}

// An IMU of pure white noise + rate random walk per axis (Kalibr's own model), N and K known and
// different per axis: acc_x/y and gyro_x/y, 10^4 s at 100 Hz.
std::string write_kalibr_imu() {
  imu::mat::MatWriter w;
  const char* names[] = {"acc_x", "acc_y", "gyro_x", "gyro_y"};
  const double n[] = {2e-3, 3e-3, 2e-4, 1.5e-4};
  const double k[] = {2e-4, 1e-4, 2e-5, 3e-5};
  for (int c = 0; c < 4; ++c) {
    imu::analyze::SynthSpec s;
    s.samples = 1000000;
    s.seed = 31 + static_cast<std::uint64_t>(c);
    s.n = n[c];
    s.b = 1e-12;  // no GM to speak of
    s.tp_s = 1.0;
    s.k = k[c];
    EXPECT_TRUE(w.add_column(names[c], imu::analyze::synthesize(s)).ok());
  }
  EXPECT_TRUE(w.add_scalar("fs", 100.0).ok());
  std::string path = tmp_path("kalibr.mat");
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(w.bytes().data()),
          static_cast<std::streamsize>(w.bytes().size()));
  return path;
}

}  // namespace

// --channel all analyses every IMU channel the file holds, one report and one
// JSON keyed by channel; a comma list takes those; --yaml writes Kalibr's keys with the largest
// axis of each sensor, recovered within 15 % of the N and K the record was made with.
TEST(AnalyzeWholeImu, ChannelAllJsonAndKalibrYaml) {
  const std::string mat = write_kalibr_imu();
  const std::string json = tmp_path("all.json");
  const std::string yaml = tmp_path("imu.yaml");
  // --plots in the same run (one analysis: this test runs under qemu-user in the cross build).
  const std::string plots = tmp_path("sensor_plots");
  ASSERT_EQ(call({"analyze", mat, "--channel", "all", "--json", json, "--yaml", yaml, "--plots",
                  plots}),
            0);
  const std::string j = slurp(json);
  EXPECT_NE(j.find("\"channels\": {"), std::string::npos);
  for (const char* c : {"\"acc_x\": {", "\"acc_y\": {", "\"gyro_x\": {", "\"gyro_y\": {"}) {
    EXPECT_NE(j.find(c), std::string::npos) << c;
  }
  const std::string y = slurp(yaml);
  // Largest axis: acc N 3e-3 (acc_y), acc K 2e-4 (acc_x), gyro N 2e-4 (gyro_x), gyro K 3e-5.
  // 15 %: K over a 2000 s record has ~10 % scatter (a few independent wanders over T).
  EXPECT_NEAR(yaml_number(y, "accelerometer_noise_density"), 3e-3, 0.15 * 3e-3) << y;
  EXPECT_NEAR(yaml_number(y, "accelerometer_random_walk"), 2e-4, 0.15 * 2e-4) << y;
  EXPECT_NEAR(yaml_number(y, "gyroscope_noise_density"), 2e-4, 0.15 * 2e-4) << y;
  EXPECT_NEAR(yaml_number(y, "gyroscope_random_walk"), 3e-5, 0.15 * 3e-5) << y;
  EXPECT_DOUBLE_EQ(yaml_number(y, "update_rate"), 100.0);
  // Numbers carry a mantissa dot: YAML 1.1 (PyYAML, Kalibr's loader) reads "1e-05" as a string.
  EXPECT_NE(y.find("\nupdate_rate: 1.0000e+02"), std::string::npos) << y;
  EXPECT_NE(y.find("\nrostopic: /imu0\n"), std::string::npos);
  // A comma list: those channels only, under "channels" as for one channel or all.
  ASSERT_EQ(call({"analyze", mat, "--channel", "gyro_y,acc_x", "--json", json}), 0);
  const std::string j2 = slurp(json);
  EXPECT_NE(j2.find("\"gyro_y\": {"), std::string::npos);
  EXPECT_EQ(j2.find("\"gyro_x\": {"), std::string::npos);
  // --yaml without both sensors is refused as a usage error before any analysis (exit 2),
  // nothing written.
  std::remove(yaml.c_str());
  const std::string json_one = json + ".one";
  EXPECT_EQ(call({"analyze", mat, "--channel", "acc_x", "--json", json_one, "--yaml", yaml}), 2);
  EXPECT_FALSE(std::ifstream(yaml).good());
  EXPECT_FALSE(std::ifstream(json_one).good()) << "--json was written before --yaml was refused";
  // An unknown name in the list is a usage error: exit 2.
  EXPECT_EQ(call({"analyze", mat, "--channel", "acc_x,acc_q"}), 2);
  // --plots: one figure per sensor with the IEEE 952 lines read off the ADEV's slopes; on this
  // white + walk IMU the read-off N and K (in the key's titles) are the record's within 15 %
  // and 35 % (a graphical read-off at one point of the curve).
  const std::string acc_gp = slurp(plots + "/analyze_accelerometer.gp");
  const std::string gyro_gp = slurp(plots + "/analyze_gyroscope.gp");
  const auto title_value = [](const std::string& gp, const std::string& what) {
    const std::size_t p = gp.find("'" + what + " = ");
    return p == std::string::npos ? std::nan("")
                                  : std::strtod(gp.c_str() + p + what.size() + 4, nullptr);
  };
  EXPECT_NEAR(title_value(acc_gp, "acc_x N"), 2e-3, 0.15 * 2e-3) << acc_gp;
  EXPECT_NEAR(title_value(acc_gp, "acc_y N"), 3e-3, 0.15 * 3e-3);
  EXPECT_NEAR(title_value(gyro_gp, "gyro_x N"), 2e-4, 0.15 * 2e-4) << gyro_gp;
  EXPECT_NEAR(title_value(acc_gp, "acc_x K"), 2e-4, 0.35 * 2e-4);
  EXPECT_NEAR(title_value(gyro_gp, "gyro_y K"), 3e-5, 0.35 * 3e-5);
  EXPECT_NE(slurp(plots + "/analyze_accelerometer.csv").find("axis,tau_s,adev,ci_lo,ci_hi,channel"),
            std::string::npos);
}

// A record past 2^20 samples is analysed on block means for the whole record,
// and its first 2^20 samples at full rate for what the means cannot resolve. The first-order model
// plus a 30 Hz sinusoid (A = 0.02, 0.6 x the white std per sample: an 8 % ADEV bump at Ts), 1.125e6
// samples at 100 Hz: the means of 2 (50 Hz) cannot hold 30 Hz, it aliases to 20 Hz at 0.59 A.
// Before the full-rate head the report named a 20 Hz sinusoid: a wrong name. Now the sinusoid
// is named at 30 Hz with its amplitude, no 20 Hz one is named, the model handed to the node
// carries it, and the report gives the head's errors before and after.
TEST(AnalyzeLongRecord, FastSinusoidIsFoundAtFullRateNotAtItsAlias) {
#ifdef IMU_EMULATED_TARGET
  GTEST_SKIP() << "1.125e6 samples analysed twice: minutes under qemu-user";
#endif
  imu::analyze::SynthSpec sp;
  sp.samples = 1125000;
  sp.seed = 31;
  sp.sin_a = 0.02;
  sp.sin_f_hz = 30.0;
  const std::vector<double> y = imu::analyze::synthesize(sp);
  ASSERT_EQ(y.size(), sp.samples);
  const std::string mat = tmp_path("long_sine.mat");
  ASSERT_TRUE(write_channel(mat, "acc_z", y));
  const std::string json = tmp_path("long_sine.json");
  ASSERT_EQ(call({"analyze", mat, "--channel", "acc_z", "--lsb", "1e-6", "--json", json}), 0);
  const std::string j = slurp(json);
  std::remove(mat.c_str());
  const std::size_t head_at = j.find("\"full_rate_head\"");
  ASSERT_NE(head_at, std::string::npos) << j.substr(0, 2000);
  EXPECT_NE(j.find("\"merged\": true", head_at), std::string::npos);
  // The record's effects (before "model_after"): the 30 Hz sinusoid, nothing near its alias.
  const std::string effects = j.substr(j.find("\"effects\""), j.find("\"model_after\"") -
                                                                  j.find("\"effects\""));
  const std::size_t sine = effects.find("{\"type\": \"sinusoid\"");
  ASSERT_NE(sine, std::string::npos) << effects;
  const double f = number_after(effects, sine, "\"freq_hz\": ");
  const double a = number_after(effects, sine, "\"amplitude\": ");
  std::printf("sinusoid named at %.6f Hz, A = %.5f (synth 30 Hz, 0.02)\n", f, a);
  EXPECT_NEAR(f, 30.0, 0.01);       // the DTFT peak of 3.1 h: resolution ~1e-4 Hz
  EXPECT_NEAR(a, 0.02, 0.02 * 0.02);  // LS amplitude; white std 0.033 over 1e6 samples: 5e-5
  EXPECT_EQ(effects.find("sinusoid", sine + 20), std::string::npos) << effects;
  EXPECT_EQ(effects.find("oscillation"), std::string::npos) << effects;
  // The model handed to the node: the sinusoid, the white noise of the full rate (the means put
  // part of it in a GM at their shortest tau, 0.02 s), no GM peaking below 4 x 0.02 s.
  const std::size_t after = j.find("\"model_after\"");
  EXPECT_NEAR(number_after(j, after, "\"sin_f0_hz\": "), 30.0, 0.01);
  EXPECT_NEAR(number_after(j, after, "\"n\": "), 3.3e-3, 0.01 * 3.3e-3);
  const std::size_t gm_end = j.find(']', after);
  for (std::size_t p = j.find("\"tb_s\": ", after); p < gm_end; p = j.find("\"tb_s\": ", p + 1)) {
    EXPECT_GE(1.89 * number_after(j, p, "\"tb_s\": "), 0.08);
  }
  // The head's own errors: its after-model and the record's are both better than the example's.
  const double before_rms = number_after(j, j.find("\"error_before\"", head_at),
                                         "\"adev_rms_rel\": ");
  const double record_rms = number_after(j, j.find("\"error_record_model\"", head_at),
                                         "\"adev_rms_rel\": ");
  std::printf("head: first-order model RMS %.4f, record's model RMS %.4f\n", before_rms, record_rms);
  EXPECT_LT(record_rms, before_rms);
}

namespace {

// One axis of a static IMU in its own unit: white noise n (unit/sqrt(Hz)) plus a small GM and
// a constant reading (gravity on z), 100 Hz.
std::vector<double> static_axis(std::uint64_t seed, double n, double offset, std::size_t samples) {
  imu::analyze::SynthSpec s;
  s.samples = samples;
  s.seed = seed;
  s.n = n;
  s.b = 0.2 * n;
  s.tp_s = 20.0;
  s.offset = offset;
  return imu::analyze::synthesize(s);
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t c = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) {
    ++c;
  }
  return c;
}

}  // namespace

// A logger's N x 6 matrix in g and deg/s with no sensor names: --acc/--gyro declare the columns,
// the accelerometer's unit is read from its triad's mean norm (about 1: g) and said, the
// gyroscope's is declared; the imu.yaml is in SI: N x 9.80665 and N x pi/180. Before, such a
// file got "--yaml needs at least one acc* and one gyro* channel" after the whole analysis, and
// a g/deg-s file got an imu.yaml labelled m/s^2 and rad/s, 9.8x and 57x off.
TEST(AnalyzeSensors, MatrixInGAndDegPerSecondGivesAnSiImuYamlWithItsUnitsSaid) {
  constexpr std::size_t kSamples = 60000;
  const double n_g = 1.5e-3;     // g/sqrt(Hz)
  const double n_dps = 0.02;     // deg/s/sqrt(Hz)
  const double gravity_g[3] = {0.03, -0.05, 0.998};
  std::vector<double> data;  // column-major N x 6
  for (std::size_t c = 0; c < 6; ++c) {
    const bool acc = c < 3;
    const std::vector<double> y = static_axis(8101 + c, acc ? n_g : n_dps,
                                              acc ? gravity_g[c] : 0.2 * static_cast<double>(c),
                                              kSamples);
    data.insert(data.end(), y.begin(), y.end());
  }
  imu::mat::MatWriter w;
  ASSERT_TRUE(w.add_matrix("data", kSamples, 6, data).ok());
  ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
  const std::string mat = tmp_path("g_dps.mat");
  {
    std::ofstream f(mat, std::ios::binary);
    f.write(reinterpret_cast<const char*>(w.bytes().data()),
            static_cast<std::streamsize>(w.bytes().size()));
  }
  const std::string json = tmp_path("g_dps.json");
  const std::string yaml = tmp_path("g_dps.yaml");
  ASSERT_EQ(call({"analyze", mat, "--acc", "data:1,data:2,data:3", "--gyro",
                  "data:4,data:5,data:6", "--gyro-unit", "deg/s", "--json", json, "--yaml", yaml}),
            0);
  const std::string y = slurp(yaml);
  constexpr double kPi = 3.14159265358979323846;
  EXPECT_NEAR(yaml_number(y, "accelerometer_noise_density"), n_g * 9.80665, 0.1 * n_g * 9.80665)
      << y;
  EXPECT_NEAR(yaml_number(y, "gyroscope_noise_density"), n_dps * kPi / 180.0,
              0.1 * n_dps * kPi / 180.0)
      << y;
  const std::string j = slurp(json);
  EXPECT_EQ(count_of(j, "\"sensor\": \"accelerometer\""), 3U) << j;
  EXPECT_EQ(count_of(j, "\"sensor\": \"gyroscope\""), 3U);
  EXPECT_EQ(count_of(j, "accelerometer (--acc/--gyro), in g: the mean norm of its three axes is "
                        "0.99"), 3U);
  EXPECT_EQ(count_of(j, "gyroscope (--acc/--gyro), in deg/s (--gyro-unit); analysed in rad/s"),
            3U);
  // The GM drive's PSD is in unit^2/s, not unit.
  EXPECT_NE(j.find("\"sb\": \"(m/s^2)^2/s\""), std::string::npos);
  EXPECT_NE(j.find("\"sb\": \"(rad/s)^2/s\""), std::string::npos);
  // Nothing declared but the channels: the norm says g, and the gyroscope beside it is taken
  // as deg/s, said in its note; the imu.yaml is the same as with --gyro-unit deg/s.
  ASSERT_EQ(call({"analyze", mat, "--acc", "data:1,data:2,data:3", "--gyro",
                  "data:4,data:5,data:6", "--json", json, "--yaml", yaml}),
            0);
  EXPECT_NEAR(yaml_number(slurp(yaml), "gyroscope_noise_density"), n_dps * kPi / 180.0,
              0.1 * n_dps * kPi / 180.0);
  EXPECT_EQ(count_of(slurp(json), "taken as deg/s, the unit that goes with an accelerometer in "
                                  "g (--gyro-unit rad/s|deg/s|deg/h declares it); analysed in "
                                  "rad/s"),
            3U);
  // The same columns in m/s^2 (scaled by the test): the norm says m/s^2, nothing is scaled.
  for (std::size_t i = 0; i < 3 * kSamples; ++i) {
    data[i] *= 9.80665;
  }
  imu::mat::MatWriter w2;
  ASSERT_TRUE(w2.add_matrix("data", kSamples, 6, data).ok());
  ASSERT_TRUE(w2.add_scalar("fs", 100.0).ok());
  {
    std::ofstream f(mat, std::ios::binary);
    f.write(reinterpret_cast<const char*>(w2.bytes().data()),
            static_cast<std::streamsize>(w2.bytes().size()));
  }
  ASSERT_EQ(call({"analyze", mat, "--acc", "data:1,data:2,data:3", "--gyro",
                  "data:4,data:5,data:6", "--json", json, "--yaml", yaml}),
            0);
  const std::string y2 = slurp(yaml);
  EXPECT_NEAR(yaml_number(y2, "accelerometer_noise_density"), n_g * 9.80665,
              0.1 * n_g * 9.80665);
  // Undeclared gyroscope beside an accelerometer in m/s^2: taken as rad/s, and said.
  EXPECT_NEAR(yaml_number(y2, "gyroscope_noise_density"), n_dps, 0.1 * n_dps);
  const std::string j2 = slurp(json);
  EXPECT_EQ(count_of(j2, "in m/s^2: the mean norm of its three axes is 9.80"), 3U) << j2;
  EXPECT_EQ(count_of(j2, "taken as rad/s (--gyro-unit rad/s|deg/s|deg/h declares it)"), 3U);
  // Declared against the norm: kept, with a warning.
  ASSERT_EQ(call({"analyze", mat, "--acc", "data:1,data:2,data:3", "--acc-unit", "g", "--json",
                  json}),
            0);
  EXPECT_EQ(count_of(slurp(json), "gravity in m/s^2: check --acc-unit"), 3U);
  // Mistakes on the command line are usage errors (exit 2).
  EXPECT_EQ(call({"analyze", mat, "--acc", "data:1", "--acc-unit", "furlong/s^2"}), 2);
  EXPECT_EQ(call({"analyze", mat, "--acc", "data:1", "--channel", "data:2"}), 2);
  EXPECT_EQ(call({"analyze", mat, "--acc", "data:1", "--gyro", "data:1"}), 2);
}

// EuRoC's column names (a_RS_S_x, w_RS_S_x) and ax..gz name their sensors: --channel all
// --yaml works without --acc/--gyro, and each channel's note says the sensor came from its name.
TEST(AnalyzeSensors, FieldColumnNamesNameTheirSensors) {
  for (const bool euroc : {true, false}) {
    const char* acc_names[3] = {"a_RS_S_x", "a_RS_S_y", "a_RS_S_z"};
    const char* gyro_names[3] = {"w_RS_S_x", "w_RS_S_y", "w_RS_S_z"};
    const char* short_acc[3] = {"ax", "ay", "az"};
    const char* short_gyro[3] = {"gx", "gy", "gz"};
    constexpr std::size_t kSamples = 20000;
    std::vector<std::vector<double>> cols;
    for (std::size_t c = 0; c < 6; ++c) {
      cols.push_back(static_axis(8201 + c, c < 3 ? 2e-3 : 2e-4, c == 2 ? 9.81 : 0.0, kSamples));
    }
    const std::string csv = tmp_path(euroc ? "euroc.csv" : "short.csv");
    {
      std::ofstream f(csv);
      f << (euroc ? "#timestamp [ns]" : "t");
      for (std::size_t c = 0; c < 6; ++c) {
        const char* name = c < 3 ? (euroc ? acc_names[c] : short_acc[c])
                                 : (euroc ? gyro_names[c - 3] : short_gyro[c - 3]);
        f << "," << name << (euroc ? (c < 3 ? " [m s^-2]" : " [rad s^-1]") : "");
      }
      f << "\n";
      char buf[64];
      for (std::size_t i = 0; i < kSamples; ++i) {
        if (euroc) {
          f << 1403636579758555392LL + static_cast<long long>(i) * 10000000LL;
        } else {
          std::snprintf(buf, sizeof buf, "%.2f", static_cast<double>(i) / 100.0);
          f << buf;
        }
        for (std::size_t c = 0; c < 6; ++c) {
          std::snprintf(buf, sizeof buf, ",%.9g", cols[c][i]);
          f << buf;
        }
        f << "\n";
      }
    }
    const std::string json = tmp_path("names.json");
    const std::string yaml = tmp_path("names.yaml");
    ASSERT_EQ(call({"analyze", csv, "--channel", "all", "--json", json, "--yaml", yaml}), 0)
        << csv;
    const std::string j = slurp(json);
    EXPECT_EQ(count_of(j, "accelerometer (from the channel's name; --acc/--gyro declare it), "
                          "in m/s^2"), 3U) << j;
    EXPECT_EQ(count_of(j, "gyroscope (from the channel's name"), 3U);
    EXPECT_NEAR(yaml_number(slurp(yaml), "gyroscope_noise_density"), 2e-4, 2e-5);
  }
}

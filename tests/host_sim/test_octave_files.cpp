// Files written by GNU Octave 7.3 (tests/host_sim/octave/make_fixtures.m; the .mat files and
// octave_ref.txt are committed, CI does not install Octave), read through imu-sim as a user
// would: save -v6 and -v7, `Fs` for the rate, a row vector, int16 counts with an LSB, a matrix
// column, struct fields (nested too). The ADEV is checked against Octave's own fully overlapping ADEV at
// m = 1, 2, 4, 8 (octave_ref.txt), where the online estimator is the fully overlapping one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "sim_test_util.hpp"

namespace {

const std::string kDir = IMU_OCTAVE_DIR;

std::vector<std::pair<double, double>> octave_reference() {
  std::vector<std::pair<double, double>> out;
  std::ifstream f(kDir + "/octave_ref.txt");
  std::string line;
  while (std::getline(f, line)) {
    double tau = 0.0;
    double adev = 0.0;
    if (!line.empty() && line[0] != '#' &&
        std::sscanf(line.c_str(), "%lf %lf", &tau, &adev) == 2) {
      out.emplace_back(tau, adev);
    }
  }
  return out;
}

// The ADEV at tau (from a JSON "adev" list); NaN if absent.
double adev_at(const std::vector<simtest::JsonAdev>& a, double tau) {
  for (const auto& p : a) {
    if (std::fabs(p.tau_s - tau) < 1e-9) {
      return p.adev;
    }
  }
  return std::nan("");
}

void expect_octave_adev(const std::string& json, const std::string& what, double rel = 5e-9) {
  const auto ref = octave_reference();
  ASSERT_EQ(ref.size(), 4U);
  const auto a = simtest::json_adev(json);
  for (const auto& [tau, adev] : ref) {
    // Level 0 of the online estimator is the fully overlapping sum (fw README, ~1e-11 on the
    // shared data); the JSONs print 9 (analyze) or 10 (adev) significant digits.
    EXPECT_NEAR(adev_at(a, tau), adev, rel * adev) << what << " tau " << tau;
  }
}

// The acc_z samples stored as a row vector, as int16 counts x acc_lsb and as column 2 of a
// matrix, through `cmd`: each gives Octave's ADEV. The row vector (acc_*) finds acc_lsb: its
// report says `lsb_text`.
void expect_same_samples_everywhere(const char* cmd, const std::string& lsb_text,
                                    simtest::TempDir& dir) {
  const std::vector<std::pair<std::string, std::string>> same = {
      {"octave_row.mat", "acc_z_row"}, {"octave_int16.mat", "acc_z_counts"},
      {"octave_matrix.mat", "data:2"}};
  for (const auto& [file, channel] : same) {
    const std::string json = dir.file("x.json");
    std::string path = kDir;
    path += "/" + file;
    const auto r = simtest::run({cmd, path, "--channel", channel, "--json", json});
    ASSERT_EQ(r.status, 0) << cmd << " " << file << ": " << r.err;
    expect_octave_adev(simtest::read_text(json), file);
    if (channel == "acc_z_row") {
      EXPECT_NE(r.out.find(lsb_text), std::string::npos) << r.out;
    }
  }
}

TEST(OctaveFiles, AdevOfV6V7AndCapitalFsMatchesOctavesOverlappingAdev) {
  simtest::TempDir dir;
  for (const char* f : {"octave_v6.mat", "octave_v7.mat", "octave_capital_fs.mat"}) {
    const std::string json = dir.file("a.json");
    const auto r = simtest::run({"adev", kDir + "/" + f, "--channel", "acc_z", "--json", json});
    ASSERT_EQ(r.status, 0) << f << ": " << r.err;
    const std::string j = simtest::read_text(json);
    EXPECT_EQ(simtest::json_number_in(j, "fs_hz", "fs_hz"), 100.0) << f;
    expect_octave_adev(j, f);
  }
}

TEST(OctaveFiles, AdevReadsAnyVariableRowVectorsInt16CountsAndMatrixColumns) {
  simtest::TempDir dir;
  expect_same_samples_everywhere("adev", "LSB 0.01 m/s^2 (from the file)", dir);
  // A matrix without its column: refused with how to name one (exit 1); a variable the file
  // does not hold: a usage error listing what it holds.
  auto r = simtest::run({"adev", kDir + "/octave_matrix.mat", "--channel", "data"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--channel data:3"), std::string::npos) << r.err;
  r = simtest::run({"adev", kDir + "/octave_matrix.mat", "--channel", "data:x"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("the column after ':' must be a number"), std::string::npos) << r.err;
  r = simtest::run({"adev", kDir + "/octave_v7.mat", "--channel", "acc_q"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("variables: acc_z, fs, acc_lsb"), std::string::npos) << r.err;
}

TEST(OctaveFiles, AnalyzeReadsRowVectorsInt16CountsAndMatrixColumns) {
  simtest::TempDir dir;
  const std::string ref_json = dir.file("v7.json");
  auto r = simtest::run({"analyze", kDir + "/octave_v7.mat", "--channel", "acc_z", "--json",
                         ref_json});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string ref = simtest::read_text(ref_json);
  expect_octave_adev(ref, "analyze v7");
  // The same samples as a row vector, as int16 counts x acc_lsb, and as column 2 of a matrix.
  expect_same_samples_everywhere("analyze", "LSB from the file: 0.01", dir);
  r = simtest::run({"analyze", kDir + "/octave_int16.mat", "--channel", "acc_z_counts"});
  EXPECT_NE(r.out.find("integer counts: analysed as counts x LSB"), std::string::npos) << r.out;
  // A matrix named without its column is refused, with the columns to choose from.
  r = simtest::run({"analyze", kDir + "/octave_matrix.mat", "--channel", "data"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("2000 x 3 matrix: name a column, data:1 .. data:3"), std::string::npos)
      << r.err;
}

// run reads the same variables as adev ("adev and run accept only the names
// acc_x..gyro_z"): a row vector, int16 counts x acc_lsb, a matrix column and a struct field
// each take the acc_z slot, are sent to the node, and its ADEV is Octave's.
TEST(OctaveFiles, RunReadsAnyVariableStructFieldsAndInt16Counts) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"octave_row.mat", "acc_z_row"}, {"octave_int16.mat", "acc_z_counts"},
      {"octave_matrix.mat", "data:2"}, {"octave_struct.mat", "imu.acc_z"}};
  for (const auto& [file, channel] : cases) {
    SCOPED_TRACE(file);
    const std::string out = dir.file("run_" + file);
    const std::string path = kDir + "/" + file;  // NOLINT(performance-inefficient-string-concatenation)
    const auto r = simtest::run({"run", path, "--channel", channel, "--no-plots", "--quiet",
                                 "--sim-windows", "10", "--out", out});
    ASSERT_EQ(r.status, 0) << r.err;
    // The node's telemetry carries the ADEV as float32 (2^-24 relative).
    expect_octave_adev(simtest::read_text(out + "/report.json"), file, 2e-7);
  }
}

// Struct fields: `imu.acc_z` (save -v7: compressed, a field before it) and `rec.imu.acc_z`
// (save -v6: uncompressed, nested) give Octave's ADEV through adev and analyze, with the rate
// from the struct's `fs` and the LSB from the top-level acc_lsb. A field the struct lacks: the
// struct's fields listed (adev: a usage error, as for any name the file does not hold).
TEST(OctaveFiles, StructFieldsAreReadByDottedName) {
  simtest::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"octave_struct.mat", "imu.acc_z"}, {"octave_struct_v6.mat", "rec.imu.acc_z"}};
  for (const auto& [file, channel] : cases) {
    for (const char* cmd : {"adev", "analyze"}) {
      SCOPED_TRACE(std::string(cmd) + " " + channel);  // NOLINT(performance-inefficient-string-concatenation)
      const std::string json = dir.file("s.json");
      const std::string path = kDir + "/" + file;  // NOLINT(performance-inefficient-string-concatenation)
      const auto r = simtest::run({cmd, path, "--channel", channel, "--json", json});
      ASSERT_EQ(r.status, 0) << r.err;
      const std::string j = simtest::read_text(json);
      EXPECT_EQ(simtest::json_number_in(j, "fs_hz", "fs_hz"), 100.0);
      expect_octave_adev(j, file);
    }
  }
  auto r = simtest::run({"adev", kDir + "/octave_struct_v6.mat", "--channel", "rec.imu.acc_q"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("variable 'rec.imu': field 'acc_q' not found; fields: acc_x, acc_z, fs"),
            std::string::npos) << r.err;
  // A field the struct lacks is the same usage error (exit 2) in every command and at any depth.
  r = simtest::run({"analyze", kDir + "/octave_struct.mat", "--channel", "imu.acc_q"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(simtest::count_lines(r.err), 1U) << r.err;
  EXPECT_NE(r.err.find("field 'acc_q' not found; fields: acc_x, acc_z, fs"), std::string::npos)
      << r.err;
}

}  // namespace

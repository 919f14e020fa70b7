// Text input: CSV, TSV and blank-separated columns with a header, a time
// column giving the rate, dropped rows as gaps, and the refusals. The ADEV of a text column is
// checked against the fully overlapping sum computed here, independently, over the samples.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "imu/cli/text_input.hpp"
#include "imu/mat/mat_writer.hpp"
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

// The logs of the field, read without options: a ROS-style CSV with nanosecond epoch stamps, a
// EuRoC file (names in a '#' line, units in brackets), a logger's milliseconds, a PX4-style log
// in microseconds (indexed names, a column of text that is not read). Each gives its rate and
// the same ADEV as the samples (the exact estimator's sum computed here); a unit read from the
// steps is said in a note, a stated one is not.
TEST(TextInput, FieldLogsGiveTheirRateAndAdevWithoutOptions) {
  simtest::TempDir dir;
  const std::vector<double> v = samples();
  struct Log {
    const char* file;
    std::string header;
    const char* column;
    long long step;    // in the log's time unit
    long long origin;  // its first time
    const char* extra;  // fields between the time and the value
    double fs_hz;
    const char* note;  // "" : none expected
  };
  const std::vector<Log> logs = {
      {"ros.csv", "timestamp,gyro_z\n", "gyro_z", 5000000, 1700000000000000001, "", 200.0, "read in ns"},
      {"euroc.csv",
       "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1]\n",
       "w_RS_S_z", 5000000, 1403636579758555392, "0.1,0.2,", 200.0, ""},
      {"logger.csv", "time,acc_z\n", "acc_z", 5, 1000, "", 200.0, "read in ms"},
      {"px4.csv", "timestamp,frame,gyro_rad[0]\n", "gyro_rad[0]", 4000, 123456789,
       "imu_link,", 250.0, "read in us"},
      {"echo.csv", "%time,field.header.frame_id,field.angular_velocity.x\n",
       "field.angular_velocity.x", 10000000, 1600000000123456789, "base_imu,", 100.0, "read in ns"}};
  for (const Log& log : logs) {
    std::string text = log.header;
    char buf[128];
    for (std::size_t i = 0; i < v.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%lld,%s%.4f\n",
                    log.origin + static_cast<long long>(i) * log.step, log.extra, v[i]);
      text += buf;
    }
    const std::string f = dir.file(log.file);
    std::ofstream(f) << text;
    const std::string json = dir.file("a.json");
    const auto r = simtest::run({"adev", f, "--channel", log.column, "--lsb", "1e-4", "--json",
                                 json});
    ASSERT_EQ(r.status, 0) << log.file << ": " << r.err;
    const std::string j = simtest::read_text(json);
    const double fs = simtest::json_number_in(j, "fs_hz", "fs_hz");
    EXPECT_NEAR(fs, log.fs_hz, 1e-9 * log.fs_hz) << log.file;
    for (const std::size_t m : {1U, 2U, 8U, 64U}) {
      const double want = oadev(v, m);
      EXPECT_NEAR(json_adev_at(j, static_cast<double>(m) / log.fs_hz), want, 1e-8 * want)
          << log.file << " m " << m;
    }
    if (*log.note != '\0') {
      EXPECT_NE(r.out.find(log.note), std::string::npos) << log.file << ": " << r.out;
    } else {
      EXPECT_EQ(r.out.find("read in"), std::string::npos) << log.file << ": " << r.out;
    }
  }
  // analyze says the same of the same file.
  auto r = simtest::run({"analyze", dir.file("ros.csv"), "--channel", "gyro_z"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("rate 200 Hz from the time column 'timestamp'; the time column "
                       "'timestamp' read in ns"),
            std::string::npos)
      << r.out;
  // A unit given overrides the steps: seconds on nanosecond stamps is a rate out of range.
  r = simtest::run({"adev", dir.file("ros.csv"), "--channel", "gyro_z", "--time-unit", "s"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("outside [1e-3, 1e6] Hz"), std::string::npos) << r.err;
  r = simtest::run({"adev", dir.file("logger.csv"), "--channel", "acc_z", "--time-unit", "ms",
                    "--lsb", "1e-4"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.find("read in"), std::string::npos) << r.out;
  r = simtest::run({"adev", dir.file("logger.csv"), "--channel", "acc_z", "--time-unit", "min"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--time-unit min: s, ms, us or ns"), std::string::npos) << r.err;
  // A '#' line that does not name every column is not a header.
  std::ofstream(dir.file("short.csv")) << "# t,gyro_z\n0,1,2\n1,2,3\n";
  r = simtest::run({"adev", dir.file("short.csv"), "--channel", "gyro_z"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("the first row must name the columns"), std::string::npos) << r.err;
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
  EXPECT_NE(r.out.find("rate 50 Hz from the time column 't'; its steps left 40 samples "
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

// The stream (adev: memory independent of the rows) and the whole table (analyze)
// place a column on the same grid: irregular steps, dropped rows, an empty field, comments and
// blank lines; read 1, 7 and 4096 samples at a time. Both are checked against the grid built
// here from the rows written.
TEST(TextInput, StreamAndWholeTableGiveTheSameGrid) {
  simtest::TempDir dir;
  const std::string f = dir.file("irregular.csv");
  std::vector<double> want;  // the grid at 100 Hz
  {
    std::ofstream o(f);
    o << "# log\ntime,acc_z,gyro_x\n";
    double t = 0.0;
    for (int i = 0; i < 300; ++i) {
      int step = 1;
      if (i % 37 == 36) {
        step = 4;  // three rows dropped
      } else if (i % 11 == 5) {
        step = 2;  // one
      }
      if (i > 0) {
        for (int k = 1; k < step; ++k) {
          want.push_back(std::nan(""));
        }
        t += 0.01 * step + (i % 3 == 0 ? 2e-4 : -1e-4);  // jitter well under half a period
      }
      if (i == 50) {
        o << t << ",," << i << "\n";  // an empty field: missing
        want.push_back(std::nan(""));
      } else {
        o << t << "," << (i * 0.5) << "," << i << "\n";
        want.push_back(i * 0.5);
      }
      if (i == 100) {
        o << "\n# a comment in the middle\n";
      }
    }
  }
  const auto same = [&want](const std::vector<double>& got, const std::string& what) {
    ASSERT_EQ(got.size(), want.size()) << what;
    for (std::size_t i = 0; i < want.size(); ++i) {
      if (std::isnan(want[i])) {
        EXPECT_TRUE(std::isnan(got[i])) << what << " sample " << i;
      } else {
        EXPECT_EQ(got[i], want[i]) << what << " sample " << i;
      }
    }
  };
  imu::cli::TextTable table;
  std::string err;
  ASSERT_TRUE(imu::cli::read_text_table(f, table, err)) << err;
  imu::cli::TextChannel tc;
  ASSERT_TRUE(imu::cli::text_channel(table, "acc_z", 0.0, tc, err)) << err;
  EXPECT_NEAR(tc.fs_hz, 100.0, 2.0);
  same(tc.samples, "whole table");
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{4096}}) {
    imu::cli::TextColumnStream st;
    ASSERT_TRUE(st.open(f, "acc_z", 0.0, err)) << err;
    EXPECT_EQ(st.fs_hz(), tc.fs_hz);
    std::vector<double> got;
    std::vector<double> buf(chunk);
    std::size_t n = 0;
    while (st.read(buf.data(), chunk, n, err) && n > 0) {
      got.insert(got.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
    }
    ASSERT_TRUE(err.empty()) << err;
    same(got, "stream, chunks of " + std::to_string(chunk));
    EXPECT_EQ(st.time_gap_samples(), tc.time_gap_samples);
    EXPECT_EQ(st.time_name(), "time");
  }
  // The same refusals: an unknown column (the columns listed), a time going back.
  imu::cli::TextColumnStream st;
  EXPECT_FALSE(st.open(f, "acc_q", 0.0, err));
  EXPECT_EQ(err, "no column 'acc_q'; the columns: time, acc_z, gyro_x");
  const std::string back = dir.file("back.csv");
  std::ofstream(back) << "t,x\n0,1\n0.01,2\n0.02,3\n0.015,4\n";
  ASSERT_TRUE(imu::cli::read_text_table(back, table, err)) << err;
  std::string whole_err;
  EXPECT_FALSE(imu::cli::text_channel(table, "x", 0.0, tc, whole_err));
  EXPECT_FALSE(st.open(back, "x", 0.0, err));
  EXPECT_EQ(err, whole_err);
}

// Several columns in one pass (analyze reads every channel of a text file so): sample i is one
// value per column, in the order asked, and each column is the grid text_channel gives it, past
// the rows that decide the rate too (time gaps, an empty field).
TEST(TextInput, SeveralColumnsInOnePassAreEachColumnsGrid) {
  simtest::TempDir dir;
  const std::string f = dir.file("three.csv");
  const std::size_t rows = 2 * imu::cli::kRateRows + 77;
  {
    std::ofstream o(f);
    o << "a,t,b\n";
    double t = 0.0;
    for (std::size_t i = 0; i < rows; ++i) {
      t += (i % 97 == 96) ? 0.03 : 0.01;  // two samples missing, now and then
      if (i == rows - 40) {
        o << "," << t << "," << i << "\n";  // a missing field in one column only
      } else {
        o << (static_cast<double>(i) * 0.25) << "," << t << "," << i << "\n";
      }
    }
  }
  imu::cli::TextTable table;
  std::string err;
  ASSERT_TRUE(imu::cli::read_text_table(f, table, err)) << err;
  imu::cli::TextChannel ta;
  imu::cli::TextChannel tb;
  ASSERT_TRUE(imu::cli::text_channel(table, "a", 0.0, ta, err)) << err;
  ASSERT_TRUE(imu::cli::text_channel(table, "b", 0.0, tb, err)) << err;
  ASSERT_EQ(ta.samples.size(), tb.samples.size());
  ASSERT_GT(ta.time_gap_samples, 0U);
  const auto same = [](double got, double want) {
    return std::isnan(want) ? std::isnan(got) : !(got < want || got > want);
  };
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{4096}}) {
    imu::cli::TextColumnStream st;
    ASSERT_TRUE(st.open(f, std::vector<std::string>{"b", "a"}, 0.0, err)) << err;
    ASSERT_EQ(st.columns(), 2U);
    EXPECT_EQ(st.fs_hz(), ta.fs_hz);
    std::vector<double> buf(2 * chunk);
    std::size_t got = 0;
    std::size_t at = 0;
    std::size_t wrong = 0;
    while (st.read(buf.data(), chunk, got, err) && got > 0) {
      for (std::size_t i = 0; i < got && at + i < ta.samples.size(); ++i) {
        wrong += same(buf[2 * i], tb.samples[at + i]) ? 0U : 1U;
        wrong += same(buf[2 * i + 1], ta.samples[at + i]) ? 0U : 1U;
      }
      at += got;
    }
    ASSERT_TRUE(err.empty()) << err;
    EXPECT_EQ(at, ta.samples.size()) << "chunk " << chunk;
    EXPECT_EQ(wrong, 0U) << "chunk " << chunk;
    EXPECT_EQ(st.time_gap_samples(), ta.time_gap_samples);
  }
  imu::cli::TextColumnStream st;
  EXPECT_FALSE(st.open(f, std::vector<std::string>{"a", "q"}, 0.0, err));
  EXPECT_EQ(err, "no column 'q'; the columns: a, t, b");
}

// A text file longer than the rows that decide the rate (kRateRows) gives adev the same ADEV,
// number for number, as the same samples in a MAT-file: the text is streamed, not held.
TEST(TextInput, LongTextGivesTheMatFilesAdev) {
  simtest::TempDir dir;
  const std::size_t n = 3 * imu::cli::kRateRows + 123;
  std::vector<double> v(n);
  std::uint32_t s = 777U;
  std::string text = "t,acc_z\n";
  char buf[64];
  for (std::size_t i = 0; i < n; ++i) {
    s = s * 1664525U + 1013904223U;
    v[i] = static_cast<double>(static_cast<int>(s >> 20U) - 2048) * 1e-3;
    std::snprintf(buf, sizeof buf, "%.2f,%.3f\n", static_cast<double>(i) * 0.01, v[i]);
    text += buf;
  }
  const std::string csv = dir.file("long.csv");
  std::ofstream(csv) << text;
  const std::string mat = dir.file("long.mat");
  imu::mat::MatWriter w;
  ASSERT_TRUE(w.add_column("acc_z", v).ok());
  ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
  ASSERT_TRUE(w.save(mat).ok());
  const std::string ja = dir.file("csv.json");
  const std::string jb = dir.file("mat.json");
  auto r = simtest::run({"adev", csv, "--channel", "acc_z", "--lsb", "1e-3", "--estimator", "online",
                         "--json", ja});
  ASSERT_EQ(r.status, 0) << r.err;
  r = simtest::run({"adev", mat, "--channel", "acc_z", "--lsb", "1e-3", "--estimator", "online",
                    "--json", jb});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto a = simtest::json_adev(simtest::read_text(ja));
  const auto b = simtest::json_adev(simtest::read_text(jb));
  ASSERT_GT(a.size(), 60U);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].tau_s, b[i].tau_s) << i;
    EXPECT_EQ(a[i].adev, b[i].adev) << "tau " << a[i].tau_s;
  }
  EXPECT_NE(simtest::read_text(ja).find("\"n_samples\": " + std::to_string(n)), std::string::npos);
}

}  // namespace

// `run` reads text as adev and analyze do: a CSV with a nanosecond time column (one row
// missing) and the same samples in a MAT-file (the missing row a NaN) give the node the same
// record: identical ADEV telemetry, the same node statistics, the gap counted missing. Before,
// `run` read MAT-files only.
TEST(TextInput, RunReadsACsvAsItsMatFile) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  constexpr std::size_t kN = 6000;
  const char* names[6] = {"acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"};
  std::vector<std::vector<double>> cols(6, std::vector<double>(kN));
  std::uint64_t x = 0x9E3779B97F4A7C15ULL;
  for (std::size_t i = 0; i < kN; ++i) {
    for (std::size_t c = 0; c < 6; ++c) {
      x = x * 6364136223846793005ULL + 1442695040888963407ULL;
      const double u = static_cast<double>((x >> 33U) % 20001U) - 10000.0;
      cols[c][i] = c < 3 ? (c == 2 ? 9.8 : 0.0) + u * 1e-6 : u * 1e-7;  // on the default LSBs
    }
  }
  constexpr std::size_t kMissing = 2500;
  const std::string csv = dir.file("log.csv");
  {
    std::ofstream f(csv);
    f << "timestamp";
    for (const char* n : names) {
      f << "," << n;
    }
    f << "\n";
    char buf[64];
    for (std::size_t i = 0; i < kN; ++i) {
      if (i == kMissing) {
        continue;
      }
      f << 1700000000000000000LL + static_cast<long long>(i) * 5000000LL;  // 200 Hz in ns
      for (std::size_t c = 0; c < 6; ++c) {
        std::snprintf(buf, sizeof buf, ",%.17g", cols[c][i]);
        f << buf;
      }
      f << "\n";
    }
  }
  imu::mat::MatWriter w;
  for (std::size_t c = 0; c < 6; ++c) {
    std::vector<double> v = cols[c];
    v[kMissing] = std::nan("");
    ASSERT_TRUE(w.add_column(names[c], v).ok());
  }
  ASSERT_TRUE(w.add_scalar("fs", 200.0).ok());
  const std::string mat = dir.file("log.mat");
  {
    std::ofstream f(mat, std::ios::binary);
    f.write(reinterpret_cast<const char*>(w.bytes().data()),
            static_cast<std::streamsize>(w.bytes().size()));
  }
  std::string json[2];
  for (int k = 0; k < 2; ++k) {
    const std::string out = dir.file(k == 0 ? "run_csv" : "run_mat");
    const auto r = simtest::run({"run", k == 0 ? csv : mat, "--channel", "gyro_y", "--no-plots",
                                 "--quiet", "--sim-windows", "5", "--out", out});
    ASSERT_EQ(r.status, 0) << r.err;
    json[k] = simtest::read_text(out + "/report.json");
  }
  EXPECT_NE(json[0].find("text input: 6 column(s) at 200 Hz from the time column 'timestamp'"),
            std::string::npos)
      << json[0].substr(0, 2000);
  const auto a = simtest::json_adev(json[0]);
  const auto b = simtest::json_adev(json[1]);
  ASSERT_GT(a.size(), 10U);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].tau_s, b[i].tau_s);
    EXPECT_EQ(a[i].adev, b[i].adev) << "tau " << a[i].tau_s;
  }
  for (const char* key : {"samples", "missing", "frames"}) {
    EXPECT_EQ(simtest::json_number_in(json[0], "node_stats", key),
              simtest::json_number_in(json[1], "node_stats", key))
        << key;
  }
}

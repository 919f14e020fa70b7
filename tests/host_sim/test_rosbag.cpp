// ROS bag input: bags written at test time by Debian's python3-rosbag (make_rosbags.py: the
// same 3000 samples at 200 Hz with a 10-sample gap, in uncompressed, LZ4 and BZ2 chunks, two
// Imu topics, zero header stamps) read by adev and analyze. Each readable bag gives the rate
// of its stamps and the ADEV of the same samples written as a CSV with the same stamps and as
// a MAT-file at 200 Hz; the refusals (BZ2, the topic, a cut bag, a corrupt LZ4 block, an
// unindexed bag) are one line each. The bags need python3-rosbag and python3-sensor-msgs
// (toolchains/install-deps.sh test): without them the tests fail.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "imu/cli/rosbag.hpp"
#include "imu/cli/text_input.hpp"
#include "imu/mat/mat_writer.hpp"
#include "sim_test_util.hpp"

namespace {

// The bags, written once for every test of this file.
class RosBag : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new simtest::TempDir();
    // Debian's interpreter: python3-rosbag installs into its dist-packages.
    const std::string cmd = std::string(IMU_DEBIAN_PYTHON) + " '" + IMU_MAKE_ROSBAGS + "' '" +
                            dir_->path() + "' 2>'" + dir_->file("make.log") + "'";
    made_ = std::system(cmd.c_str()) == 0;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override {
    SKIP_IF_EMULATED();
    ASSERT_TRUE(made_) << "make_rosbags.py failed (python3-rosbag and python3-sensor-msgs are "
                          "needed: toolchains/install-deps.sh test): "
                       << simtest::read_text(dir_->file("make.log"));
  }
  static std::string file(const std::string& name) { return dir_->file(name); }

 private:
  static simtest::TempDir* dir_;
  static bool made_;
};
simtest::TempDir* RosBag::dir_ = nullptr;
bool RosBag::made_ = false;

// The members of channel `name` in adev's JSON of several channels.
std::string channel_json(const std::string& json, const std::string& name) {
  const std::size_t at = json.find("\"" + name + "\": {");
  return at == std::string::npos ? std::string() : json.substr(at);
}

std::string read_bytes(const std::string& path) { return simtest::read_text(path); }

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// adev's JSON of acc_z and gyro_x of FILE (extra options after).
std::string adev_json(const std::string& path, const std::string& json,
                      const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {"adev", path, "--channel", "acc_z,gyro_x", "--json", json};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = simtest::run(args);
  EXPECT_EQ(r.status, 0) << path << ": " << r.err;
  return simtest::read_text(json);
}

// The same ADEV (rel 1e-9: the JSON's 10 significant digits of the same sums), rate and length.
void expect_same_adev(const std::string& got, const std::string& want, const std::string& what) {
  for (const char* ch : {"acc_z", "gyro_x"}) {
    const std::string g = channel_json(got, ch);
    const std::string w = channel_json(want, ch);
    ASSERT_FALSE(g.empty()) << what << " " << ch;
    ASSERT_FALSE(w.empty()) << what << " " << ch;
    EXPECT_NEAR(simtest::json_number_in(g, "fs_hz", "fs_hz"), 200.0, 200.0 * 1e-9) << what;
    EXPECT_EQ(simtest::json_number_in(g, "n_samples", "n_samples"), 3000.0) << what;
    EXPECT_EQ(simtest::json_number_in(g, "gaps", "samples"), 10.0) << what;
    const auto a = simtest::json_adev(g);
    const auto b = simtest::json_adev(w);
    ASSERT_GT(a.size(), 8U) << what;
    ASSERT_EQ(a.size(), b.size()) << what;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_NEAR(a[i].tau_s, b[i].tau_s, 1e-12) << what << " " << ch;
      EXPECT_NEAR(a[i].adev, b[i].adev, 1e-9 * b[i].adev) << what << " " << ch << " tau "
                                                          << a[i].tau_s;
    }
  }
}

// The CSV's acc_z and gyro_x on their 200 Hz grid (gaps NaN) as a MAT-file with fs = 200.
void csv_to_mat(const std::string& csv, const std::string& mat) {
  imu::cli::TextColumnStream st;
  std::string err;
  ASSERT_TRUE(st.open(csv, std::vector<std::string>{"acc_z", "gyro_x"}, 0.0, err)) << err;
  std::vector<double> acc;
  std::vector<double> gyro;
  std::vector<double> buf(2 * 512);
  std::size_t got = 0;
  while (st.read(buf.data(), 512, got, err) && got > 0) {
    for (std::size_t i = 0; i < got; ++i) {
      acc.push_back(buf[2 * i]);
      gyro.push_back(buf[2 * i + 1]);
    }
  }
  ASSERT_TRUE(err.empty()) << err;
  ASSERT_EQ(acc.size(), 3000U);
  imu::mat::MatWriter w;
  ASSERT_TRUE(w.add_column("acc_z", acc).ok());
  ASSERT_TRUE(w.add_column("gyro_x", gyro).ok());
  ASSERT_TRUE(w.add_scalar("fs", 200.0).ok());
  ASSERT_TRUE(w.save(mat).ok());
}

TEST_F(RosBag, EachReadableBagGivesTheAdevOfItsSamplesAtTheRateOfItsStamps) {
  csv_to_mat(file("imu.csv"), file("imu.mat"));
  const std::string from_csv = adev_json(file("imu.csv"), file("csv.json"));
  const std::string from_mat = adev_json(file("imu.mat"), file("mat.json"));
  expect_same_adev(from_csv, from_mat, "csv vs mat");
  for (const char* bag : {"plain.bag", "lz4.bag", "zero.bag"}) {
    const std::string j = adev_json(file(bag), file("bag.json"));
    expect_same_adev(j, from_mat, bag);
    expect_same_adev(j, from_csv, bag);
  }
  // The second topic of two.bag: its own samples.
  csv_to_mat(file("imu1.csv"), file("imu1.mat"));
  expect_same_adev(adev_json(file("two.bag"), file("two.json"), {"--topic", "/imu1"}),
                   adev_json(file("imu1.mat"), file("imu1.json")), "two.bag /imu1");
}

TEST_F(RosBag, NoOptionsNeededAndTheTimesAreSaid) {
  auto r = simtest::run({"adev", file("lz4.bag"), "--channel", "acc_z"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("acc_z: 3000 samples at 200 Hz"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("header stamps"), std::string::npos) << r.out;
  r = simtest::run({"adev", file("zero.bag"), "--channel", "gyro_z"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("note: the header stamps of /imu are all zero: its times are the bag's "
                       "record times"),
            std::string::npos)
      << r.out;
  r = simtest::run({"analyze", file("plain.bag"), "--channel", "gyro_x"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("ROS bag topic /imu: rate 200 Hz from the time column 't_ns'; its steps "
                       "left 10 samples missing (gaps)"),
            std::string::npos)
      << r.out;
}

// `run` reads a bag as adev and analyze do: the LZ4 bag and the CSV of the same samples give
// the node the same record (identical ADEV telemetry), the bag's topic and gap said.
// --time-unit names a text column's unit; a bag's stamps are ns: refused (exit 2), not applied.
TEST_F(RosBag, TimeUnitIsRefusedOnABag) {
  for (const char* cmd : {"adev", "analyze"}) {
    const auto r = simtest::run({cmd, file("plain.bag"), "--channel", "acc_z", "--time-unit", "s"});
    EXPECT_EQ(r.status, 2) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find("is a ROS bag, whose header stamps are in ns"), std::string::npos)
        << r.err;
  }
}

TEST_F(RosBag, RunSendsABagAsItsCsv) {
  std::string json[2];
  for (int k = 0; k < 2; ++k) {
    const std::string out = file(k == 0 ? "run_bag" : "run_csv");
    const auto r = simtest::run({"run", file(k == 0 ? "lz4.bag" : "imu.csv"), "--channel",
                                 "gyro_x", "--no-plots", "--quiet", "--sim-windows", "5", "--out",
                                 out});
    ASSERT_EQ(r.status, 0) << r.err;
    json[k] = simtest::read_text(out + "/report.json");
  }
  EXPECT_NE(json[0].find("ROS bag topic /imu: 6 column(s) at 200 Hz from the time column "
                         "'t_ns'; its steps left 10 samples missing"),
            std::string::npos);
  const auto a = simtest::json_adev(json[0]);
  const auto b = simtest::json_adev(json[1]);
  ASSERT_GT(a.size(), 8U);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].adev, b[i].adev) << "tau " << a[i].tau_s;
  }
}

// The reader's rows through the library: the topic, the connections, exact epoch stamps.
TEST_F(RosBag, RowsCarryExactStampsAndTheImuFields) {
  imu::cli::BagRows rows;
  std::string err;
  ASSERT_TRUE(rows.open(file("lz4.bag"), "", err)) << err;
  EXPECT_EQ(rows.topic(), "/imu");
  ASSERT_EQ(rows.connections().size(), 2U);
  EXPECT_EQ(rows.names(), (std::vector<std::string>{"t_ns", "acc_x", "acc_y", "acc_z", "gyro_x",
                                                    "gyro_y", "gyro_z"}));
  imu::cli::TextTable csv;
  ASSERT_TRUE(imu::cli::read_text_table(file("imu.csv"), csv, err)) << err;
  rows.exact_integers(0);
  std::vector<double> row;
  std::size_t n = 0;
  std::size_t wrong = 0;
  long long first = 0;
  while (rows.next(row, err)) {
    ASSERT_TRUE(rows.has_exact());
    if (n == 0) {
      first = rows.exact();
    }
    for (std::size_t c = 1; c < 7 && n < csv.cols[c].size(); ++c) {
      const double want = csv.cols[c][n];
      wrong += row[c] < want || row[c] > want ? 1U : 0U;  // the same double, bit for bit
    }
    ++n;
  }
  EXPECT_TRUE(err.empty()) << err;
  EXPECT_EQ(n, 2990U);
  EXPECT_EQ(wrong, 0U);
  EXPECT_EQ(first, 1700000000000000123LL);
}

TEST_F(RosBag, Bz2IsRefusedWithTheCommandThatConvertsIt) {
  for (const char* cmd : {"adev", "analyze"}) {
    const auto r = simtest::run({cmd, file("bz2.bag"), "--channel", "acc_z"});
    EXPECT_EQ(r.status, 1) << cmd;
    EXPECT_NE(r.err.find("ROS bag chunk compressed with bz2: not read; run `rosbag decompress " +
                         file("bz2.bag") + "` (or `rosbag compress --lz4`) first"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(simtest::count_lines(r.err), 1U) << r.err;
  }
}

TEST_F(RosBag, SeveralImuTopicsNeedTopicWhichMustNameOne) {
  for (const char* cmd : {"adev", "analyze"}) {
    auto r = simtest::run({cmd, file("two.bag"), "--channel", "acc_z"});
    EXPECT_EQ(r.status, 2) << cmd;
    EXPECT_NE(r.err.find("2 sensor_msgs/Imu topics: /imu0, /imu1; choose one with --topic"),
              std::string::npos)
        << r.err;
    r = simtest::run({cmd, file("two.bag"), "--channel", "acc_z", "--topic", "/status"});
    EXPECT_EQ(r.status, 2) << cmd;
    EXPECT_NE(r.err.find("--topic /status: no sensor_msgs/Imu topic of that name; the "
                         "sensor_msgs/Imu topics: /imu0, /imu1"),
              std::string::npos)
        << r.err;
    r = simtest::run({cmd, file("imu.csv"), "--channel", "acc_z", "--topic", "/imu"});
    EXPECT_EQ(r.status, 2) << cmd;
    EXPECT_NE(r.err.find("is not a ROS bag"), std::string::npos) << r.err;
  }
  const auto r = simtest::run({"adev", file("two.bag"), "--channel", "acc_z", "--topic", "/imu0"});
  EXPECT_EQ(r.status, 0) << r.err;
}

// Damaged bags: one line each, exit 1, whatever part is damaged.
TEST_F(RosBag, DamagedBagsAreRefusedInOneLine) {
  const std::string lz4 = read_bytes(file("lz4.bag"));
  const std::string plain = read_bytes(file("plain.bag"));
  const std::size_t frame = lz4.find(std::string("\x04\x22\x4d\x18", 4));
  ASSERT_NE(frame, std::string::npos);
  const std::size_t index = plain.find("index_pos=");
  ASSERT_NE(index, std::string::npos);
  struct Case {
    const char* name;
    std::string bytes;
    const char* why;
  };
  std::vector<Case> cases = {
      {"half.bag", lz4.substr(0, lz4.size() / 2), "ROS bag truncated: its index is at byte"},
      {"short.bag", lz4.substr(0, lz4.size() - 10), "runs past the end of the file (truncated)"},
      {"head.bag", lz4.substr(0, 40), "runs past the end of the file (truncated)"},
      {"block.bag", lz4, "lz4 chunk: "},
      {"size.bag", lz4, "lz4 chunk: an LZ4 block larger than its frame's block maximum"},
      {"noindex.bag", plain, "ROS bag without an index (the recording was not closed); run "
                             "`rosbag reindex"}};
  cases[3].bytes[frame + 7 + 4 + 100] ^= 0x21;  // inside the first block's sequences
  cases[4].bytes[frame + 7 + 3] = 0x7F;         // its size word: far above 1 MiB
  for (std::size_t k = 0; k < 8; ++k) {
    cases[5].bytes[index + 10 + k] = '\0';  // index_pos = 0
  }
  for (const Case& c : cases) {
    write_bytes(file(c.name), c.bytes);
    const auto r = simtest::run({"adev", file(c.name), "--channel", "acc_z"});
    EXPECT_EQ(r.status, 1) << c.name;
    EXPECT_NE(r.err.find(c.why), std::string::npos) << c.name << ": " << r.err;
    EXPECT_EQ(simtest::count_lines(r.err), 1U) << c.name << ": " << r.err;
  }
}

}  // namespace

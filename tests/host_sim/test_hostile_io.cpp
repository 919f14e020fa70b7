// Hostile names, paths and files against imu-sim and imu-fw: no command runs from a name,
// nothing is written outside the chosen folder, no device or link is replaced, every write is
// checked, a small file never turns into minutes of work or gigabytes, a rate the time column
// contradicts is refused, a node that does not read is dropped, and a run whose node refused its
// model or sent impossible telemetry is an error. Each case names the defect it guards against.
#include <gtest/gtest.h>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "fw_process.hpp"
#include "imu/hal/receiver.hpp"
#include "sim_test_util.hpp"

namespace {

using simtest::run;
using simtest::TempDir;

// Every path under dir (recursive), relative to it.
void list_tree(const std::string& dir, const std::string& rel, std::vector<std::string>& out) {
  DIR* d = opendir(dir.c_str());
  if (d == nullptr) {
    return;
  }
  while (const dirent* e = readdir(d)) {
    const std::string n = e->d_name;
    if (n == "." || n == "..") {
      continue;
    }
    std::string rel_n = rel;
    rel_n += n;
    out.push_back(rel_n);
    std::string path = dir;
    path += '/';
    path += n;
    struct stat st {};
    if (lstat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
      rel_n += '/';
      list_tree(path, rel_n, out);
    }
  }
  closedir(d);
}

std::vector<std::string> tree(const std::string& dir) {
  std::vector<std::string> out;
  list_tree(dir, "", out);
  return out;
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  for (const auto& x : v) {
    if (x.find(s) != std::string::npos) {
      return true;
    }
  }
  return false;
}

// A CSV: header `names` (time column first: t), n rows of white noise at fs_hz.
void write_csv(const std::string& path, const std::vector<std::string>& names, std::size_t n,
               double fs_hz, unsigned seed) {
  std::ofstream f(path, std::ios::binary);
  f << "t";
  for (const auto& c : names) {
    f << ',' << c;
  }
  f << '\n';
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1e-3);
  char b[64];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, "%.6f", static_cast<double>(i) / fs_hz);
    f << b;
    for (std::size_t c = 0; c < names.size(); ++c) {
      std::snprintf(b, sizeof b, ",%.9g", g(rng));
      f << b;
    }
    f << '\n';
  }
}

// python3's json module accepts the file (CI installs python3 with the test tools).
bool valid_json(const std::string& path) {
  const std::string cmd = "python3 -c 'import json,sys; json.load(open(sys.argv[1], encoding=\"utf-8\"))' '" +
                          path + "' 2>/dev/null";
  return std::system(cmd.c_str()) == 0;
}

bool has_gnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

// A newline in the input file's name or in --plots ended gnuplot's string: the next line ran as
// a gnuplot command (system() included).
TEST(HostileIo, NewlinesInNamesRunNoGnuplotCommand) {
  TempDir dir;
  const std::string evil = "in\nsystem 'touch PWNED'\nprint '";
  const std::string csv = dir.file(evil + ".csv");
  write_csv(csv, {"gyro_x"}, 4000, 100.0, 11);
  const std::string plots = dir.file("plots");
  auto r = run({"adev", csv, "--channel", "gyro_x", "--plots", plots});
  EXPECT_EQ(r.status, 0) << r.err;
  // A newline in --plots: refused before any work (control characters in an output path).
  r = run({"adev", csv, "--channel", "gyro_x", "--plots", dir.file("p\nsystem 'touch PWNED'\n")});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.out, "");
  const auto files = tree(dir.path());
  for (const auto& f : files) {
    EXPECT_NE(f.substr(f.rfind('/') == std::string::npos ? 0 : f.rfind('/') + 1), "PWNED")
        << "a gnuplot command ran from a file name";
  }
  if (has_gnuplot()) {
    EXPECT_TRUE(contains(files, ".svg")) << r.out << r.err;
  } else {
    std::printf("gnuplot absent: plots not rendered, the .gp files were still checked\n");
  }
}

// Column names became file names unchecked: `../../../x` wrote three folders up; `a/b` and `a_b`
// (and `a-b`, `a_b` in adev) overwrote each other.
TEST(HostileIo, ColumnNamesStayInsideThePlotsFolderAndDistinct) {
  TempDir dir;
  const std::string csv = dir.file("cols.csv");
  write_csv(csv, {"../../x", "a/b", "a_b"}, 3000, 100.0, 12);
  const std::string plots = dir.file("deep/er/plots");
  ASSERT_EQ(std::system(("mkdir -p '" + plots + "'").c_str()), 0);
  auto r = run({"analyze", csv, "--channel", "all", "--plots", plots});
  ASSERT_EQ(r.status, 0) << r.err;
  for (const auto& f : tree(dir.path())) {
    EXPECT_TRUE(f == "cols.csv" || f.rfind("deep", 0) == 0) << "written outside: " << f;
    EXPECT_TRUE(f.rfind("deep/er/plots", 0) == 0 || f == "deep" || f == "deep/er" ||
                f == "cols.csv")
        << "written outside the plots folder: " << f;
  }
  // Three channels, three distinct sets of files.
  std::size_t gp = 0;
  for (const auto& f : tree(plots)) {
    gp += f.size() > 3 && f.compare(f.size() - 3, 3, ".gp") == 0 ? 1U : 0U;
  }
  EXPECT_GE(gp, 3U) << "plot files of different channels collided";
  // adev: `a-b` and `a_b` give two plot stems.
  const std::string csv2 = dir.file("dash.csv");
  write_csv(csv2, {"a-b", "a_b"}, 3000, 100.0, 13);
  const std::string p2 = dir.file("p2");
  r = run({"adev", csv2, "--channel", "all", "--plots", p2});
  ASSERT_EQ(r.status, 0) << r.err;
  std::size_t gp2 = 0;
  for (const auto& f : tree(p2)) {
    gp2 += f.size() > 3 && f.compare(f.size() - 3, 3, ".gp") == 0 ? 1U : 0U;
  }
  EXPECT_EQ(gp2, 2U) << "adev plot names collided after cleaning";
}

// The atomic writer renamed its temp file over any target: /dev/null became a regular file
// (as root), a FIFO never got the data, a symlink was replaced; `run --out ''` wrote into /.
TEST(HostileIo, DevicesFifosAndLinksAreWrittenThroughNotReplaced) {
  TempDir dir;
  const std::string csv = dir.file("in.csv");
  write_csv(csv, {"gyro_x"}, 3000, 100.0, 14);
  // A character device stays one. As root (the case where a rename would replace it), a private
  // null device in the test's folder: a writer that replaces devices must not take the
  // machine's /dev/null with it. Otherwise /dev/null itself (a rename there is refused).
  std::string null_dev = "/dev/null";
  if (geteuid() == 0 && mknod(dir.file("null").c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0) {
    const int fd = ::open(dir.file("null").c_str(), O_WRONLY);  // fails on a nodev mount
    if (fd >= 0) {
      ::close(fd);
      null_dev = dir.file("null");
    }
  }
  auto r = run({"adev", csv, "--channel", "gyro_x", "--json", null_dev});
  EXPECT_EQ(r.status, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(stat(null_dev.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << null_dev << " was replaced";
  // A symlink is followed: the target gets the data, the link stays a link.
  ASSERT_EQ(mkdir(dir.file("real").c_str(), 0700), 0);
  const std::string target = dir.file("real/out.json");
  const std::string link = dir.file("link.json");
  ASSERT_EQ(symlink(target.c_str(), link.c_str()), 0);
  {
    std::ofstream(target) << "old";
  }
  r = run({"adev", csv, "--channel", "gyro_x", "--json", link});
  EXPECT_EQ(r.status, 0) << r.err;
  ASSERT_EQ(lstat(link.c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode)) << "the link was replaced by a file";
  EXPECT_NE(simtest::read_text(target).find("\"adev\": ["), std::string::npos);
  // Refused before any work, with the reason: a dangling link, a directory, an empty path.
  const std::string dangling = dir.file("dangling.json");
  ASSERT_EQ(symlink(dir.file("nowhere/x.json").c_str(), dangling.c_str()), 0);
  for (const std::string& bad : {dangling, dir.path(), std::string()}) {
    r = run({"adev", csv, "--channel", "gyro_x", "--json", bad});
    EXPECT_EQ(r.status, 2) << "'" << bad << "': " << r.err;
    EXPECT_EQ(r.out, "") << "work was done before the output was refused";
    EXPECT_EQ(simtest::count_lines(r.err), 1U) << r.err;
  }
  r = run({"run", csv, "--out", "", "--quiet"});
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
}

// A FIFO target gets the document (the reader is a thread here, so not under qemu-user).
TEST(HostileIo, AFifoTargetGetsTheDocument) {
  SKIP_IF_EMULATED();
  TempDir dir;
  const std::string csv = dir.file("in.csv");
  write_csv(csv, {"gyro_x"}, 3000, 100.0, 14);
  struct stat st {};
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] { got = simtest::read_text(fifo); });
  const auto r = run({"adev", csv, "--channel", "gyro_x", "--json", fifo});
  reader.join();
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(got.find("\"adev\": ["), std::string::npos) << got;
  ASSERT_EQ(lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

// Small files, long work: a 30 KB CSV whose time jumps by 1e6 s filled in 10^8 samples per jump
// (15 s; minutes for more rows); thousands of columns were re-read once per column; a
// 100k-column header held gigabytes; one 2 MB line was read whole.
TEST(HostileIo, SmallFilesAreBoundedWork) {
  TempDir dir;
  const std::string jump = dir.file("jump.csv");
  {
    std::ofstream f(jump);
    f << "t,gyro_x\n";
    double t = 0.0;
    for (int i = 0; i < 1000; ++i) {
      t += i % 30 == 29 ? 1e6 : 0.01;
      char b[64];
      std::snprintf(b, sizeof b, "%.3f,%g\n", t, (i % 7) * 1e-3);
      f << b;
    }
  }
  auto r = run({"adev", jump, "--channel", "gyro_x"});
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.err.find("split the file at its long gaps"), std::string::npos) << r.err;
  // 3000 columns x 5 rows: one pass, every channel in the JSON.
  const std::string wide = dir.file("wide.csv");
  {
    std::ofstream f(wide);
    for (int c = 0; c < 3000; ++c) {
      f << (c ? "," : "") << 'c' << c;
    }
    f << '\n';
    for (int i = 0; i < 5; ++i) {
      for (int c = 0; c < 3000; ++c) {
        f << (c ? "," : "") << (c * 7 + i) % 13;
      }
      f << '\n';
    }
  }
  const std::string json = dir.file("wide.json");
  r = run({"adev", wide, "--channel", "all", "--fs", "100", "--json", json});
  EXPECT_EQ(r.status, 0) << r.err;
  const std::string j = simtest::read_text(json);
  EXPECT_NE(j.find("\"c2999\": {"), std::string::npos);
  // Too many channels for one analysis: refused at once, not minutes later.
  r = run({"analyze", wide, "--channel", "all", "--fs", "100"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("3000 channels, more than the 24"), std::string::npos) << r.err;
  // A header wider than the column limit and a line longer than the line limit.
  const std::string wider = dir.file("wider.csv");
  {
    std::ofstream f(wider);
    for (int c = 0; c < 5000; ++c) {
      f << (c ? "," : "") << 'c' << c;
    }
    f << "\n1\n";
  }
  r = run({"adev", wider, "--channel", "all", "--fs", "100"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("5000 columns, more than 4096"), std::string::npos) << r.err;
  // A header of blanks only (the text fuzzer's first finding: the table had no column).
  const std::string blanks = dir.file("blanks.csv");
  {
    std::ofstream(blanks) << " \n\t\n";
  }
  r = run({"analyze", blanks, "--channel", "gyro_x", "--fs", "100"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no header and data rows"), std::string::npos) << r.err;
  const std::string longline = dir.file("long.csv");
  {
    std::ofstream f(longline);
    f << "gyro_x\n" << std::string(std::size_t{3} << 20U, '1') << "\n";
  }
  r = run({"adev", longline, "--channel", "gyro_x", "--fs", "100"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("line 2 is longer than 1048576 bytes"), std::string::npos) << r.err;
}

// A 100 Hz log going on at 1 kHz was analysed as 100 Hz without a word; --fs 10 against a
// 100 Hz time column was accepted.
TEST(HostileIo, ARateTheTimeColumnContradictsIsRefused) {
  TempDir dir;
  const std::string csv = dir.file("rate.csv");
  {
    std::ofstream f(csv);
    f << "t,gyro_x\n";
    double t = 0.0;
    for (int i = 0; i < 3000; ++i) {
      t += i < 2000 ? 0.01 : 0.001;
      char b[64];
      std::snprintf(b, sizeof b, "%.4f,%g\n", t, (i % 5) * 1e-3);
      f << b;
    }
  }
  auto r = run({"adev", csv, "--channel", "gyro_x"});
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.err.find("the rate rises there"), std::string::npos) << r.err;
  const std::string steady = dir.file("steady.csv");
  write_csv(steady, {"gyro_x"}, 3000, 100.0, 15);
  r = run({"adev", steady, "--channel", "gyro_x", "--fs", "10"});
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.err.find("--fs 10 Hz contradicts the time column 't'"), std::string::npos) << r.err;
  r = run({"adev", steady, "--channel", "gyro_x", "--fs", "100"});
  EXPECT_EQ(r.status, 0) << r.err;
}

// `"` in a column name gave unparseable multi-channel JSON; `#` broke the Kalibr YAML; a newline
// in the input path injected YAML keys; ESC bytes from the file reached the terminal raw.
TEST(HostileIo, NamesAreEscapedForJsonYamlAndTheTerminal) {
  TempDir dir;
  const std::string csv = dir.file("a\"b\nrostopic: evil\n.csv");
  write_csv(csv, {"acc_x", "gyro_x", "acc_\"q\" #c"}, 3000, 100.0, 16);
  const std::string json = dir.file("all.json");
  const std::string yaml = dir.file("imu.yaml");
  auto r = run({"analyze", csv, "--channel", "acc_x,gyro_x,acc_\"q\" #c", "--json", json,
                "--yaml", yaml});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(valid_json(json)) << simtest::read_text(json).substr(0, 400);
  const std::string y = simtest::read_text(yaml);
  std::size_t topics = 0;
  for (std::size_t p = y.find("rostopic:"); p != std::string::npos; p = y.find("rostopic:", p + 1)) {
    topics += p == 0 || y[p - 1] == '\n' ? 1U : 0U;
  }
  EXPECT_EQ(topics, 1U) << "a key was injected into the YAML:\n" << y;
  // Terminal escapes from a field reach the error message escaped.
  const std::string esc = dir.file("esc.csv");
  {
    std::ofstream f(esc);
    f << "t,gyro_x\n0,1\n0.01,\x1b]0;owned\x07\x1b[2J\n";
  }
  r = run({"adev", esc, "--channel", "gyro_x"});
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err.find('\x1b'), std::string::npos) << "raw ESC in the error message";
  EXPECT_NE(r.err.find("not a number"), std::string::npos) << r.err;
}

// A time column stepping by 1e-300 s: the rate 1e+300 Hz was printed with 300 digits.
TEST(HostileIo, HugeNumbersArePrintedShort) {
  TempDir dir;
  const std::string csv = dir.file("tiny.csv");
  {
    std::ofstream(csv) << "t,gyro_x\n0,1\n1e-300,2\n2e-300,3\n";
  }
  const auto r = run({"adev", csv, "--channel", "gyro_x"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("1e+300 Hz"), std::string::npos) << r.err;
  EXPECT_LT(r.err.size(), 200U) << r.err;
}

// On a full disk `analyze --plots` said "wrote ... svg, png" and exited 0 with a cut CSV and an
// empty .gp. Needs a small tmpfs: root only.
TEST(HostileIo, AFullDiskIsAnErrorNotAWrite) {
  if (geteuid() != 0) {
    GTEST_SKIP() << "needs root to mount a small tmpfs (a full disk); skipped";
  }
  TempDir dir;
  const std::string csv = dir.file("in.csv");
  write_csv(csv, {"gyro_x"}, 20000, 100.0, 17);
  const std::string mnt = dir.file("small");
  ASSERT_EQ(mkdir(mnt.c_str(), 0700), 0);
  if (mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=16k") != 0) {
    GTEST_SKIP() << "mount(tmpfs) refused here (" << std::strerror(errno) << "); skipped";
  }
  {
    // Fill it nearly: 12 KiB of 16.
    std::ofstream(mnt + "/fill", std::ios::binary) << std::string(12 * 1024, 'x');
  }
  const auto r = run({"analyze", csv, "--channel", "gyro_x", "--plots", mnt});
  const auto r2 = run({"adev", csv, "--channel", "gyro_x", "--json", mnt + "/a.json", "--taus",
                       "all", "--estimator", "full"});
  umount(mnt.c_str());
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("No space left"), std::string::npos) << r.err;
  EXPECT_EQ(r2.status, 1) << r2.out;
}

// A refused model ran the default one with exit 0 (only `model_rejected 1` said so).
TEST(HostileIo, ARefusedModelIsAnErrorExit) {
  SKIP_IF_EMULATED();  // run's loopback node is a thread
  TempDir dir;
  const std::string mat = dir.file("synth.mat");
  auto r = run({"synth", "--out", mat, "--duration", "200"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string model = dir.file("model.json");
  {
    std::ofstream(model) << R"({"channel": "acc_z", "model_after": {"n": -1e-3, "q": 0, "k": 0,
      "r": 0, "sin_a": 0, "sin2_a": 0, "gm": [{"sb": 1e-6, "tb_s": 300}],
      "bias_instability": {"b": 0, "tau_lo_s": 0, "tau_hi_s": 0}}})";
  }
  r = run({"run", mat, "--model", model, "--no-plots", "--quiet", "--out", dir.file("o")});
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.err.find("refused the pushed model"), std::string::npos) << r.err;
}

// A node that sends impossible ADEV points (a negative ADEV, ci_lo above ci_hi) beside a
// complete final set: run accepted them and exited 0. The node here is this test: it listens on
// the loopback name, takes run's samples, then answers with its own telemetry.
TEST(HostileIo, ImpossibleTelemetryIsAnErrorExit) {
  SKIP_IF_EMULATED();
  TempDir dir;
  const std::string mat = dir.file("s.mat");
  ASSERT_EQ(run({"synth", "--out", mat, "--duration", "20"}).status, 0);  // 2000 samples
  const std::string bus = fwtest::unique_bus("badtel");
  imu::hal::CanSocket node;
  ASSERT_EQ(node.open(bus.c_str()), imu::hal::IoStatus::kOk);  // first on the name: it listens
  fwtest::FwProcess p({"run", mat, "--bus", bus, "--node", "external", "--window", "0",
                       "--no-plots", "--quiet", "--out", dir.file("o")},
                      IMU_SIM_PATH);
  imu::hal::Receiver<8> rx;
  std::uint64_t samples = 0;
  imu::hal::RxFrame in[64];
  const double t0 = fwtest::now_s();
  while (samples < 2000 && fwtest::now_s() - t0 < 20.0) {
    std::size_t n = 0;
    if (node.receive(in, 64, n, 100) != imu::hal::IoStatus::kOk) {
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      (void)rx.push_drain(in[i].frame, in[i].nbytes, in[i].rx_time_ns,
                          [&](const imu::hal::RxEvent& e) {
                            samples += e.type == imu::hal::RxEvent::Type::kSample ? 1U : 0U;
                          });
    }
  }
  ASSERT_EQ(samples, 2000U);
  imu::hal::EncodedFrames fr{};
  const auto send_all = [&]() {
    for (std::size_t i = 0; i < fr.count; ++i) {
      ASSERT_EQ(node.send(fr.frame[i], 2000), imu::hal::IoStatus::kOk);
    }
  };
  imu::hal::StatsRecord st{};
  st.frames = 2001;
  st.samples = 2000;
  imu::hal::encode(st, imu::hal::Layout::kFd, 1, fr);
  send_all();
  // The impossible point goes first: once the final set is complete run may end the session,
  // and on a loaded machine it did so between two of these sends (the last one then failed).
  imu::hal::AdevRecord bad{0, 0, 1, 0.01F, -1e-3F, 2e-3F, 1e-3F, 1999};
  imu::hal::encode(bad, imu::hal::Layout::kFd, 2, fr);
  send_all();
  for (std::uint8_t c = 0; c < 6; ++c) {
    imu::hal::AdevRecord a{c, 0, 1, 0.01F, 1e-3F, 9e-4F, 1.1e-3F, 1999};
    imu::hal::encode(a, imu::hal::Layout::kFd, 3, fr);
    send_all();
  }
  ASSERT_TRUE(p.wait(40.0)) << "run still waiting";
  EXPECT_EQ(p.status(), 1) << p.out() << p.err();
  EXPECT_NE(p.err().find("impossible ADEV records"), std::string::npos) << p.err();
}

// SIGTERM during a long synth left a 230 MB *.tmp-XXXXXX behind.
TEST(HostileIo, ASignalLeavesNoTempFile) {
  SKIP_IF_EMULATED();
  TempDir dir;
  fwtest::FwProcess p({"synth", "--out", dir.file("big.mat"), "--duration", "300000"},
                      IMU_SIM_PATH);
  // Wait for the temp file to appear (the writer is at work), then stop it.
  bool seen = false;
  for (int i = 0; i < 500 && !seen; ++i) {
    seen = contains(tree(dir.path()), ".tmp-");
    usleep(10000);
  }
  ASSERT_TRUE(seen) << "no temp file seen while synth wrote";
  p.signal(SIGTERM);
  ASSERT_TRUE(p.wait(10.0)) << "synth still running 10 s after SIGTERM";
  EXPECT_NE(p.status(), 0);
  EXPECT_FALSE(contains(tree(dir.path()), ".tmp-")) << "a temp file was left behind";
  EXPECT_FALSE(contains(tree(dir.path()), "big.mat")) << "a partial output appeared";
}

// A peer that keeps sending but never reads the telemetry: imu-fw ignored SIGTERM (still
// running 60 s after) and stayed connected forever.
void flood_without_reading(imu::hal::CanSocket& peer, double seconds) {
  imu::hal::EncodedFrames fr{};
  imu::hal::ConfigRecord c{};
  c.cfg_id = 1;
  c.rate_hz = 100.0;
  for (double& l : c.lsb) {
    l = 1e-3;
  }
  imu::hal::encode(c, imu::hal::Layout::kFd, 0, fr);
  (void)peer.send(fr.frame[0], 1000);
  const double t0 = fwtest::now_s();
  for (std::uint32_t k = 0; fwtest::now_s() - t0 < seconds; ++k) {
    imu::hal::SampleRecord s{};
    s.seq = k;
    s.cfg_id = 1;
    for (std::size_t ch = 0; ch < 6; ++ch) {
      s.counts[ch] = static_cast<std::int32_t>((k * 7 + ch * 3) % 11) - 5;
    }
    imu::hal::encode(s, imu::hal::Layout::kFd, fr);
    const auto st = peer.send(fr.frame[0], 20);
    if (st != imu::hal::IoStatus::kOk && st != imu::hal::IoStatus::kWouldBlock &&
        st != imu::hal::IoStatus::kTimeout) {
      return;  // dropped by imu-fw
    }
  }
}

TEST(HostileIo, ImuFwStopsOnSigtermWhateverThePeerDoes) {
  SKIP_IF_EMULATED();
  const std::string bus = fwtest::unique_bus("noread-term");
  fwtest::FwProcess fw({"--bus", bus, "--quiet", "--status-period", "1"});
  ASSERT_TRUE(fwtest::wait_listening(bus, 5.0));
  imu::hal::CanSocket peer;
  ASSERT_EQ(peer.open(bus.c_str()), imu::hal::IoStatus::kOk);
  flood_without_reading(peer, 3.0);
  fw.signal(SIGTERM);
  ASSERT_TRUE(fw.wait(3.0)) << "imu-fw still running 3 s after SIGTERM";
  std::printf("imu-fw ended %.2f s after SIGTERM\n", fw.elapsed_s());
  EXPECT_LT(fw.elapsed_s(), 1.5);
}

TEST(HostileIo, ImuFwDropsAPeerThatDoesNotRead) {
  SKIP_IF_EMULATED();
  const std::string bus = fwtest::unique_bus("noread-drop");
  fwtest::FwProcess fw({"--bus", bus, "--status-period", "1", "--peer-timeout-s", "2",
                        "--exit-idle-s", "1"});
  ASSERT_TRUE(fwtest::wait_listening(bus, 5.0));
  imu::hal::CanSocket peer;
  ASSERT_EQ(peer.open(bus.c_str()), imu::hal::IoStatus::kOk);
  flood_without_reading(peer, 25.0);
  if (!fw.wait(40.0)) {
    fw.signal(SIGTERM);  // for its final line (the counters) in the failure message
    (void)fw.wait(5.0);
    FAIL() << "imu-fw still connected to a peer that never reads: " << fw.out() << fw.err();
  }
  EXPECT_NE(fw.out().find("peers dropped for not reading 1"), std::string::npos)
      << fw.out() << fw.err();
}

}  // namespace

// Helpers shared by the host_sim CLI tests: run imu-sim / imu-fw in-process with captured
// output, temporary folders, and a minimal reader for the numbers in the JSON reports.
#ifndef IMU_TESTS_SIM_TEST_UTIL_HPP
#define IMU_TESTS_SIM_TEST_UTIL_HPP

#include <gtest/gtest.h>

#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "imu/node/fw_main.hpp"
#include "imu/sim/cli.hpp"

// Tests that need threads or a child process skip under qemu-user (the cross tests: its
// user mode hangs on a second thread here).
#ifdef IMU_EMULATED_TARGET
#define SKIP_IF_EMULATED() GTEST_SKIP() << "needs threads or exec, unavailable under qemu-user here"
#else
#define SKIP_IF_EMULATED() (void)0
#endif

namespace simtest {

struct CliResult {
  int status;
  std::string out;
  std::string err;
};

/// Run imu-sim (fw = false) or imu-fw (fw = true) in this process; args exclude argv[0].
inline CliResult run(const std::vector<std::string>& args, bool fw = false) {
  std::vector<std::string> store = args;
  store.insert(store.begin(), fw ? "imu-fw" : "imu-sim");
  std::vector<char*> argv;
  argv.reserve(store.size() + 1);
  for (std::string& s : store) {
    argv.push_back(s.data());
  }
  argv.push_back(nullptr);
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const int st = fw ? imu::node::fw_main(static_cast<int>(store.size()), argv.data())
                    : imu::sim::cli_main(static_cast<int>(store.size()), argv.data());
  CliResult r{st, testing::internal::GetCapturedStdout(), testing::internal::GetCapturedStderr()};
  return r;
}

inline std::size_t count_lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) {
    n += c == '\n' ? 1U : 0U;
  }
  return n;
}

/// A fresh folder under /tmp, removed at destruction.
class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/imu-sim-test-XXXXXX";
    const char* p = mkdtemp(tmpl);
    path_ = p != nullptr ? p : "/tmp";
  }
  ~TempDir() {
    const std::string cmd = "rm -rf '" + path_ + "'";
    (void)std::system(cmd.c_str());
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

inline std::string read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

struct JsonAdev {
  double tau_s, adev, edf, ci_lo, ci_hi;
};

/// The objects of the list under key "adev" (the writer puts one object per line).
inline std::vector<JsonAdev> json_adev(const std::string& json) {
  std::vector<JsonAdev> out;
  const std::size_t start = json.find("\"adev\": [");
  if (start == std::string::npos) {
    return out;
  }
  const std::size_t end = json.find(']', start);
  std::istringstream in(json.substr(start, end - start));
  std::string line;
  while (std::getline(in, line)) {
    JsonAdev a{};
    if (std::sscanf(line.c_str(),
                    " {\"tau_s\": %lf, \"adev\": %lf, \"edf\": %lf, \"ci_lo\": %lf, \"ci_hi\": %lf",
                    &a.tau_s, &a.adev, &a.edf, &a.ci_lo, &a.ci_hi) == 5) {
      out.push_back(a);
    }
  }
  return out;
}

/// The number after "key": inside the object named `group` (first occurrence); NaN if absent.
inline double json_number_in(const std::string& json, const std::string& group,
                             const std::string& key) {
  std::size_t g = json.find("\"" + group + "\"");
  if (g == std::string::npos) {
    return std::nan("");
  }
  const std::size_t k = json.find("\"" + key + "\": ", g);
  if (k == std::string::npos) {
    return std::nan("");
  }
  return std::strtod(json.c_str() + k + key.size() + 4, nullptr);
}

}  // namespace simtest

#endif  // IMU_TESTS_SIM_TEST_UTIL_HPP

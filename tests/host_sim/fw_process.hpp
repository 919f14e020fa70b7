// imu-fw as a separate process for the tests that need one (test_fw_peer, test_hostile_io):
// start it, wait for its exit with a bound, read what it printed; a loopback peer in the test.
#ifndef IMU_TESTS_FW_PROCESS_HPP
#define IMU_TESTS_FW_PROCESS_HPP

#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/hal/codec.hpp"
#include "imu/hal/linux/can_socket.hpp"
#include "sim_test_util.hpp"

// Under qemu-user (the aarch64 cross run) an exec of another aarch64 binary hangs or fails, as
// for test_cli.cpp: the tests that use this skip there (SKIP_IF_EMULATED) and run natively.
namespace fwtest {

inline double now_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

inline std::string unique_bus(const char* tag) {
  return "loopback:fwpeer-" + std::to_string(getpid()) + "-" + tag;
}

/// Wait until some process listens on the loopback name (imu-fw, started first, as in the demo
/// and the README's external mode): /proc/net/unix lists abstract names with a leading '@'.
inline bool wait_listening(const std::string& bus, double limit_s) {
  const std::string needle = "@imu-can-loopback:" + bus.substr(9);  // after "loopback:"
  const double t0 = now_s();
  while (now_s() - t0 < limit_s) {
    if (simtest::read_text("/proc/net/unix").find(needle) != std::string::npos) {
      return true;
    }
    usleep(10000);
  }
  return false;
}

/// imu-fw (or another program) started as a process, stdout and stderr to files in a
/// temporary folder.
class FwProcess {
 public:
  explicit FwProcess(std::vector<std::string> args, const std::string& program = IMU_FW_PATH) {
    args.insert(args.begin(), program);
    const std::string out = dir_.file("out.txt");
    const std::string err = dir_.file("err.txt");
    pid_ = fork();
    if (pid_ == 0) {
      const int fo = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      const int fe = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      dup2(fo, 1);
      dup2(fe, 2);
      std::vector<char*> av;
      av.reserve(args.size() + 1);
      for (std::string& s : args) {
        av.push_back(s.data());
      }
      av.push_back(nullptr);
      execv(av[0], av.data());
      _exit(127);
    }
    t0_ = now_s();
  }
  ~FwProcess() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      (void)waitpid(pid_, nullptr, 0);
    }
  }
  FwProcess(const FwProcess&) = delete;
  FwProcess& operator=(const FwProcess&) = delete;

  /// Wait at most limit_s for the exit; false (and the process killed) if it is still running.
  bool wait(double limit_s) {
    while (now_s() - t0_ < limit_s) {
      int st = 0;
      if (waitpid(pid_, &st, WNOHANG) == pid_) {
        reaped_ = true;
        elapsed_s_ = now_s() - t0_;
        status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        return true;
      }
      usleep(20000);
    }
    return false;
  }
  /// Send a signal; the time of wait()'s exit is counted from here on.
  void signal(int sig) {
    kill(pid_, sig);
    t0_ = now_s();
  }
  [[nodiscard]] int status() const { return status_; }
  [[nodiscard]] double elapsed_s() const { return elapsed_s_; }
  [[nodiscard]] std::string err() const { return simtest::read_text(dir_.file("err.txt")); }
  [[nodiscard]] std::string out() const { return simtest::read_text(dir_.file("out.txt")); }

 private:
  simtest::TempDir dir_;
  pid_t pid_ = -1;
  bool reaped_ = false;
  int status_ = -1;
  double elapsed_s_ = 0.0;
  double t0_ = 0.0;
};

/// The peer: a config and `n` samples on the same loopback name.
inline void send_stream(imu::hal::CanSocket& peer, std::uint32_t n) {
  imu::hal::EncodedFrames fr{};
  imu::hal::ConfigRecord c{};
  c.cfg_id = 1;
  c.rate_hz = 100.0;
  for (double& l : c.lsb) {
    l = 1e-3;
  }
  imu::hal::encode(c, imu::hal::Layout::kFd, 0, fr);
  ASSERT_EQ(peer.send(fr.frame[0], 2000), imu::hal::IoStatus::kOk);
  for (std::uint32_t k = 0; k < n; ++k) {
    imu::hal::SampleRecord s{};
    s.seq = k;
    s.cfg_id = 1;
    for (std::size_t ch = 0; ch < 6; ++ch) {
      s.counts[ch] = static_cast<std::int32_t>((k * 7 + ch * 3) % 11) - 5;
    }
    imu::hal::encode(s, imu::hal::Layout::kFd, fr);
    ASSERT_EQ(peer.send(fr.frame[0], 2000), imu::hal::IoStatus::kOk);
  }
}

}  // namespace fwtest

#endif  // IMU_TESTS_FW_PROCESS_HPP

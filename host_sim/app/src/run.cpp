// imu-sim run: the sensor emulator, the telemetry receiver and the report (see README.md).
//
// Data flow: MAT-file -> counts -> SampleRecord frames -> bus -> firmware node (in-process
// thread, imu-fw child process, or an external imu-fw) -> telemetry frames -> bus -> here.
// One thread sends and receives: while a send meets back-pressure it polls for input and
// drains telemetry, so neither side can block the other. A credit window (samples sent minus
// samples the node reports processed) keeps a fast sender from overrunning a node on a bus
// without back-pressure (SocketCAN).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <bitset>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common.hpp"
#include "data.hpp"
#include "imu/edf.hpp"
#include "imu/hal/can_socket.hpp"
#include "imu/hal/gpio_line.hpp"
#include "imu/node/node.hpp"
#include "imu/node/node_loop.hpp"
#include "report.hpp"
#include "run.hpp"

namespace imu::sim {
namespace {

constexpr const char* kCmd = "imu-sim run";

/// Telemetry received from the node.
struct Telemetry {
  hal::Receiver<8> rx;
  bool have_stats = false;
  hal::StatsRecord stats{};
  std::uint64_t stats_records = 0;
  bool have_bias = false;
  hal::BiasRecord bias{};
  bool have_monitor = false;
  hal::MonitorRecord monitor{};
  hal::RejectsRecord rejects{};
  hal::AdevRecord curve[kNumChannels][node::kMaxAdevPoints] = {};
  std::uint8_t n_points[kNumChannels] = {};
  std::bitset<node::kMaxAdevPoints> got[kNumChannels];
  std::uint64_t adev_records = 0;
  std::uint64_t bad_adev_records = 0;
  std::uint64_t target = ~std::uint64_t{0};  // samples sent, once all are sent
  bool armed = false;
  bool final_done = false;

  [[nodiscard]] std::uint64_t processed() const {
    return have_stats ? std::uint64_t{stats.samples} + stats.missing : 0;
  }

  void on_event(const hal::RxEvent& e) {
    switch (e.type) {
      case hal::RxEvent::Type::kStats:
        stats = e.rec.stats;
        have_stats = true;
        ++stats_records;
        if (!armed && processed() >= target) {
          armed = true;
          for (auto& g : got) {
            g.reset();
          }
        }
        break;
      case hal::RxEvent::Type::kBias:
        bias = e.rec.bias;
        have_bias = true;
        break;
      case hal::RxEvent::Type::kMonitor:
        monitor = e.rec.monitor;
        have_monitor = true;
        break;
      case hal::RxEvent::Type::kAdev: {
        const hal::AdevRecord& a = e.rec.adev;
        ++adev_records;
        if (a.channel >= kNumChannels || a.n_points == 0 || a.n_points > node::kMaxAdevPoints ||
            a.index >= a.n_points) {
          ++bad_adev_records;
          break;
        }
        if (n_points[a.channel] != a.n_points) {
          n_points[a.channel] = a.n_points;
          got[a.channel].reset();
        }
        curve[a.channel][a.index] = a;
        got[a.channel].set(a.index);
        if (armed && !final_done) {
          bool all = true;
          for (std::size_t c = 0; c < kNumChannels; ++c) {
            all = all && n_points[c] > 0 && got[c].count() == n_points[c];
          }
          final_done = all;
        }
        break;
      }
      case hal::RxEvent::Type::kRejects:
        rejects = e.rec.rejects;
        break;
      case hal::RxEvent::Type::kSample:
      case hal::RxEvent::Type::kMissing:
      case hal::RxEvent::Type::kConfig:
        break;  // samples of another sender on a shared bus: not ours
    }
  }
};

class Link {
 public:
  Link(hal::CanSocket& sock, Telemetry& tel) : sock_(sock), tel_(tel) {}

  /// Take every frame waiting (no wait).
  void drain() {
    for (;;) {
      std::size_t n = 0;
      const hal::IoStatus st = sock_.receive(batch_, hal::CanSocket::kMaxBatch, n, 0);
      if (st != hal::IoStatus::kOk) {
        if (st == hal::IoStatus::kLinkDown) {
          link_down_ = true;
        }
        return;
      }
      for (std::size_t i = 0; i < n; ++i) {
        (void)tel_.rx.push_drain(batch_[i].frame, batch_[i].nbytes, batch_[i].rx_time_ns,
                                 [this](const hal::RxEvent& e) { tel_.on_event(e); });
      }
    }
  }

  /// Wait up to timeout_ms for input (or for room to send), then drain.
  void service(int timeout_ms, bool want_out) {
    pollfd p{sock_.poll_fd(), static_cast<short>(POLLIN | (want_out ? POLLOUT : 0)), 0};
    if (p.fd >= 0) {
      (void)poll(&p, 1, timeout_ms);
    }
    drain();
  }

  /// Send one frame; on back-pressure keep draining telemetry until it goes. The first send
  /// may wait for a loopback peer (first_timeout_ms).
  bool send(const hal::CanFrame& f, int first_timeout_ms, std::string& err) {
    int timeout = first_timeout_ms;
    for (int attempt = 0;; ++attempt) {
      const hal::IoStatus st = sock_.send(f, timeout);
      if (st == hal::IoStatus::kOk) {
        ++frames_;
        return true;
      }
      if (st == hal::IoStatus::kWouldBlock) {
        ++backpressure_waits_;
        service(20, true);
        timeout = 0;
        continue;
      }
      err = std::string(hal::to_string(st)) + ": " + sock_.error();
      return false;
    }
  }

  [[nodiscard]] std::uint64_t frames() const { return frames_; }
  [[nodiscard]] std::uint64_t backpressure_waits() const { return backpressure_waits_; }
  [[nodiscard]] bool link_down() const { return link_down_; }

 private:
  hal::CanSocket& sock_;
  Telemetry& tel_;
  hal::RxFrame batch_[hal::CanSocket::kMaxBatch];
  std::uint64_t frames_ = 0;
  std::uint64_t backpressure_waits_ = 0;
  bool link_down_ = false;
};

/// The firmware node in a thread of this process.
struct InprocNode {
  hal::CanSocket sock;
  hal::MemoryLine static_line;
  hal::MemoryLine alarm_line;
  node::Node node;
  std::atomic<bool> stop{false};
  std::atomic<bool> done{false};
  node::LoopEnd end = node::LoopEnd::kStopped;
  std::thread th;

  void start() {
    static_line.set(true);
    th = std::thread([this] {
      node::LoopOptions lo;
      lo.idle_ms = 100;
      lo.exit_on_link_down = true;
      lo.stop = &stop;
      end = node::run_node_loop(node, sock, lo);
      done.store(true);
    });
  }
  void join() {
    if (th.joinable()) {
      th.join();
    }
  }
};

std::string self_dir() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) {
    return ".";
  }
  buf[n] = '\0';
  std::string p = buf;
  const std::size_t slash = p.rfind('/');
  return slash == std::string::npos ? "." : p.substr(0, slash);
}

double edf_of(std::uint32_t af, std::uint64_t n_terms) {
  // Recover m and the stride of OnlineAdev<8, 22> from af = m * 2^level (m in 1..8 at level 0,
  // 5..8 above), then the same Greenhall EDF the estimator computes (white FM assumed).
  std::uint32_t m = af;
  while (m > 8) {
    m >>= 1;
  }
  return edf_greenhall(0, 2, static_cast<double>(af), static_cast<double>(m),
                       static_cast<double>(n_terms));
}

void print_progress(double t0, std::uint64_t sent, std::uint64_t total,
                    const Telemetry& tel, bool tty, bool final_line) {
  const double dt = now_s() - t0;
  const double rate = dt > 0 ? static_cast<double>(sent) / dt : 0.0;
  const std::uint64_t missing = tel.have_stats ? tel.stats.missing : 0;
  std::fprintf(stderr, "%s[run] %llu/%llu samples sent, %.0f samples/s, node processed %llu, "
               "dropped %llu%s",
               tty ? "\r" : "", static_cast<unsigned long long>(sent),
               static_cast<unsigned long long>(total), rate,
               static_cast<unsigned long long>(tel.processed()),
               static_cast<unsigned long long>(missing), tty && !final_line ? "   " : "\n");
  std::fflush(stderr);
}

}  // namespace

int cmd_run(int argc, char** argv) {
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {
      {"--mat", true},     {"--channel", true},   {"--bus", true},       {"--rate", true},
      {"--node", true},    {"--out", true},       {"--json", true},      {"--N", true},
      {"--B", true},       {"--Tp", true},        {"--K", true},         {"--fw", true},
      {"--no-plots", false}, {"--quiet", false},  {"--T-avg", true},     {"--T-int", true},
      {"--sim-windows", true}, {"--seed", true},  {"--timeout", true},   {"--window", true},
      {"--lsb", true},     {"--fs", true},        {"--layout", true},    {"--only-channel", false},
  };
  if (!a.parse(argc, argv, 2, specs, 0, err)) {
    return fail(kCmd, err + " (see imu-sim --help)", 2);
  }
  if (!a.has("--mat")) {
    return fail(kCmd, "--mat FILE is required", 2);
  }
  const std::string path = a.get("--mat");
  const std::string chan_name = a.get("--channel", "acc_z");
  std::size_t chan = 0;
  if (!channel_index(chan_name, chan)) {
    return fail(kCmd, "unknown channel '" + chan_name + "' (acc_x acc_y acc_z gyro_x gyro_y gyro_z)", 2);
  }
  const std::string bus = a.get("--bus", "loopback");
  const bool is_loopback = bus == "loopback" || bus.rfind("loopback:", 0) == 0;
  const std::string rate = a.get("--rate", "max");
  if (rate != "max" && rate != "realtime") {
    return fail(kCmd, "--rate must be max or realtime", 2);
  }
  const std::string node_mode = a.get("--node", is_loopback ? "inproc" : "external");
  if (node_mode != "inproc" && node_mode != "spawn" && node_mode != "external") {
    return fail(kCmd, "--node must be inproc, spawn or external", 2);
  }
  std::string layout_s = a.get("--layout", "auto");
  if (layout_s != "fd" && layout_s != "classic" && layout_s != "auto") {
    return fail(kCmd, "--layout must be auto, fd or classic", 2);
  }
  hal::Layout layout = layout_s == "classic" ? hal::Layout::kClassic : hal::Layout::kFd;
  const std::string out_dir = a.get("--out", "out/run");
  ReportOptions ro;
  ro.out_dir = out_dir;
  ro.json_path = a.get("--json", out_dir + "/report.json");
  ro.plots = !a.has("--no-plots");
  const int given = (a.has("--N") ? 1 : 0) + (a.has("--B") ? 1 : 0) + (a.has("--Tp") ? 1 : 0);
  if (given != 0 && given != 3) {
    return fail(kCmd, "give all of --N, --B, --Tp (the model under test) or none (fit)", 2);
  }
  ro.given_model = given == 3;
  double timeout_s = 30.0;
  // Credit window: on the loopback bus back-pressure already protects the node; on SocketCAN
  // the sender must not get further ahead than the node's socket queue holds (a few hundred
  // frames at the default buffer size).
  const double window_default = is_loopback ? 4096.0 : 256.0;
  double window = window_default;
  double sim_windows = 1000.0;
  double seed = 1.0;
  double lsb_opt = 0.0;
  double fs_opt = 0.0;
  if (!a.number("--N", 0.0, ro.n, err) || !a.number("--B", 0.0, ro.b, err) ||
      !a.number("--Tp", 0.0, ro.tp_s, err) || !a.number("--K", 0.0, ro.k, err) ||
      !a.number("--T-avg", 10.0, ro.t_avg_s, err) || !a.number("--T-int", 20.0, ro.t_int_s, err) ||
      !a.number("--sim-windows", 1000.0, sim_windows, err) || !a.number("--seed", 2.0, seed, err) ||
      !a.number("--timeout", 30.0, timeout_s, err) || !a.number("--window", window_default, window, err) ||
      !a.number("--lsb", 0.0, lsb_opt, err) || !a.number("--fs", 0.0, fs_opt, err)) {
    return fail(kCmd, err, 2);
  }
  if (!(ro.t_avg_s > 0.0) || !(ro.t_int_s > 0.0) || sim_windows < 1.0 || window < 0.0 ||
      !(timeout_s > 0.0) || seed < 0.0 || lsb_opt < 0.0 || fs_opt < 0.0) {
    return fail(kCmd, "a numeric option is out of range", 2);
  }
  ro.sim_windows = static_cast<std::size_t>(sim_windows);
  ro.seed = static_cast<std::uint64_t>(seed);
  const bool quiet = a.has("--quiet");

  // ---- Data ------------------------------------------------------------------------------
  const double t0 = now_s();
  bool want[kNumChannels];
  bool required[kNumChannels];
  double lsb_over[kNumChannels];
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    want[c] = !a.has("--only-channel") || c == chan;
    required[c] = c == chan;
    lsb_over[c] = c == chan ? lsb_opt : 0.0;
  }
  SensorData sd;
  if (!load_sensor(path, want, required, lsb_over, fs_opt, sd, err)) {
    return fail(kCmd, err);
  }
  std::vector<std::int32_t> counts[kNumChannels];
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    if (sd.ch[c].present) {
      to_counts(sd.ch[c], counts[c]);
    }
  }
  const double t_load = now_s() - t0;
  const std::size_t n = sd.n_samples;
  if (n < 16) {
    return fail(kCmd, path + ": " + std::to_string(n) + " samples: too short for an ADEV (16 or more)");
  }
  if (n > 0xFFFFFFFFULL) {
    return fail(kCmd, path + ": more than 2^32 samples (the sequence number would wrap)");
  }

  // ---- Bus and node ------------------------------------------------------------------------
  hal::CanSocket sock;
  std::unique_ptr<InprocNode> inproc;
  pid_t child = -1;
  std::string bus_used = bus;
  node::NodeConfig nc;
  if (ro.given_model) {
    const std::size_t first = chan < 3 ? 0 : 3;
    for (std::size_t c = first; c < first + 3; ++c) {
      nc.model[c] = node::ChannelModel{ro.n, ro.b, ro.tp_s};
    }
  }
  if (node_mode == "inproc") {
    inproc = std::make_unique<InprocNode>();
    hal::IoStatus st = hal::IoStatus::kOk;
    if (is_loopback) {
      st = hal::CanSocket::open_pair(sock, inproc->sock);
      bus_used = "in-process loopback pair";
    } else {
      st = sock.open(bus.c_str());
      if (st == hal::IoStatus::kOk) {
        st = inproc->sock.open(bus.c_str());
      }
    }
    if (st != hal::IoStatus::kOk) {
      return fail(kCmd, std::string("cannot open bus: ") +
                            (sock.error()[0] != '\0' ? sock.error() : inproc->sock.error()));
    }
    if (layout_s == "auto" && !sock.fd_capable()) {
      layout = hal::Layout::kClassic;  // CAN interface with MTU 16: classic frames only
    }
    nc.layout = layout;
    if (inproc->node.configure(nc, inproc->sock, &inproc->static_line, &inproc->alarm_line) !=
        node::NodeStatus::kOk) {
      return fail(kCmd, "node configuration rejected (model parameters)");
    }
    inproc->start();
  } else {
    if (node_mode == "spawn" && bus == "loopback") {
      bus_used = "loopback:imu-sim-" + std::to_string(getpid());
    }
    if (sock.open(bus_used.c_str()) != hal::IoStatus::kOk) {
      return fail(kCmd, std::string("cannot open bus: ") + sock.error());
    }
    if (layout_s == "auto" && !sock.fd_capable()) {
      layout = hal::Layout::kClassic;  // CAN interface with MTU 16: classic frames only
    }
    layout_s = layout == hal::Layout::kFd ? "fd" : "classic";
    if (node_mode == "spawn") {
      const std::string fw = a.get("--fw", self_dir() + "/imu-fw");
      if (access(fw.c_str(), X_OK) != 0) {
        return fail(kCmd, "imu-fw not found at '" + fw + "' (give --fw PATH)");
      }
      std::string err_dir;
      if (!make_dirs(out_dir, err_dir)) {
        return fail(kCmd, err_dir);
      }
      std::vector<std::string> args = {fw, "--bus", bus_used, "--layout", layout_s};
      if (ro.given_model) {
        const std::string pre = chan < 3 ? "--" : "--gyro-";
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.17g", ro.n);
        args.insert(args.end(), {pre + "N", buf});
        std::snprintf(buf, sizeof buf, "%.17g", ro.b);
        args.insert(args.end(), {pre + "B", buf});
        std::snprintf(buf, sizeof buf, "%.17g", ro.tp_s);
        args.insert(args.end(), {pre + "Tp", buf});
      }
      const std::string log = out_dir + "/imu-fw.log";
      std::fflush(stdout);
      std::fflush(stderr);
      child = fork();
      if (child < 0) {
        return fail(kCmd, std::string("fork: ") + std::strerror(errno));
      }
      if (child == 0) {
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
          dup2(fd, 1);
          dup2(fd, 2);
          ::close(fd);
        }
        std::vector<char*> av;
        av.reserve(args.size() + 1);
        for (std::string& s : args) {
          av.push_back(s.data());
        }
        av.push_back(nullptr);
        execv(av[0], av.data());
        _exit(127);
      }
    }
  }

  // ---- Send --------------------------------------------------------------------------------
  Telemetry tel;
  Link link(sock, tel);
  hal::ConfigRecord cfg{};
  cfg.cfg_id = 1;
  cfg.rate_hz = sd.fs_hz;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    cfg.lsb[c] = sd.ch[c].present ? sd.ch[c].lsb : default_lsb(c);
  }
  hal::EncodedFrames fr{};
  const bool tty = isatty(2) != 0;
  const double t_send0 = now_s();
  double last_progress = t_send0;
  double last_credit = t_send0;
  std::uint64_t last_processed = 0;
  std::uint8_t cfg_tid = 0;
  int status = 0;
  const auto credit = static_cast<std::uint64_t>(window);
  const std::uint64_t period_ns = static_cast<std::uint64_t>(std::llround(1e9 / sd.fs_hz));
  for (std::size_t k = 0; k < n && status == 0; ++k) {
    if (k % 100 == 0) {  // configuration at start and once per 100 samples (1 s at 100 Hz)
      hal::encode(cfg, layout, cfg_tid++, fr);
      for (std::size_t i = 0; i < fr.count && status == 0; ++i) {
        if (!link.send(fr.frame[i], k == 0 ? 10000 : 0, err)) {
          std::string msg = "send on " + bus_used + " failed: ";
          msg += err;
          if (k == 0 && node_mode != "inproc") {
            msg += " (is imu-fw running on this bus?)";
          }
          status = fail(kCmd, msg);
        }
      }
    }
    hal::SampleRecord s{};
    s.seq = static_cast<std::uint32_t>(k);
    s.t_sensor_ns = static_cast<std::uint64_t>(k) * period_ns;
    s.cfg_id = cfg.cfg_id;
    for (std::size_t c = 0; c < kNumChannels; ++c) {
      s.counts[c] = sd.ch[c].present ? counts[c][k] : 0;
    }
    if (rate == "realtime") {
      const double due = t_send0 + static_cast<double>(k) / sd.fs_hz;
      double now = now_s();
      while (now < due) {
        link.service(static_cast<int>(std::ceil((due - now) * 1000.0)), false);
        now = now_s();
      }
    }
    while (credit > 0 && k >= tel.processed() + credit && status == 0) {
      link.service(50, false);
      if (tel.processed() != last_processed) {
        last_processed = tel.processed();
        last_credit = now_s();
      } else if (now_s() - last_credit > 10.0) {
        status = fail(kCmd, "no progress report from the firmware node for 10 s on " + bus_used +
                                " (is imu-fw running? --window 0 disables the credit window)");
      }
    }
    if (status != 0) {
      break;
    }
    hal::encode(s, layout, fr);
    for (std::size_t i = 0; i < fr.count && status == 0; ++i) {
      if (!link.send(fr.frame[i], 0, err)) {
        std::string msg = "send on " + bus_used + " failed: ";
        msg += err;
        status = fail(kCmd, msg);
      }
    }
    if ((k & 63U) == 63U) {
      link.drain();
      const double now = now_s();
      if (!quiet && now - t_send0 > 2.0 && now - last_progress >= 1.0) {
        last_progress = now;
        print_progress(t_send0, k + 1, n, tel, tty, false);
      }
    }
  }
  tel.target = n;
  if (tel.processed() >= n) {
    tel.armed = true;  // already reported: the next complete set is the final one
    for (auto& g : tel.got) {
      g.reset();
    }
  }
  const double t_sent = now_s() - t_send0;

  // ---- Wait for the final telemetry ---------------------------------------------------------
  const double wait_end = now_s() + timeout_s;
  while (status == 0 && !tel.final_done && now_s() < wait_end && !link.link_down()) {
    link.service(50, false);
    if (inproc && inproc->done.load()) {
      link.drain();
      break;
    }
  }
  const double t_total = now_s() - t_send0;
  if (!quiet && t_total > 2.0) {
    print_progress(t_send0, n, n, tel, tty, true);
  }
  sock.close();  // the node sees the end of the stream (loopback)
  if (inproc) {
    inproc->stop.store(true);
    inproc->join();
  }
  int child_status = 0;
  if (child > 0) {
    const double kill_at = now_s() + 5.0;
    pid_t w = 0;
    while ((w = waitpid(child, &child_status, WNOHANG)) == 0 && now_s() < kill_at) {
      usleep(20000);
    }
    if (w == 0) {
      kill(child, SIGTERM);
      (void)waitpid(child, &child_status, 0);
    }
  }
  if (status != 0) {
    return status;
  }
  if (!tel.final_done) {
    return fail(kCmd, "no final telemetry from the firmware node within " +
                          std::to_string(static_cast<int>(timeout_s)) + " s on " + bus_used +
                          " (processed " + std::to_string(tel.processed()) + " of " +
                          std::to_string(n) + " samples)");
  }

  // ---- Report ------------------------------------------------------------------------------
  ReportInput ri;
  ri.source = path;
  ri.channel = chan_name;
  ri.channel_index = chan;
  ri.fs_hz = sd.fs_hz;
  ri.lsb = sd.ch[chan].lsb;
  ri.data = &sd.ch[chan].values;
  ri.adev_origin = "online ADEV of the firmware node, received as telemetry over " + bus_used;
  const double ts_s = 1.0 / sd.fs_hz;
  for (std::size_t i = 0; i < tel.n_points[chan]; ++i) {
    const hal::AdevRecord& r = tel.curve[chan][i];
    const auto af = static_cast<std::uint32_t>(std::lround(static_cast<double>(r.tau_s) / ts_s));
    AdevRow row;
    row.tau_s = static_cast<double>(af) * ts_s;
    row.adev = static_cast<double>(r.adev);
    row.ci_lo = static_cast<double>(r.ci_lo);
    row.ci_hi = static_cast<double>(r.ci_hi);
    row.n_terms = r.n_terms;
    row.edf = edf_of(af, r.n_terms);
    ri.adev.push_back(row);
  }
  const hal::RxStats& rs = tel.rx.stats();
  const hal::LinkStats& ls = sock.stats();
  ri.stats.push_back(StatGroup{
      "sender (imu-sim emulator)",
      {{"samples", static_cast<double>(n)},
       {"frames", static_cast<double>(link.frames())},
       {"backpressure_waits", static_cast<double>(link.backpressure_waits())},
       {"tx_link_down", static_cast<double>(ls.tx_link_down)},
       {"sys_errors", static_cast<double>(ls.sys_errors)}}});
  const hal::StatsRecord& ns = tel.stats;
  auto d = [](std::uint64_t v) { return static_cast<double>(v); };
  ri.stats.push_back(StatGroup{"firmware node (its StatsRecord)",
                               {{"frames", d(ns.frames)},
                                {"samples", d(ns.samples)},
                                {"missing", d(ns.missing)},
                                {"crc_errors", d(ns.crc_errors)},
                                {"bad_mtu_or_dlc", d(ns.bad_mtu_or_dlc)},
                                {"unknown_id", d(ns.unknown_id)},
                                {"duplicates", d(ns.duplicates)},
                                {"truncated", d(ns.truncated)},
                                {"error_frames", d(ns.error_frames)},
                                {"kernel_drops", d(ns.kernel_drops)},
                                {"lost", d(n) - d(ns.samples)}}});
  const hal::RejectsRecord& nr = tel.rejects;
  ri.stats.push_back(StatGroup{"firmware node refusals (its RejectsRecord)",
                               {{"bad_config", d(nr.bad_config)},
                                {"config_same_values", d(nr.config_same_values)},
                                {"model_rejected", d(nr.model_rejected)},
                                {"samples_before_config", d(nr.samples_before_config)},
                                {"cfg_mismatch", d(nr.cfg_mismatch)},
                                {"late", d(nr.late)},
                                {"resyncs", d(nr.resyncs)},
                                {"remote_frames", d(nr.remote_frames)},
                                {"bad_fragment", d(nr.bad_fragment)},
                                {"orphan_fragments", d(nr.orphan_fragments)},
                                {"busy", d(nr.busy)},
                                {"telemetry_failures", d(nr.telemetry_failures)},
                                {"gpio_errors", d(nr.gpio_errors)},
                                {"peer_refused", d(nr.peer_refused)},
                                {"bad_record", d(nr.bad_record)}}});
  ri.stats.push_back(StatGroup{
      "telemetry receiver (imu-sim)",
      {{"frames", static_cast<double>(rs.frames)},
       {"adev_records", static_cast<double>(tel.adev_records)},
       {"stats_records", static_cast<double>(tel.stats_records)},
       {"crc_errors", static_cast<double>(rs.crc_errors)},
       {"bad_mtu", static_cast<double>(rs.bad_mtu)},
       {"bad_dlc", static_cast<double>(rs.bad_dlc)},
       {"unknown_id", static_cast<double>(rs.unknown_id)},
       {"kernel_drops", static_cast<double>(ls.kernel_drops)}}});
  if (inproc) {
    const node::NodeStats& st = inproc->node.stats();
    ri.stats.push_back(StatGroup{
        "firmware node (in-process counters)",
        {{"telemetry_frames", static_cast<double>(st.telemetry_frames)},
         {"telemetry_failures", static_cast<double>(st.telemetry_failures)},
         {"adev_sets", static_cast<double>(st.adev_sets)},
         {"status_sets", static_cast<double>(st.status_sets)},
         {"alarm_changes", static_cast<double>(st.alarm_changes)},
         {"saturated", static_cast<double>(st.saturated)}}});
  }
  if (tel.have_bias) {
    ri.stats.push_back(StatGroup{
        "bias filter (last BiasRecord, channel " + chan_name + ")",
        {{"bias", static_cast<double>(tel.bias.bias[chan])},
         {"std", std::sqrt(static_cast<double>(tel.bias.var[chan]))},
         {"static_flag", static_cast<double>(tel.bias.flags & hal::kBiasStatic)}}});
  }
  if (tel.have_monitor) {
    ri.stats.push_back(StatGroup{"residual monitors (last MonitorRecord)",
                                 {{"nis_mean", static_cast<double>(tel.monitor.nis_mean)},
                                  {"whiteness_ratio", static_cast<double>(tel.monitor.whiteness)},
                                  {"flags", static_cast<double>(tel.monitor.flags)},
                                  {"cusum_mask", static_cast<double>(tel.monitor.cusum_mask)}}});
  }
  ri.timing_s = {{"read MAT-file + quantize", t_load},
                 {"send all samples (" + rate + ")", t_sent},
                 {"until final telemetry", t_total}};
  if (tel.have_monitor && tel.monitor.flags != 0) {
    // Say what the raw flags mean: a user reading "flags 5" should not have to open codec.hpp.
    std::string chans;
    for (std::size_t c = 0; c < kNumChannels; ++c) {
      if ((tel.monitor.cusum_mask & (1U << c)) != 0U) {
        chans += (chans.empty() ? "" : ", ") + std::string(kChannelNames[c]);
      }
    }
    std::string what;
    if ((tel.monitor.flags & hal::kMonitorCusum) != 0U) {
      what += "the innovation CUSUM alarm (" + (chans.empty() ? std::string("-") : chans) + ")";
    }
    if ((tel.monitor.flags & hal::kMonitorWhiteness) != 0U) {
      what += std::string(what.empty() ? "" : ", ") + "a failed whiteness check";
    }
    if ((tel.monitor.flags & hal::kMonitorAlarmLine) != 0U) {
      what += std::string(what.empty() ? "" : "; ") + "the alarm line is set";
    }
    ri.notes.push_back(
        "residual monitors: " + what + ". The node's bias filter is the seed's first-order "
        "model (white + one GM); its innovations drift when the data hold an effect that model "
        "lacks (a rate random walk, a step, a ramp). `imu-sim analyze FILE.mat --channel " +
        chan_name + "` names it.");
  }
  if (sd.ch[chan].off_grid > 0) {
    ri.notes.push_back(std::to_string(sd.ch[chan].off_grid) +
                       " samples are not integer multiples of the LSB (quantised to it)");
  }
  if (sd.ch[chan].saturated > 0) {
    ri.notes.push_back(std::to_string(sd.ch[chan].saturated) + " samples saturated int32 counts");
  }
  if (child > 0) {
    ri.notes.push_back("imu-fw ran as a separate process; its output is in " + out_dir +
                       "/imu-fw.log (exit status " +
                       std::to_string(WIFEXITED(child_status) ? WEXITSTATUS(child_status) : -1) +
                       ")");
  }
  std::string text;
  if (!write_report(ri, ro, text, err)) {
    return fail(kCmd, err);
  }
  std::fputs(text.c_str(), stdout);
  std::printf("\nreport folder: %s\n", out_dir.c_str());
  return 0;
}

}  // namespace imu::sim

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

#include <algorithm>
#include <array>
#include <atomic>
#include <bitset>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common.hpp"
#include "data.hpp"
#include "imu/analyze/node_tuning.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/edf.hpp"
#include "imu/hal/linux/can_socket.hpp"
#include "imu/hal/sim/memory_line.hpp"
#include "imu/cli/row_source.hpp"
#include "imu/cli/rosbag.hpp"
#include "imu/cli/text_input.hpp"
#include "imu/mat/mat_reader.hpp"
#include "imu/mat/mat_writer.hpp"
#include "imu/node/node.hpp"
#include "imu/node/node_loop.hpp"
#include "model_json.hpp"
#include "report.hpp"
#include "run.hpp"

namespace imu::sim {
namespace {

constexpr const char* kCmd = "imu-sim run";

/// Telemetry received from the node.
// Level shifts listed per channel in the report (the node's count goes on beyond).
constexpr std::size_t kMaxListedSteps = 64;

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
  hal::ModelRecord model_echo[hal::kChannels] = {};  // what the node runs, per channel
  bool have_model_echo[hal::kChannels] = {};
  hal::ModelSignalsRecord signals_echo[hal::kChannels] = {};  // its deterministic terms
  bool have_signals_echo[hal::kChannels] = {};
  hal::ChannelMonitorRecord chan_mon[hal::kChannels] = {};  // each channel's monitors
  bool have_chan_mon[hal::kChannels] = {};
  // Each detected level shift's first sample, as the per-second records show them (two within
  // one record period are seen as one: the count says how many there were).
  std::vector<std::int64_t> step_samples[hal::kChannels];
  hal::AdevRecord curve[kNumChannels][node::kMaxAdevPoints] = {};
  std::uint8_t n_points[kNumChannels] = {};
  std::bitset<node::kMaxAdevPoints> got[kNumChannels];
  std::uint64_t adev_records = 0;
  std::uint64_t bad_adev_records = 0;
  std::uint64_t target = ~std::uint64_t{0};  // samples sent, once all are sent
  bool armed = false;
  bool final_done = false;
  // Each ADEV set on its own (reset at the end of every set): a set received whole, and the
  // samples the node had processed by its StatsRecord just before it. A node whose last sample
  // falls on its ADEV period sends its final set as it processes that sample, and nothing at
  // idle (no sample since): that set is the final one, whether it arrives before the sender
  // knows it has sent the last sample, or while the check below re-arms.
  std::bitset<node::kMaxAdevPoints> set_got[kNumChannels];
  std::uint64_t whole_set_processed = 0;

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
        // A point no estimator can give (a hostile or broken node): counted, never plotted.
        const bool finite = std::isfinite(a.tau_s) && std::isfinite(a.adev) &&
                            std::isfinite(a.ci_lo) && std::isfinite(a.ci_hi);
        const bool possible = finite && a.tau_s > 0.0F && a.adev >= 0.0F && a.ci_lo >= 0.0F &&
                              a.ci_lo <= a.ci_hi;
        if (a.channel >= kNumChannels || a.n_points == 0 || a.n_points > node::kMaxAdevPoints ||
            a.index >= a.n_points || !possible) {
          ++bad_adev_records;
          break;
        }
        if (n_points[a.channel] != a.n_points) {
          n_points[a.channel] = a.n_points;
          got[a.channel].reset();
        }
        curve[a.channel][a.index] = a;
        got[a.channel].set(a.index);
        set_got[a.channel].set(a.index);
        if (a.channel + 1U == kNumChannels && a.index + 1U == a.n_points) {  // a set's end
          bool whole = true;
          for (std::size_t c = 0; c < kNumChannels; ++c) {
            whole = whole && n_points[c] > 0 && set_got[c].count() == n_points[c];
            set_got[c].reset();
          }
          whole_set_processed = whole ? processed() : whole_set_processed;
          final_done = final_done || (whole && processed() >= target);
        }
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
      case hal::RxEvent::Type::kModelEcho:
        model_echo[e.rec.model.channel] = e.rec.model;  // channel < 6: checked by the receiver
        have_model_echo[e.rec.model.channel] = true;
        break;
      case hal::RxEvent::Type::kChannelMonitor: {
        const hal::ChannelMonitorRecord& cm = e.rec.channel_monitor;
        if (cm.cusum_detections > chan_mon[cm.channel].cusum_detections &&
            step_samples[cm.channel].size() < kMaxListedSteps) {
          // The record's last sample (seq) is its last update (updates): the step's first
          // sample is that many updates back from it, after update cusum_step_update.
          step_samples[cm.channel].push_back(static_cast<std::int64_t>(cm.seq) -
                                             static_cast<std::int64_t>(cm.updates) +
                                             static_cast<std::int64_t>(cm.cusum_step_update) + 1);
        }
        chan_mon[cm.channel] = cm;  // channel < 6: checked by the receiver
        have_chan_mon[cm.channel] = true;
        break;
      }
      case hal::RxEvent::Type::kModelSignalsEcho:
        signals_echo[e.rec.signals.channel] = e.rec.signals;  // channel < 6: the receiver's
        have_signals_echo[e.rec.signals.channel] =
            (e.rec.signals.flags & hal::kModelPushed) != 0U;
        break;
      case hal::RxEvent::Type::kModel:
      case hal::RxEvent::Type::kSample:
      case hal::RxEvent::Type::kMissing:
      case hal::RxEvent::Type::kConfig:
      case hal::RxEvent::Type::kModelSignals:
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
  InprocNode() = default;
  InprocNode(const InprocNode&) = delete;
  InprocNode& operator=(const InprocNode&) = delete;
  InprocNode(InprocNode&&) = delete;
  InprocNode& operator=(InprocNode&&) = delete;
  /// An early return (or an exception) must not leave a joinable thread: std::terminate.
  ~InprocNode() {
    stop.store(true);
    join();
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

/// What `run` was asked to do: the options, range-checked.
struct RunOptions {
  bool help = false;
  std::string path;
  std::string source;  ///< the input as given (path: the MAT-file a text input became)
  std::string input_note;  ///< how a text input became that MAT-file
  std::string chan_name;
  std::size_t chan = 0;
  ChannelVars vars;  // a variable other than acc_x..gyro_z in the slot `chan` (if renamed)
  std::string bus;
  bool is_loopback = false;
  std::string rate;
  std::string node_mode;
  std::string layout_s;
  hal::Layout layout = hal::Layout::kFd;
  std::string out_dir;
  std::string fw;
  ReportOptions ro;
  double timeout_s = 30.0;
  std::uint64_t window = 0;
  double lsb_opt = 0.0;
  double fs_opt = 0.0;
  bool quiet = false;
  bool only_channel = false;
  bool renamed = false;  // `vars` is used
  std::string model_path;       ///< --model: analysis JSON whose model_after is pushed
  hal::ModelRecord model[kNumChannels] = {};  ///< read from model_path, per channel slot
  bool pushed[kNumChannels] = {};             ///< model[c] is sent
  /// model_after's deterministic terms, sent before model[c] when has_signals[c]
  hal::ModelSignalsRecord signals[kNumChannels] = {};
  bool has_signals[kNumChannels] = {};
  bool push_model = false;
  bool model_as_is = false;  ///< --model-as-is: push model_after untuned
};

// Work limits of the covariance check: simulated windows, and samples simulated in all.
constexpr std::uint64_t kMaxSimWindows = 100000;
constexpr double kMaxSimSamples = 2e8;

// The enumerated options and the file (positional, or --mat as an alias).
bool parse_run_names(const Args& a, RunOptions& o, std::string& err) {
  if (a.has("--mat") && !a.positional().empty()) {
    err = "FILE given twice ('" + a.positional()[0] + "' and --mat " + a.get("--mat") + ")";
    return false;
  }
  o.path = a.positional().empty() ? a.get("--mat") : a.positional()[0];
  if (o.path.empty()) {
    err = "a MAT-file is required: imu-sim run FILE";
    return false;
  }
  o.chan_name = a.get("--channel", "acc_z");
  if (!channel_slot(o.chan_name, o.chan, o.vars, o.renamed, err)) {
    return false;
  }
  o.bus = a.get("--bus", "loopback");
  o.is_loopback = o.bus == "loopback" || o.bus.rfind("loopback:", 0) == 0;
  o.rate = a.get("--rate", "max");
  o.node_mode = a.get("--node", o.is_loopback ? "inproc" : "external");
  o.layout_s = a.get("--layout", "auto");
  if (o.rate != "max" && o.rate != "realtime") {
    err = "--rate must be max or realtime";
  } else if (o.node_mode != "inproc" && o.node_mode != "spawn" && o.node_mode != "external") {
    err = "--node must be inproc, spawn or external";
  } else if (o.layout_s != "fd" && o.layout_s != "classic" && o.layout_s != "auto") {
    err = "--layout must be auto, fd or classic";
  }
  o.layout = o.layout_s == "classic" ? hal::Layout::kClassic : hal::Layout::kFd;
  o.out_dir = a.get("--out", "out/run");
  if (err.empty() && o.out_dir.empty()) {
    err = "--out: empty output folder";
  }
  o.fw = a.get("--fw", "");
  o.quiet = a.has("--quiet");
  o.only_channel = a.has("--only-channel");
  o.model_path = a.get("--model", "");
  o.push_model = !o.model_path.empty();
  o.model_as_is = a.has("--model-as-is");
  if (err.empty() && o.model_as_is && !o.push_model) {
    err = "--model-as-is needs --model";
  }
  return err.empty();
}

// The numeric options, each in its range before it becomes a size, a count or an integer.
bool parse_run_numbers(const Args& a, RunOptions& o, std::string& err) {
  ReportOptions& ro = o.ro;
  ro.out_dir = o.out_dir;
  ro.json_path = a.get("--json", o.out_dir + "/report.json");
  ro.plots = !a.has("--no-plots");
  const int given = (a.has("--N") ? 1 : 0) + (a.has("--B") ? 1 : 0) + (a.has("--Tp") ? 1 : 0);
  if (given != 0 && given != 3) {
    err = "give all of --N, --B, --Tp (the model under test) or none (fit)";
    return false;
  }
  ro.given_model = given == 3;
  // Credit window: on the loopback bus back-pressure already protects the node; on SocketCAN
  // the sender must not get further ahead than the node's socket queue holds (a few hundred
  // frames at the default buffer size).
  const std::uint64_t window_default = o.is_loopback ? 4096 : 256;
  std::uint64_t sim_windows = 0;
  if (!a.number("--N", 0.0, 1e-12, 1e3, ro.n, err) || !a.number("--B", 0.0, 1e-12, 1e3, ro.b, err) ||
      !a.number("--Tp", 0.0, 1e-6, 1e9, ro.tp_s, err) ||
      !a.number("--K", 0.0, 0.0, 1e3, ro.k, err) ||
      !a.number("--T-avg", 10.0, 1e-6, 1e9, ro.t_avg_s, err) ||
      !a.number("--T-int", 20.0, 1e-6, 1e9, ro.t_int_s, err) ||
      !a.integer("--sim-windows", 1000, 1, kMaxSimWindows, sim_windows, err) ||
      !a.integer("--seed", 2, 0, std::uint64_t{1} << 53U, ro.seed, err) ||
      !a.number("--timeout", 30.0, 1e-3, 86400.0, o.timeout_s, err) ||
      !a.integer("--window", window_default, 0, 1000000, o.window, err) ||
      (a.has("--lsb") && !a.number("--lsb", 0.0, 1e-12, 1e6, o.lsb_opt, err)) ||
      (a.has("--fs") && !a.number("--fs", 0.0, kMinFsHz, kMaxFsHz, o.fs_opt, err))) {
    return false;
  }
  ro.sim_windows = static_cast<std::size_t>(sim_windows);
  return true;
}

bool parse_run(int argc, char** argv, RunOptions& o, std::string& err) {
  Args a;
  const std::vector<OptSpec> specs = {
      {"--mat", true},     {"--channel", true},   {"--bus", true},       {"--rate", true},
      {"--node", true},    {"--out", true},       {"--json", true},      {"--N", true},
      {"--B", true},       {"--Tp", true},        {"--K", true},         {"--fw", true},
      {"--no-plots", false}, {"--quiet", false},  {"--T-avg", true},     {"--T-int", true},
      {"--sim-windows", true}, {"--seed", true},  {"--timeout", true},   {"--window", true},
      {"--lsb", true},     {"--fs", true},        {"--layout", true},    {"--only-channel", false},
      {"--model", true},   {"--model-as-is", false},
  };
  if (!a.parse(argc, argv, 2, specs, 1, err)) {
    return false;
  }
  o.help = a.help();
  return o.help || (parse_run_names(a, o, err) && parse_run_numbers(a, o, err));
}

/// Which samples are sent. A sample with a non-finite value in any channel sent is not sent (the
/// protocol has no per-channel validity): inside [lo, hi) it is a gap the node counts missing;
/// before the first / after the last sendable sample it is not part of the series (the node's
/// receiver starts at the first sequence number it sees). Which samples inside are skipped is
/// decided again, chunk by chunk, while sending (no per-sample vector).
struct SendPlan {
  std::size_t lo = 0;
  std::size_t hi = 0;
  std::uint64_t sent = 0;
};

/// The present channels of a file read together, chunk by chunk (every present channel has
/// sd.n_samples samples, checked by load_sensor_meta).
class Lockstep {
 public:
  static constexpr std::size_t kChunk = 8192;
  bool open(const SensorData& sd, std::string& err) {
    for (std::size_t c = 0; c < kNumChannels; ++c) {
      if (!sd.ch[c].present) {
        continue;
      }
      auto cs = open_channel(sd, c);
      if (!cs.ok()) {
        err = cs.error().message;
        return false;
      }
      stream_[c] = std::make_unique<mat::ChannelStream>(std::move(cs.value()));
      ch_[c] = &sd.ch[c];
      values_[c].resize(kChunk);
    }
    return true;
  }
  // The next chunk: n samples of every present channel in values(c). False with err on a read
  // error or channels of different lengths; n == 0 at the end.
  bool next(std::size_t& n, std::string& err) {
    bool first = true;
    n = 0;
    for (std::size_t c = 0; c < kNumChannels; ++c) {
      if (!stream_[c]) {
        continue;
      }
      const auto r = stream_[c]->read(values_[c].data(), kChunk);
      if (!r.ok()) {
        err = r.error().message;
        return false;
      }
      scale_counts(*ch_[c], values_[c].data(), r.value());
      if (!first && r.value() != n) {
        err = "channels of different lengths";
        return false;
      }
      n = r.value();
      first = false;
    }
    return true;
  }
  [[nodiscard]] const double* values(std::size_t c) const { return values_[c].data(); }
  // Sample i of the chunk is finite in every present channel.
  [[nodiscard]] bool sendable(std::size_t i) const {
    for (std::size_t c = 0; c < kNumChannels; ++c) {
      if (stream_[c] && !std::isfinite(values_[c][i])) {
        return false;
      }
    }
    return true;
  }

 private:
  std::unique_ptr<mat::ChannelStream> stream_[kNumChannels];
  const ChannelData* ch_[kNumChannels] = {};
  std::vector<double> values_[kNumChannels];
};

// lo, hi and sent from one pass over the present channels. False with err on a read error.
bool plan_send(const SensorData& sd, SendPlan& plan, std::string& err) {
  Lockstep ls;
  if (!ls.open(sd, err)) {
    return false;
  }
  plan = SendPlan{};
  bool any = false;
  std::size_t base = 0;
  for (std::size_t n = 0; ls.next(n, err) && n > 0; base += n) {
    for (std::size_t i = 0; i < n; ++i) {
      if (ls.sendable(i)) {
        plan.lo = any ? plan.lo : base + i;
        plan.hi = base + i + 1;
        ++plan.sent;
        any = true;
      }
    }
  }
  return err.empty();
}

// The first samples of the report's channel, as many as the covariance check uses (at most
// kMaxCovWindows windows: a bounded prefix whatever the record's length).
constexpr std::size_t kMaxCovWindows = 400;
// The first `want` samples of channel c in its unit (NaN where the file has gaps).
bool read_channel_head(const SensorData& sd, std::size_t c, std::size_t want,
                       std::vector<double>& out, std::string& err) {
  auto cs = open_channel(sd, c);
  if (!cs.ok()) {
    err = cs.error().message;
    return false;
  }
  out.resize(want);
  std::size_t got = 0;
  while (got < want) {
    const auto r = cs.value().read(out.data() + got, want - got);
    if (!r.ok() || r.value() == 0U) {
      err = r.ok() ? sd.path + ": channel shorter than declared" : r.error().message;
      return false;
    }
    got += r.value();
  }
  scale_counts(sd.ch[c], out.data(), out.size());
  return true;
}

bool read_cov_prefix(const RunOptions& o, const SensorData& sd, std::vector<double>& prefix,
                     std::string& err) {
  const double win = std::round(o.ro.t_avg_s * sd.fs_hz) + std::round(o.ro.t_int_s * sd.fs_hz);
  const auto want = static_cast<std::size_t>(
      std::min(static_cast<double>(sd.n_samples), win * static_cast<double>(kMaxCovWindows)));
  return read_channel_head(sd, o.chan, want, prefix, err);
}

// A sink that keeps nothing: stream_counts() for its checks alone.
class CheckOnly final : public CountSink {
 public:
  void push(const std::int32_t* /*counts*/, std::size_t /*n*/) override {}
  void gap(std::size_t /*n*/) override {}
};

// The covariance check's windows and simulation in a work and memory budget: a window of at
// most kMaxSamples, at most kMaxSimSamples samples simulated, at most kMaxSamples doubles of
// simulated trajectories (256 MiB). A window longer than the recording is allowed (the check
// then has simulated windows only, and says so).
bool check_cov_windows(const RunOptions& o, const SensorData& sd, std::string& err) {
  const double n_avg = std::round(o.ro.t_avg_s * sd.fs_hz);
  const double n_int = std::round(o.ro.t_int_s * sd.fs_hz);
  const double win = n_avg + n_int;
  const auto windows = static_cast<double>(o.ro.sim_windows);
  const auto max_samples = static_cast<double>(kMaxSamples);
  if (n_avg < 1.0 || n_int < 1.0 || win > max_samples) {
    err = "--T-avg and --T-int (" + imu::cli::num_text(o.ro.t_avg_s) + " s, " +
          imu::cli::num_text(o.ro.t_int_s) + " s at " + imu::cli::num_text(sd.fs_hz) +
          " Hz) must each be at least one sample and together at most " +
          std::to_string(kMaxSamples) + " samples";
    return false;
  }
  if (windows * win > kMaxSimSamples || windows * n_int > max_samples) {
    err = "--sim-windows x (--T-avg + --T-int) = " + std::to_string(windows * win) +
          " samples to simulate (at most 2e8, and --sim-windows x --T-int at most " +
          std::to_string(kMaxSamples) + " samples)";
    return false;
  }
  return true;
}

// The text input's columns `cols` (n samples each on the grid), each in a pass of its own,
// straight into the MAT-file `mat` under its slot's name, then fs: memory does not grow with the
// record. Each column is a column_start() and its samples. False with err.
bool stream_columns_to_mat(const RunOptions& o, const std::vector<std::string>& cols,
                           const std::vector<std::size_t>& slots, std::uint64_t n, double fs_hz,
                           const std::string& mat, std::string& err) {
  imu::mat::MatWriter w;
  if (!w.add_scalar("fs", fs_hz).ok()) {
    err = o.path + ": could not convert";
    return false;
  }
  std::vector<std::vector<std::uint8_t>> starts;
  for (std::size_t k = 0; k < cols.size(); ++k) {
    // A column's own name may not be a MAT name (w_RS_S_x is, gyro_rad[0] is not): it is written
    // under its slot's name, which the run then reports.
    auto start = w.column_start(kChannelNames[slots[k]], n);
    if (!start.ok()) {
      err = o.path + ": column '" + cols[k] + "': " + start.error().message;
      return false;
    }
    starts.push_back(std::move(start.value()));
  }
  const std::vector<std::uint8_t>& small = w.bytes();
  constexpr std::size_t kHeader = 128;
  imu::cli::AtomicFileWriter out;
  if (!out.open(mat, err) || !out.write(small.data(), kHeader, err)) {
    return false;
  }
  std::vector<double> col(4096);
  std::vector<std::uint8_t> bytes(8U * col.size());
  for (std::size_t k = 0; k < cols.size(); ++k) {
    imu::cli::TextColumnStream one;
    if (!out.write(starts[k].data(), starts[k].size(), err) ||
        !one.open(o.path, std::vector<std::string>{cols[k]}, o.fs_opt, err)) {
      return false;
    }
    std::uint64_t written = 0;
    for (std::size_t got = 1; got > 0;) {
      if (!one.read(col.data(), col.size(), got, err)) {
        return false;
      }
      written += got;
      if (written > n) {
        break;
      }
      imu::mat::MatWriter::encode_doubles(col.data(), got, bytes.data());
      if (!out.write(bytes.data(), 8U * got, err)) {
        return false;
      }
    }
    if (written != n) {
      err = o.path + ": column '" + cols[k] + "' gave " + (written > n ? "more than " : "") +
            std::to_string(std::min(written, n + 1)) + " samples on its own and " +
            std::to_string(n) + " beside the others";
      return false;
    }
  }
  return out.write(small.data() + kHeader, small.size() - kHeader, err) && out.commit(err);
}

// A text input (CSV, TSV) or a ROS bag's only sensor_msgs/Imu topic (imu::cli::open_rows,
// TextColumnStream: the rate from --fs or its time column, missing rows as gaps, the same grid
// as adev and analyze) becomes DIR/input.mat: the slots'
// columns it holds (acc_x..gyro_z, or the column --channel names in its slot) and fs, written as
// they are read (one pass to count, one per column; constant memory at any length). The run
// then streams that file like any MAT input; a note says so. False with err (a missing
// column names the columns; `usage` when --channel named it: exit 2, as for a MAT variable).
bool text_input_to_mat(RunOptions& o, std::string& note, bool& usage, std::string& err) {
  usage = false;
  const auto header = imu::cli::open_rows(o.path, "", err);
  if (header == nullptr) {
    return false;
  }
  const std::vector<std::string>& names = header->names();
  const auto holds = [&names](const std::string& n) {
    return std::find(names.begin(), names.end(), n) != names.end();
  };
  std::vector<std::string> cols;
  std::vector<std::size_t> slots;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    const std::string n = o.renamed && c == o.chan ? o.vars.names[c] : kChannelNames[c];
    if (o.only_channel && c != o.chan) {
      continue;
    }
    if (holds(n)) {
      cols.push_back(n);
      slots.push_back(c);
    } else if (c == o.chan) {
      std::string listed;
      for (const std::string& h : names) {
        listed += (listed.empty() ? "" : ", ") + h;
      }
      err = o.path;
      err += ": no column '";
      err += n;
      err += "'; columns: ";
      err += listed;
      usage = o.renamed;  // a name given on the command line, as for a MAT-file's variable
      return false;
    }
  }
  // Pass 1: every column on the grid, counted (the rate, the time notes and the length).
  imu::cli::TextColumnStream st;
  if (!st.open(o.path, cols, o.fs_opt, err)) {
    return false;
  }
  std::uint64_t n = 0;
  {
    std::vector<double> buf(4096 * cols.size());
    for (std::size_t got = 1; got > 0; n += got) {
      if (!st.read(buf.data(), 4096, got, err)) {
        return false;
      }
    }
  }
  const std::string mat = o.out_dir + "/input.mat";
  if (!imu::cli::make_dirs(o.out_dir, err) ||
      !stream_columns_to_mat(o, cols, slots, n, st.fs_hz(), mat, err)) {
    return false;
  }
  note = st.origin() + ": " + std::to_string(cols.size()) + " column(s) at " +
         imu::cli::num_text(st.fs_hz()) + " Hz" +
         (o.fs_opt > 0.0 ? " (--fs)" : " from the time column '" + st.time_name() + "'") +
         (st.time_note().empty() ? "" : "; " + st.time_note()) +
         (st.time_gap_samples() > 0
              ? "; its steps left " + std::to_string(st.time_gap_samples()) + " samples missing"
              : "") +
         "; streamed from " + mat;
  if (o.renamed) {
    note += " (column '" + o.vars.names[o.chan] + "' as " + kChannelNames[o.chan] + ")";
    o.renamed = false;
    o.vars.names[o.chan].clear();
  }
  o.path = mat;
  return true;
}

// Check every present channel of the file (LSB, finite samples: stream_counts' checks, chunk by chunk)
// and plan what is sent; nothing of the record is kept. Exit status.
int load_run_data(const RunOptions& o, SensorData& sd, SendPlan& plan, std::string& err) {
  bool want[kNumChannels];
  bool required[kNumChannels];
  double lsb_over[kNumChannels];
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    want[c] = !o.only_channel || c == o.chan;
    required[c] = c == o.chan;
    lsb_over[c] = c == o.chan ? o.lsb_opt : 0.0;
  }
  if (!load_sensor_meta(o.path, want, required, lsb_over, o.fs_opt, sd, err,
                        o.renamed ? &o.vars : nullptr)) {
    // A variable the file does not hold is a usage error, as in adev.
    return o.renamed && err.find("not found") != std::string::npos ? kExitUsage : kExitRuntime;
  }
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    if (sd.ch[c].present) {
      CheckOnly sink;
      StreamTiming tm;
      const int st = stream_counts(o.path, c, sd.ch[c], sink, tm, err);
      if (st != kExitOk) {
        return st;
      }
    }
  }
  if (!plan_send(sd, plan, err)) {
    return kExitRuntime;
  }
  if (plan.sent == 0) {
    err = o.path + ": no sample has every channel finite (nothing to send; --only-channel sends "
          "one channel)";
    return kExitRuntime;
  }
  if (plan.sent < 16) {
    err = o.path + ": " + std::to_string(plan.sent) +
          " samples to send: too short for an ADEV (16 or more)";
    return kExitRuntime;
  }
  if (plan.hi - plan.lo > 0xFFFFFFFFULL) {
    err = o.path + ": more than 2^32 samples (the sequence number would wrap)";
    return kExitRuntime;
  }
  if (!check_cov_windows(o, sd, err)) {
    return kExitUsage;
  }
  return kExitOk;
}

/// The bus and the firmware node on it: a thread of this process, a child imu-fw, or none.
struct Session {
  hal::CanSocket sock;
  std::unique_ptr<InprocNode> inproc;
  pid_t child = -1;
  int child_status = 0;
  std::string bus_used;
  hal::Layout layout = hal::Layout::kFd;
  std::string layout_s;
};

// The node's configuration: the model under test, when given, on the channel group of --channel.
node::NodeConfig node_config(const RunOptions& o) {
  node::NodeConfig nc;
  if (o.ro.given_model) {
    const std::size_t first = o.chan < 3 ? 0 : 3;
    for (std::size_t c = first; c < first + 3; ++c) {
      nc.model[c] = node::ChannelModel{o.ro.n, o.ro.b, o.ro.tp_s};
    }
  }
  return nc;
}

bool start_inproc(const RunOptions& o, Session& s, std::string& err) {
  s.inproc = std::make_unique<InprocNode>();
  hal::IoStatus st = hal::IoStatus::kOk;
  if (o.is_loopback) {
    st = hal::CanSocket::open_pair(s.sock, s.inproc->sock);
    s.bus_used = "in-process loopback pair";
  } else {
    st = s.sock.open(o.bus.c_str());
    if (st == hal::IoStatus::kOk) {
      st = s.inproc->sock.open(o.bus.c_str());
    }
  }
  if (st != hal::IoStatus::kOk) {
    err = std::string("cannot open bus: ") +
          (s.sock.error()[0] != '\0' ? s.sock.error() : s.inproc->sock.error());
    return false;
  }
  if (o.layout_s == "auto" && !s.sock.fd_capable()) {
    s.layout = hal::Layout::kClassic;  // CAN interface with MTU 16: classic frames only
  }
  node::NodeConfig nc = node_config(o);
  nc.layout = s.layout;
  if (s.inproc->node.configure(nc, s.inproc->sock, &s.inproc->static_line,
                               &s.inproc->alarm_line) != node::NodeStatus::kOk) {
    err = "node configuration rejected (model parameters)";
    return false;
  }
  s.inproc->start();
  return true;
}

// fork + exec imu-fw on s.bus_used, its output in OUT/imu-fw.log.
bool spawn_fw(const RunOptions& o, Session& s, std::string& err) {
  const std::string fw = o.fw.empty() ? self_dir() + "/imu-fw" : o.fw;
  if (access(fw.c_str(), X_OK) != 0) {
    err = "imu-fw not found at '" + fw + "' (give --fw PATH)";
    return false;
  }
  if (!make_dirs(o.out_dir, err)) {
    return false;
  }
  std::vector<std::string> args = {fw, "--bus", s.bus_used, "--layout", s.layout_s};
  if (o.ro.given_model) {
    const std::string pre = o.chan < 3 ? "--" : "--gyro-";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", o.ro.n);
    args.insert(args.end(), {pre + "N", buf});
    std::snprintf(buf, sizeof buf, "%.17g", o.ro.b);
    args.insert(args.end(), {pre + "B", buf});
    std::snprintf(buf, sizeof buf, "%.17g", o.ro.tp_s);
    args.insert(args.end(), {pre + "Tp", buf});
  }
  const std::string log = o.out_dir + "/imu-fw.log";
  std::vector<char*> av;
  av.reserve(args.size() + 1);
  for (std::string& a : args) {
    av.push_back(a.data());
  }
  av.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  s.child = fork();
  if (s.child < 0) {
    err = std::string("fork: ") + std::strerror(errno);
    return false;
  }
  if (s.child == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      ::close(fd);
    }
    execv(av[0], av.data());
    _exit(127);
  }
  return true;
}

bool open_session(const RunOptions& o, Session& s, std::string& err) {
  s.bus_used = o.bus;
  s.layout = o.layout;
  s.layout_s = o.layout_s;
  if (o.node_mode == "inproc") {
    return start_inproc(o, s, err);
  }
  if (o.node_mode == "spawn" && o.bus == "loopback") {
    s.bus_used = "loopback:imu-sim-" + std::to_string(getpid());
  }
  if (s.sock.open(s.bus_used.c_str()) != hal::IoStatus::kOk) {
    err = std::string("cannot open bus: ") + s.sock.error();
    return false;
  }
  if (o.layout_s == "auto" && !s.sock.fd_capable()) {
    s.layout = hal::Layout::kClassic;  // CAN interface with MTU 16: classic frames only
  }
  s.layout_s = s.layout == hal::Layout::kFd ? "fd" : "classic";
  return o.node_mode != "spawn" || spawn_fw(o, s, err);
}

/// What the sending loop needs besides the data.
struct Sender {
  const RunOptions& o;
  Session& s;
  Link& link;
  Telemetry& tel;
  hal::ConfigRecord cfg{};
  std::uint8_t cfg_tid = 0;
  hal::EncodedFrames fr{};
  double t_send0 = 0.0;
  double last_progress = 0.0;
  double last_credit = 0.0;
  std::uint64_t last_processed = 0;
  bool tty = false;

  // Send the encoded frames; 0 or the failure status (printed). first: wait for a peer.
  int send_frames(bool first, bool hint_node) {
    std::string err;
    for (std::size_t i = 0; i < fr.count; ++i) {
      if (!link.send(fr.frame[i], first ? 10000 : 0, err)) {
        return fail(kCmd, "send on " + s.bus_used + " failed: " + err +
                              (hint_node ? " (is imu-fw running on this bus?)" : ""));
      }
    }
    return kExitOk;
  }

  // Hold sample q until the node has acknowledged all but --window samples; 0 or status.
  int wait_for_credit(std::uint64_t q) {
    while (o.window > 0 && q >= tel.processed() + o.window) {
      link.service(50, false);
      if (tel.processed() != last_processed) {
        last_processed = tel.processed();
        last_credit = now_s();
      } else if (now_s() - last_credit > 10.0) {
        return fail(kCmd, "no progress report from the firmware node for 10 s on " + s.bus_used +
                              " (is imu-fw running? --window 0 disables the credit window)");
      }
    }
    return kExitOk;
  }

  void pace(std::uint64_t q, double fs_hz) {
    const double due = t_send0 + static_cast<double>(q) / fs_hz;
    double now = now_s();
    while (now < due) {
      link.service(static_cast<int>(std::ceil((due - now) * 1000.0)), false);
      now = now_s();
    }
  }
};

// The sample with sequence number q of the planned range: the configuration first and every 100
// samples, then the sample unless it holds a non-finite value; counts[c][i] are its counts.
int send_one(const SensorData& sd, std::uint64_t q, std::uint64_t span,
             std::uint64_t period_ns, bool sendable,
             const std::vector<std::int32_t> (&counts)[kNumChannels], std::size_t i, Sender& tx) {
  if (q % 100 == 0) {  // configuration at start and once per 100 samples (1 s at 100 Hz)
    hal::encode(tx.cfg, tx.s.layout, tx.cfg_tid++, tx.fr);
    int st = tx.send_frames(q == 0, q == 0 && tx.o.node_mode != "inproc");
    for (std::size_t c = 0; st == kExitOk && q == 0 && c < kNumChannels; ++c) {
      if (tx.o.pushed[c] && tx.o.has_signals[c]) {  // its deterministic terms first
        hal::encode(tx.o.signals[c], false, tx.s.layout, tx.cfg_tid++, tx.fr);
        st = tx.send_frames(false, false);
      }
      if (st == kExitOk && tx.o.pushed[c]) {  // after the config
        hal::encode(tx.o.model[c], false, tx.s.layout, tx.cfg_tid++, tx.fr);
        st = tx.send_frames(false, false);
      }
    }
    if (st != kExitOk) {
      return st;
    }
  }
  if (!sendable) {
    return kExitOk;  // a non-finite value: not sent, the node counts the sequence number missing
  }
  hal::SampleRecord rec{};
  rec.seq = static_cast<std::uint32_t>(q);
  rec.t_sensor_ns = q * period_ns;
  rec.cfg_id = tx.cfg.cfg_id;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    rec.counts[c] = sd.ch[c].present ? counts[c][i] : 0;
  }
  if (tx.o.rate == "realtime") {
    tx.pace(q, sd.fs_hz);
  }
  int st = tx.wait_for_credit(q);
  if (st == kExitOk) {
    hal::encode(rec, tx.s.layout, tx.fr);
    st = tx.send_frames(false, false);
  }
  if (st != kExitOk) {
    return st;
  }
  if ((q & 63U) == 63U) {
    tx.link.drain();
    const double now = now_s();
    if (!tx.o.quiet && now - tx.t_send0 > 2.0 && now - tx.last_progress >= 1.0) {
      tx.last_progress = now;
      print_progress(tx.t_send0, q + 1, span, tx.tel, tx.tty, false);
    }
  }
  return kExitOk;
}

// Send the planned samples (configuration first and every 100 samples), reading the present
// channels chunk by chunk and quantising each chunk. 0 or the status of the failure,
// already printed.
int send_samples(const SensorData& sd, const SendPlan& plan, Sender& tx) {
  tx.cfg.cfg_id = 1;
  tx.cfg.rate_hz = sd.fs_hz;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    tx.cfg.lsb[c] = sd.ch[c].present ? sd.ch[c].lsb : default_lsb(c);
  }
  const std::uint64_t span = plan.hi - plan.lo;
  const auto period_ns = static_cast<std::uint64_t>(std::llround(1e9 / sd.fs_hz));
  Lockstep ls;
  std::string err;
  if (!ls.open(sd, err)) {
    return fail(kCmd, err);
  }
  std::vector<std::int32_t> counts[kNumChannels];
  for (auto& cc : counts) {
    cc.assign(Lockstep::kChunk, 0);
  }
  std::size_t base = 0;
  for (std::size_t n = 0; base < plan.hi; base += n) {
    if (!ls.next(n, err) || n == 0U) {
      return fail(kCmd, err.empty() ? sd.path + ": the record ended early" : err);
    }
    for (std::size_t c = 0; c < kNumChannels; ++c) {
      if (!sd.ch[c].present) {
        continue;
      }
      const double* v = ls.values(c);
      for (std::size_t i = 0; i < n; ++i) {
        counts[c][i] = std::isfinite(v[i]) ? quantize(v[i], sd.ch[c].lsb).counts : 0;
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = base + i;
      if (k < plan.lo || k >= plan.hi) {
        continue;
      }
      const int st = send_one(sd, k - plan.lo, span, period_ns, ls.sendable(i), counts, i, tx);
      if (st != kExitOk) {
        return st;
      }
    }
  }
  return kExitOk;
}

// After the last sample: wait for the final telemetry (--timeout at most).
void wait_final_telemetry(const RunOptions& o, Session& s, Link& link, const Telemetry& tel) {
  const double wait_end = now_s() + o.timeout_s;
  while (!tel.final_done && now_s() < wait_end && !link.link_down()) {
    link.service(50, false);
    if (s.inproc && s.inproc->done.load()) {
      link.drain();
      break;
    }
  }
}

// End the stream, stop the in-process node, reap the child (SIGTERM after 5 s).
void end_session(Session& s) {
  s.sock.close();  // the node sees the end of the stream (loopback)
  if (s.inproc) {
    s.inproc->stop.store(true);
    s.inproc->join();
  }
  if (s.child > 0) {
    const double kill_at = now_s() + 5.0;
    pid_t w = 0;
    while ((w = waitpid(s.child, &s.child_status, WNOHANG)) == 0 && now_s() < kill_at) {
      usleep(20000);
    }
    if (w == 0) {
      kill(s.child, SIGTERM);
      (void)waitpid(s.child, &s.child_status, 0);
    }
  }
}

// The channel's ADEV as received, tau rebuilt exactly from the averaging factor.
std::vector<AdevRow> received_adev(const Telemetry& tel, std::size_t chan, double fs_hz) {
  std::vector<AdevRow> rows;
  const double ts_s = 1.0 / fs_hz;
  for (std::size_t i = 0; i < tel.n_points[chan]; ++i) {
    const hal::AdevRecord& r = tel.curve[chan][i];
    const auto af = static_cast<std::uint32_t>(std::lround(static_cast<double>(r.tau_s) / ts_s));
    AdevRow row;
    row.tau_s = static_cast<double>(af) * ts_s;
    row.adev = static_cast<double>(r.adev);
    row.ci_lo = static_cast<double>(r.ci_lo);
    row.ci_hi = static_cast<double>(r.ci_hi);
    row.n_terms = r.n_terms;
    row.af = af;
    row.edf = edf_of(af, r.n_terms);
    rows.push_back(row);
  }
  return rows;
}

std::vector<StatGroup> chain_stats(const RunOptions& o, const SensorData& sd,
                                   const SendPlan& plan, const Session& s, const Link& link,
                                   const Telemetry& tel) {
  auto d = [](std::uint64_t v) { return static_cast<double>(v); };
  const hal::RxStats& rs = tel.rx.stats();
  const hal::LinkStats& ls = s.sock.stats();
  const hal::StatsRecord& ns = tel.stats;
  std::vector<StatGroup> g;
  g.push_back(StatGroup{"sender", "sender (imu-sim emulator)",
                        {{"samples", d(sd.n_samples)},
                         {"sent", d(plan.sent)},
                         {"non_finite", d(sd.n_samples - plan.sent)},
                         {"frames", d(link.frames())},
                         {"backpressure_waits", d(link.backpressure_waits())},
                         {"tx_link_down", d(ls.tx_link_down)},
                         {"sys_errors", d(ls.sys_errors)}}});
  g.push_back(StatGroup{"node_stats", "firmware node (its StatsRecord)",
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
                         {"lost", d(plan.sent) - d(ns.samples)}}});
  const hal::RejectsRecord& nr = tel.rejects;
  g.push_back(StatGroup{"node_rejects", "firmware node refusals (its RejectsRecord)",
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
  g.push_back(StatGroup{"telemetry_receiver", "telemetry receiver (imu-sim)",
                        {{"frames", d(rs.frames)},
                         {"adev_records", d(tel.adev_records)},
                         {"stats_records", d(tel.stats_records)},
                         {"crc_errors", d(rs.crc_errors)},
                         {"bad_mtu", d(rs.bad_mtu)},
                         {"bad_dlc", d(rs.bad_dlc)},
                         {"unknown_id", d(rs.unknown_id)},
                         {"kernel_drops", d(ls.kernel_drops)}}});
  if (s.inproc) {
    const node::NodeStats& st = s.inproc->node.stats();
    g.push_back(StatGroup{"node_inproc", "firmware node (in-process counters)",
                          {{"telemetry_frames", d(st.telemetry_frames)},
                           {"telemetry_failures", d(st.telemetry_failures)},
                           {"adev_sets", d(st.adev_sets)},
                           {"status_sets", d(st.status_sets)},
                           {"alarm_changes", d(st.alarm_changes)},
                           {"saturated", d(st.saturated)}}});
  }
  if (tel.have_bias) {
    g.push_back(StatGroup{"bias_filter", "bias filter (last BiasRecord, channel " + o.chan_name + ")",
                          {{"bias", static_cast<double>(tel.bias.bias[o.chan])},
                           {"std", std::sqrt(static_cast<double>(tel.bias.var[o.chan]))},
                           {"static_flag", static_cast<double>(tel.bias.flags & hal::kBiasStatic)}}});
  }
  if (tel.have_monitor) {
    g.push_back(StatGroup{"residual_monitors", "residual monitors (last MonitorRecord)",
                          {{"nis_mean", static_cast<double>(tel.monitor.nis_mean)},
                           {"whiteness_ratio", static_cast<double>(tel.monitor.whiteness)},
                           {"flags", static_cast<double>(tel.monitor.flags)},
                           {"cusum_mask", static_cast<double>(tel.monitor.cusum_mask)}}});
  }
  return g;
}

std::vector<std::string> report_notes(const RunOptions& o, const SensorData& sd,
                                      const SendPlan& plan, const Session& s) {
  std::vector<std::string> notes;
  if (sd.ch[o.chan].off_grid > 0) {
    notes.push_back(std::to_string(sd.ch[o.chan].off_grid) +
                    " samples are not integer multiples of the LSB (quantised to it)");
  }
  if (sd.n_samples > plan.sent) {
    notes.push_back(std::to_string(sd.n_samples - plan.sent) +
                    " samples hold NaN/Inf in a channel sent: not sent (gaps; the node counts "
                    "those between finite samples as missing)");
  }
  if (s.child > 0) {
    const int st = WIFEXITED(s.child_status) ? WEXITSTATUS(s.child_status) : -1;
    notes.push_back("imu-fw ran as a separate process; its output is in " + o.out_dir +
                    "/imu-fw.log (exit status " + std::to_string(st) + ")");
  }
  return notes;
}

// The name of channel slot c in this run (the selected channel may be a renamed variable).
std::string slot_name(const RunOptions& o, std::size_t c) {
  return c == o.chan ? o.chan_name : std::string(kChannelNames[c]);
}

// The models of an analysis JSON, one per channel slot it holds (a whole-IMU analysis holds
// all six; a one-channel analysis one). With --only-channel only the selected channel's. Notes
// on what the node cannot run go to `notes`, prefixed with the channel.
bool load_models(const std::string& json, RunOptions& o, std::string& notes, std::string& err) {
  notes.clear();
  std::string names;
  std::size_t n_pushed = 0;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    const std::string name = slot_name(o, c);
    names += (c == 0 ? "" : ", ") + name;
    if ((o.only_channel && c != o.chan) || !analysis_holds_channel(json, name)) {
      continue;
    }
    std::string dropped;
    NodeModel nm{};
    if (!model_from_analysis_json(json, name, c, nm, dropped, err)) {
      err.insert(0, ": ");
      err.insert(0, name);
      return false;
    }
    o.model[c] = nm.rec;
    o.signals[c] = nm.signals;
    o.has_signals[c] = nm.has_signals;
    o.pushed[c] = true;
    ++n_pushed;
    if (!dropped.empty()) {
      notes.append(notes.empty() ? "" : "; ").append(name).append(": ").append(dropped);
    }
  }
  if (n_pushed == 0) {
    err = o.only_channel ? "holds no model of " + o.chan_name + " (--only-channel)"
                         : "holds no model of any channel sent (" + names + ")";
    return false;
  }
  return true;
}

// Samples of a channel the pushed model is tuned on (imu::analyze::tune_node_record uses at
// most 16 segments of 2^18).
constexpr std::size_t kTuneSamples = std::size_t{1} << 22U;

// Each pushed model tuned to the node's filter on the record the run sends (the fast terms by
// the record's Whittle likelihood, node_tuning.hpp), unless --model-as-is; the channels in
// parallel (imu::cli::parallel_for), each with its own head of the record (at most
// kTuneSamples doubles per thread). What changed goes to `notes`, in channel order.
bool tune_models(RunOptions& o, const SensorData& sd, std::string& notes, std::string& err) {
  if (!o.push_model || o.model_as_is) {
    return true;
  }
  std::vector<std::size_t> todo;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    if (o.pushed[c] && sd.ch[c].present) {
      todo.push_back(c);
    }
  }
  std::array<std::string, kNumChannels> said{};
  std::array<std::string, kNumChannels> errs{};
  imu::cli::parallel_for(todo.size(), [&](std::size_t i) {
    const std::size_t c = todo[i];
    std::vector<double> head;
    if (read_channel_head(sd, c, std::min(sd.n_samples, kTuneSamples), head, errs[c])) {
      // The deterministic terms are no part of the spectrum tuned: the record less their fit.
      std::size_t reserved = 0;
      if (o.has_signals[c]) {
        (void)analyze::remove_signals(head.data(), head.size(), sd.fs_hz, o.signals[c]);
        reserved = node::signal_states(o.signals[c]);
      }
      said[c] =
          analyze::tune_node_record(head.data(), head.size(), sd.fs_hz, o.model[c], reserved).note;
    }
  });
  for (const std::size_t c : todo) {
    if (!errs[c].empty()) {
      err = errs[c];
      return false;
    }
    notes.append(notes.empty() ? "" : "; ").append(slot_name(o, c)).append(": ").append(said[c]);
  }
  return true;
}

// A whiteness or NIS test that flags a block with probability p_flag under a correct model,
// run on `blocks` blocks: the most flagged blocks that are still consistent with a correct
// model at the 1 % level (the smallest m with P(Bin(blocks, p_flag) > m) <= 0.01). O(blocks).
std::uint32_t max_flagged_blocks(std::uint32_t blocks, double p_flag) {
  // pmf by the recurrence P(k+1) = P(k) (n-k)/(k+1) p/(1-p), in logs from P(0) = (1-p)^n.
  const double n = static_cast<double>(blocks);
  double log_pk = n * std::log1p(-p_flag);
  double cdf = 0.0;
  for (std::uint32_t k = 0; k < blocks; ++k) {
    cdf += std::exp(log_pk);
    if (1.0 - cdf <= 0.01) {
      return k;
    }
    const double kd = static_cast<double>(k);
    log_pk += std::log((n - kd) / (kd + 1.0)) + std::log(p_flag / (1.0 - p_flag));
  }
  return blocks;
}

// The per-channel judgement of the node's monitors: what a navigation engineer asks of a model
// (NIS mean near 1, whiteness failures at the test's own rate, no CUSUM alarm). The record as
// received plus what is derived from it.
struct ChannelVerdict {
  bool have = false;  // a ChannelMonitorRecord of the channel arrived
  hal::ChannelMonitorRecord m{};
  std::uint32_t white_allowed = 0;  // max_flagged_blocks at the whiteness test's rate
  bool whiteness_passed = false;
  std::vector<double> steps_t_s;  // detected level shifts' estimated times in the record
  [[nodiscard]] bool pushed() const { return (m.flags & hal::kChanMonPushed) != 0; }
  [[nodiscard]] bool cusum_alarm() const { return (m.flags & hal::kChanMonCusum) != 0; }
};
using Verdicts = std::array<ChannelVerdict, kNumChannels>;

// The node's whiteness test flags a block at 5 % (Box-Pierce at 95 %: residual_monitor.hpp).
constexpr double kWhitenessFlagRate = 0.05;

// Every channel's verdict, once per run (the report's table, note and JSON read them).
Verdicts channel_verdicts(const Telemetry& tel, double fs_hz) {
  Verdicts vs{};
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    ChannelVerdict& v = vs[c];
    v.have = tel.have_chan_mon[c];
    v.m = tel.chan_mon[c];
    v.white_allowed = max_flagged_blocks(v.m.blocks, kWhitenessFlagRate);
    v.whiteness_passed = v.have && v.m.blocks > 0 && v.m.white_flagged <= v.white_allowed;
    for (const std::int64_t q : tel.step_samples[c]) {
      v.steps_t_s.push_back(static_cast<double>(q) / fs_hz);
    }
  }
  return vs;
}

// The report's per-channel table of the node.
std::string node_channels_text(const RunOptions& o, const Verdicts& vs) {
  std::string t;
  char line[200];
  std::snprintf(line, sizeof line, "%-10s %-8s %6s %9s %10s %14s %10s\n", "channel", "model",
                "states", "NIS mean", "whiteness", "white. fails", "CUSUM");
  t += line;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    const ChannelVerdict& v = vs[c];
    if (!v.have) {
      continue;
    }
    char fails[40];
    std::snprintf(fails, sizeof fails, "%u/%u %s", v.m.white_flagged, v.m.blocks,
                  v.whiteness_passed ? "ok" : "FAIL");
    char shifts[24] = "quiet";
    if (v.cusum_alarm()) {
      std::snprintf(shifts, sizeof shifts, "%u shift%s", static_cast<unsigned>(v.m.cusum_detections),
                    v.m.cusum_detections == 1 ? "" : "s");
    }
    std::snprintf(line, sizeof line, "%-10.10s %-8s %6u %9.3f %10.3f %14s %10s\n",
                  slot_name(o, c).c_str(), v.pushed() ? "pushed" : "default",
                  static_cast<unsigned>(v.m.n_states), static_cast<double>(v.m.nis_mean),
                  static_cast<double>(v.m.whiteness), fails, shifts);
    t += line;
  }
  t += "model: pushed (from --model) or default (the first-order model); NIS mean over every\n"
       "filter update (1 for a model that fits); whiteness: the last block's Box-Pierce\n"
       "statistic over its 95 % bound; white. fails: blocks that failed it, ok while their count\n"
       "is within the test's own 5 % false-alarm rate (binomial, 1 % level); CUSUM: the level\n"
       "shifts of the innovations' mean it detected (255: 255 or more); at each the node moves\n"
       "its known signal to the new level and re-arms (their times: the JSON's cusum_steps_t_s).\n";
  return t;
}

// Say what the monitors found, channel by channel, and what to do about it: a user reading
// "flags 5" should not have to open codec.hpp.
std::string monitor_note(const RunOptions& o, const Telemetry& tel, const Verdicts& vs) {
  std::string alarm_default;
  std::string alarm_pushed;
  std::string white_failed;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    const ChannelVerdict& v = vs[c];
    if (!v.have) {
      continue;
    }
    std::string& list = v.pushed() ? alarm_pushed : alarm_default;
    if (v.cusum_alarm()) {
      list += (list.empty() ? "" : ", ") + slot_name(o, c) + " (" +
              std::to_string(v.m.cusum_detections) + ")";
    }
    if (!v.whiteness_passed) {
      white_failed += (white_failed.empty() ? "" : ", ") + slot_name(o, c);
    }
  }
  if (alarm_default.empty() && alarm_pushed.empty() && white_failed.empty()) {
    return "";
  }
  std::string t = "residual monitors:";
  if (!alarm_default.empty()) {
    t += " the innovation CUSUM detected level shifts on " + alarm_default +
         ", which run the first-order model (white + one GM): their innovations drift when the "
         "data hold an effect that model lacks (a rate random walk, a step, a ramp), and each "
         "drift reads as shifts. `imu-sim analyze " + o.path +
         " --channel all --json M.json` names it and `--model M.json` pushes the fitted models.";
  }
  if (!alarm_pushed.empty()) {
    t += " The CUSUM detected level shifts on " + alarm_pushed +
         " with the pushed model: bias steps (compare their times, cusum_steps_t_s, with the "
         "analysis's bias_step effects), or what the node does not run (a ramp or sinusoids are "
         "not filter states) or the analysis did not name.";
  }
  if (!white_failed.empty()) {
    t += " Whiteness fails on " + white_failed +
         " (more failed blocks than the test's 5 % false-alarm rate explains): the innovations "
         "are coloured, the model misses correlated noise.";
  }
  if ((tel.monitor.flags & hal::kMonitorAlarmLine) != 0U) {
    t += " The alarm line is set.";
  }
  return t;
}

// The run JSON's "node" object: the model the node reports it runs for the channel, its
// residual monitors and its fault counters.
std::string node_json(const RunOptions& o, const Telemetry& tel, const Verdicts& vs) {
  const auto f = [](float v) { return json_num(static_cast<double>(v)); };
  std::string j = "{\"model\": ";
  if (tel.have_model_echo[o.chan]) {
    const hal::ModelRecord& m = tel.model_echo[o.chan];
    j += std::string("{\"origin\": ") + ((m.flags & hal::kModelPushed) != 0 ? "\"pushed\"" : "\"default\"") +
         ", \"n_states\": " + std::to_string(m.n_states) + ", \"n\": " + f(m.n) +
         ", \"q\": " + f(m.q) + ", \"gm\": [";
    bool first = true;
    for (std::size_t i = 0; i < 2; ++i) {
      if (m.gm_sb[i] > 0.0F) {
        j += std::string(first ? "" : ", ") + "{\"sb\": " + f(m.gm_sb[i]) + ", \"tb_s\": " +
             f(m.gm_tb_s[i]) + "}";
        first = false;
      }
    }
    j += "], \"k\": " + f(m.k) + ", \"bias_instability\": {\"b\": " + f(m.bi) +
         ", \"tau_lo_s\": " + f(m.bi_tau_lo_s) + ", \"tau_hi_s\": " + f(m.bi_tau_hi_s) +
         "}, \"n_filter_s\": " + f(m.n_filter_s) + ", \"oscillation\": {\"sigma\": " +
         f(m.osc_sigma) + ", \"f0_hz\": " + f(m.osc_f0_hz) + ", \"beta_per_s\": " +
         f(m.osc_beta_per_s) + "}";
    // The deterministic terms it runs beside them (zeros: none).
    const bool sig = tel.have_signals_echo[o.chan];
    const hal::ModelSignalsRecord se = sig ? tel.signals_echo[o.chan] : hal::ModelSignalsRecord{};
    j += ", \"ramp_r\": " + f(se.ramp_r) + ", \"sinusoids\": [";
    bool first_s = true;
    for (std::size_t i = 0; i < 2; ++i) {
      if (se.sin_a[i] > 0.0F) {
        j += std::string(first_s ? "" : ", ") + "{\"a\": " + f(se.sin_a[i]) +
             ", \"f0_hz\": " + f(se.sin_f0_hz[i]) + "}";
        first_s = false;
      }
    }
    j += "], \"signal_memory_s\": " + f(se.memory_s) + "}";
  } else {
    j += "null";
  }
  j += ", \"model_pushed\": " + std::string(o.push_model ? "true" : "false");
  // The selected channel's own monitors (the summary record's are the worst over channels).
  const ChannelVerdict& sel = vs[o.chan];
  j += ", \"nis_mean\": " + (sel.have ? f(sel.m.nis_mean) : std::string("null"));
  j += ", \"whiteness_ratio\": " + (sel.have ? f(sel.m.whiteness) : std::string("null"));
  j += ", \"cusum_alarm\": " + std::string(sel.have && sel.cusum_alarm() ? "true" : "false");
  j += ", \"channels\": [";
  bool first_c = true;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    const ChannelVerdict& v = vs[c];
    if (!v.have) {
      continue;
    }
    j += std::string(first_c ? "" : ", ") + "{\"channel\": " + json_str(slot_name(o, c)) +
         ", \"origin\": " + (v.pushed() ? "\"pushed\"" : "\"default\"") +
         ", \"n_states\": " + std::to_string(v.m.n_states) +
         ", \"updates\": " + std::to_string(v.m.updates) +
         ", \"nis_mean\": " + f(v.m.nis_mean) +
         ", \"whiteness_ratio\": " + f(v.m.whiteness) +
         ", \"blocks\": " + std::to_string(v.m.blocks) +
         ", \"whiteness_failed_blocks\": " + std::to_string(v.m.white_flagged) +
         ", \"whiteness_failed_allowed\": " + std::to_string(v.white_allowed) +
         ", \"whiteness_passed\": " + (v.whiteness_passed ? "true" : "false") +
         ", \"cusum_alarm\": " + (v.cusum_alarm() ? "true" : "false") +
         ", \"cusum_detections\": " + std::to_string(v.m.cusum_detections) +
         ", \"cusum_steps_t_s\": [";
    for (std::size_t i = 0; i < v.steps_t_s.size(); ++i) {
      j += (i == 0 ? "" : ", ") + json_num(v.steps_t_s[i]);
    }
    j += "]}";
    first_c = false;
  }
  j += "]";
  const hal::RejectsRecord& r = tel.rejects;
  j += ", \"faults\": {\"model_rejected\": " + std::to_string(r.model_rejected) +
       ", \"bad_config\": " + std::to_string(r.bad_config) +
       ", \"bad_record\": " + std::to_string(r.bad_record) +
       ", \"cfg_mismatch\": " + std::to_string(r.cfg_mismatch) +
       ", \"late\": " + std::to_string(r.late) + ", \"busy\": " + std::to_string(r.busy) +
       ", \"telemetry_failures\": " + std::to_string(r.telemetry_failures) +
       ", \"gpio_errors\": " + std::to_string(r.gpio_errors) +
       ", \"missing\": " + std::to_string(tel.stats.missing) +
       ", \"crc_errors\": " + std::to_string(tel.stats.crc_errors) + "}}";
  return j;
}

// The analysis JSON of --model, read and turned into the channels' model records.
bool read_models(RunOptions& o, std::string& model_note, std::string& err) {
  std::ifstream in(o.model_path, std::ios::binary);
  std::stringstream buf;
  buf << in.rdbuf();
  if (!in) {
    err = o.model_path + ": cannot read";
    return false;
  }
  if (!load_models(buf.str(), o, model_note, err)) {
    err.insert(0, o.model_path + ": ");
    return false;
  }
  return true;
}

// Wall-clock seconds of the run's steps, for the report.
struct RunTimes {
  double load_s;
  double send_s;
  double total_s;
};

// What the report is made of: the node's ADEV of the channel, the chain's counters, the node's
// per-channel monitors and the notes.
ReportInput report_input(const RunOptions& o, const SensorData& sd, const SendPlan& plan,
                         const Session& s, const Link& link, const Telemetry& tel,
                         const std::vector<double>& cov_prefix, const RunTimes& times,
                         const std::string& model_note) {
  ReportInput ri;
  ri.source = o.source;
  ri.channel = o.chan_name;
  ri.channel_index = o.chan;
  ri.fs_hz = sd.fs_hz;
  ri.lsb = sd.ch[o.chan].lsb;
  ri.data = &cov_prefix;
  ri.n_samples = sd.n_samples;
  ri.adev_origin = "online ADEV of the firmware node, received as telemetry over " + s.bus_used;
  ri.adev = received_adev(tel, o.chan, sd.fs_hz);
  ri.stats = chain_stats(o, sd, plan, s, link, tel);
  ri.timing_s = {{"load", "check MAT-file channels + plan", times.load_s},
                 {"send", "send all samples (" + o.rate + ")", times.send_s},
                 {"total", "until final telemetry", times.total_s}};
  ri.notes = report_notes(o, sd, plan, s);
  if (!o.input_note.empty()) {
    ri.notes.insert(ri.notes.begin(), o.input_note);
  }
  const Verdicts vs = channel_verdicts(tel, sd.fs_hz);
  const std::string mon_note = monitor_note(o, tel, vs);
  if (!mon_note.empty()) {
    ri.notes.insert(ri.notes.begin(), mon_note);
  }
  if (!model_note.empty()) {
    ri.notes.push_back(model_note);
  }
  ri.node_json = node_json(o, tel, vs);
  if (tel.have_model_echo[o.chan] && (tel.model_echo[o.chan].flags & hal::kModelPushed) != 0U) {
    // With the deterministic terms it echoes beside it: the whole model the node runs.
    const bool sig = tel.have_signals_echo[o.chan];
    const hal::ModelSignalsRecord& se = tel.signals_echo[o.chan];
    ri.node_model_pushed =
        node::model_record_valid(tel.model_echo[o.chan], ri.node_model,
                                 sig ? node::signal_states(se) : 0U) &&
        (!sig || node::model_signals_valid(se, ri.node_model));
  }
  ri.node_text = node_channels_text(o, vs);
  return ri;
}

}  // namespace

int cmd_run(int argc, char** argv) {
  std::string err;
  RunOptions o;
  if (!parse_run(argc, argv, o, err)) {
    return fail(kCmd, err + " (imu-sim run --help)", kExitUsage);
  }
  if (o.help) {
    return print_help("run");
  }
  // Output paths are checked before the work (a run is not lost to a typo in --json).
  if (!imu::cli::check_output_dir(o.out_dir, err) ||
      !imu::cli::check_output_path(o.ro.json_path, err)) {
    return fail(kCmd, err, kExitUsage);
  }
  std::string model_note;
  if (o.push_model && !read_models(o, model_note, err)) {
    return fail(kCmd, err);
  }
  const double t0 = now_s();
  o.source = o.path;
  if (imu::cli::looks_like_text(o.path) || imu::cli::looks_like_bag(o.path)) {
    bool usage = false;
    if (!text_input_to_mat(o, o.input_note, usage, err)) {
      return fail(kCmd, err, usage ? kExitUsage : kExitRuntime);
    }
  }
  SensorData sd;
  SendPlan plan;
  const int load_status = load_run_data(o, sd, plan, err);
  if (load_status != kExitOk || !tune_models(o, sd, model_note, err)) {
    return fail(kCmd, err, load_status != kExitOk ? load_status : kExitRuntime);
  }
  std::vector<double> cov_prefix;  // the report's covariance check: a bounded prefix
  if (!read_cov_prefix(o, sd, cov_prefix, err)) {
    return fail(kCmd, err);
  }
  const double t_load = now_s() - t0;
  const std::uint64_t span = plan.hi - plan.lo;  // sequence numbers 0 .. span - 1

  Session s;
  if (!open_session(o, s, err)) {
    return fail(kCmd, err);  // no thread started, no child forked
  }
  Telemetry tel;
  Link link(s.sock, tel);
  Sender tx{o, s, link, tel};
  tx.tty = isatty(2) != 0;
  tx.t_send0 = now_s();
  tx.last_progress = tx.t_send0;
  tx.last_credit = tx.t_send0;
  const int status = send_samples(sd, plan, tx);
  tel.target = span;
  if (tel.processed() >= span && tel.whole_set_processed >= span) {
    tel.armed = true;  // the final set came whole before the last sample was known sent
    tel.final_done = true;
  } else if (tel.processed() >= span) {
    tel.armed = true;  // already reported: the next complete set is the final one
    for (auto& g : tel.got) {
      g.reset();
    }
  }
  const double t_sent = now_s() - tx.t_send0;
  if (status == kExitOk) {
    wait_final_telemetry(o, s, link, tel);
  }
  const double t_total = now_s() - tx.t_send0;
  if (!o.quiet && t_total > 2.0) {
    print_progress(tx.t_send0, span, span, tel, tx.tty, true);
  }
  end_session(s);
  if (status != kExitOk) {
    return status;
  }
  if (!tel.final_done) {
    return fail(kCmd, "no final telemetry from the firmware node within " +
                          std::to_string(static_cast<int>(o.timeout_s)) + " s on " + s.bus_used +
                          " (processed " + std::to_string(tel.processed()) + " of " +
                          std::to_string(span) + " samples)");
  }

  if (tel.bad_adev_records > 0) {
    return fail(kCmd, "the firmware node sent " + std::to_string(tel.bad_adev_records) +
                          " impossible ADEV records (index out of range, tau <= 0, negative or "
                          "non-finite ADEV, ci_lo > ci_hi): its telemetry cannot be trusted");
  }
  if (o.push_model && tel.rejects.model_rejected > 0) {
    return fail(kCmd, "the firmware node refused the pushed model (" +
                          std::to_string(tel.rejects.model_rejected) +
                          " channel filters could not be configured: a negative or zero "
                          "parameter, or more states than the node holds); it ran its default "
                          "model instead");
  }
  const RunTimes times{t_load, t_sent, t_total};
  const ReportInput ri = report_input(o, sd, plan, s, link, tel, cov_prefix, times, model_note);
  std::string text;
  if (!write_report(ri, o.ro, text, err)) {
    return fail(kCmd, err);
  }
  std::fputs(text.c_str(), stdout);
  std::printf("\nreport folder: %s\n", o.out_dir.c_str());
  return kExitOk;
}

}  // namespace imu::sim

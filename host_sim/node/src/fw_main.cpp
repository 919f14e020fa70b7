// imu-fw: the firmware node on Linux (node core + CanSocket + optional libgpiod lines).
#include <signal.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "imu/hal/linux/can_socket.hpp"
#include "imu/hal/linux/gpio_line.hpp"
#include "imu/node/fw_main.hpp"
#include "imu/node/node.hpp"
#include "imu/node/node_loop.hpp"

namespace imu::node {
namespace {

constexpr const char* kCmd = "imu-fw";
constexpr const char* const kChannelNames[kChannels] = {"acc_x",  "acc_y",  "acc_z",
                                                        "gyro_x", "gyro_y", "gyro_z"};

int fail(const char* cmd, const std::string& msg, int status = 1) {
  std::fprintf(stderr, "%s: %s\n", cmd, msg.c_str());
  return status;
}

struct OptSpec {
  const char* name;
  bool has_value;
};

/// imu-fw's command line: `--name VALUE`, `--name=VALUE`, `--flag`; no positionals. Errors are
/// one line without the command's name.
class Args {
 public:
  bool parse(int argc, char** argv, const std::vector<OptSpec>& specs, std::string& err) {
    for (int i = 1; i < argc; ++i) {
      std::string arg = argv[i];
      std::string value;
      bool inline_value = false;
      const std::size_t eq = arg.find('=');
      if (arg.rfind("--", 0) == 0 && eq != std::string::npos) {
        value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
        inline_value = true;
      }
      if (arg == "-h") {
        arg = "--help";
      }
      const OptSpec* spec = nullptr;
      for (const OptSpec& sp : specs) {
        if (arg == sp.name) {
          spec = &sp;
        }
      }
      if (spec == nullptr) {
        err = "unknown option or argument '" + arg + "'";
        return false;
      }
      if (spec->has_value && !inline_value) {
        if (i + 1 >= argc) {
          err = arg + " needs a value";
          return false;
        }
        value = argv[++i];
      } else if (!spec->has_value && inline_value) {
        err = arg + " takes no value";
        return false;
      }
      opts_[arg] = value;
    }
    return true;
  }
  [[nodiscard]] bool has(const std::string& name) const { return opts_.count(name) != 0; }
  [[nodiscard]] std::string get(const std::string& name, const std::string& def = "") const {
    const auto it = opts_.find(name);
    return it == opts_.end() ? def : it->second;
  }
  /// def if absent; false (with err) unless the whole value is a finite number.
  [[nodiscard]] bool number(const std::string& name, double def, double& out,
                            std::string& err) const {
    const auto it = opts_.find(name);
    if (it == opts_.end()) {
      out = def;
      return true;
    }
    const char* b = it->second.c_str();
    char* e = nullptr;
    const double v = std::strtod(b, &e);
    if (e == b || *e != '\0' || !std::isfinite(v)) {
      err = name + ": '" + it->second + "' is not a finite number";
      return false;
    }
    out = v;
    return true;
  }

 private:
  std::map<std::string, std::string> opts_;
};

std::atomic<bool> g_stop{false};

extern "C" void on_signal(int /*sig*/) { g_stop.store(true); }

constexpr const char* kFwUsage =
    "usage: imu-fw --bus loopback[:NAME]|vcan0|can0 [--gpio-chip CHIP --static-line NAME\n"
    "              --alarm-line NAME] [--N 3.3e-3 --B 9e-4 --Tp 300] [--gyro-N 5.8e-4\n"
    "              --gyro-B 1.2e-4 --gyro-Tp 300] [--listen-only] [--layout auto|fd|classic]\n"
    "              [--idle-ms 200] [--exit-idle-s S] [--peer-timeout-s S] [--status-period 100]\n"
    "              [--adev-period 6000] [--init-samples 1000] [--quiet]\n"
    "Runs until the stream ends: the loopback peer closes, or (CAN) no frame for --exit-idle-s\n"
    "seconds after samples (default 3; 0 = run until SIGINT). Prints the final ADEV table.\n"
    "No frame at all for --peer-timeout-s seconds (default 10 on loopback, 0 = never on CAN):\n"
    "the peer is gone, exit status 1.\n";

// What the command line asks for beyond the node's configuration.
struct FwOptions {
  std::string bus;
  std::string layout;
  std::string chip;
  std::string static_line;
  std::string alarm_line;
  double idle_ms = 0.0;
  double exit_idle_s = 0.0;
  double peer_timeout_s = 0.0;
  bool quiet = false;
};

// The options' values into the node's configuration and fo; 0, or the exit status after the
// message (2: usage).
int read_options(const Args& a, NodeConfig& nc, FwOptions& fo) {
  std::string err;
  if (!a.has("--bus")) {
    std::fputs(kFwUsage, stderr);
    return fail(kCmd, "--bus is required", 2);
  }
  fo.bus = a.get("--bus");
  const bool is_loopback = fo.bus == "loopback" || fo.bus.rfind("loopback:", 0) == 0;
  double v[6] = {};
  double status_p = 0;
  double adev_p = 0;
  double init_n = 0;
  if (!a.number("--N", 3.3e-3, v[0], err) || !a.number("--B", 9e-4, v[1], err) ||
      !a.number("--Tp", 300.0, v[2], err) || !a.number("--gyro-N", 5.8e-4, v[3], err) ||
      !a.number("--gyro-B", 1.2e-4, v[4], err) || !a.number("--gyro-Tp", 300.0, v[5], err) ||
      !a.number("--idle-ms", 200.0, fo.idle_ms, err) ||
      !a.number("--exit-idle-s", is_loopback ? 0.0 : 3.0, fo.exit_idle_s, err) ||
      !a.number("--peer-timeout-s", is_loopback ? 10.0 : 0.0, fo.peer_timeout_s, err) ||
      !a.number("--status-period", 100.0, status_p, err) ||
      !a.number("--adev-period", 6000.0, adev_p, err) ||
      !a.number("--init-samples", 1000.0, init_n, err)) {
    return fail(kCmd, err, 2);
  }
  if (fo.idle_ms < 1.0 || fo.exit_idle_s < 0.0 || status_p < 1.0 || adev_p < 0.0 ||
      init_n < 1.0 || status_p > 4e9 || adev_p > 4e9 || init_n > 4e9 || fo.idle_ms > 1e6 ||
      fo.exit_idle_s > 1e6 || !(fo.peer_timeout_s >= 0.0 && fo.peer_timeout_s <= 1e6)) {
    return fail(kCmd, "a numeric option is out of range", 2);
  }
  for (std::size_t c = 0; c < node::kChannels; ++c) {
    const double* p = c < 3 ? v : v + 3;
    nc.model[c] = node::ChannelModel{p[0], p[1], p[2]};
  }
  fo.layout = a.get("--layout", "auto");
  if (fo.layout != "fd" && fo.layout != "classic" && fo.layout != "auto") {
    return fail(kCmd, "--layout must be auto, fd or classic", 2);
  }
  nc.layout = fo.layout == "classic" ? hal::Layout::kClassic : hal::Layout::kFd;
  nc.telemetry = !a.has("--listen-only");
  nc.status_period_samples = static_cast<std::uint32_t>(status_p);
  nc.adev_period_samples = static_cast<std::uint32_t>(adev_p);
  nc.init_samples = static_cast<std::uint32_t>(init_n);
  const bool gpio = a.has("--gpio-chip") || a.has("--static-line") || a.has("--alarm-line");
  if (gpio && !a.has("--gpio-chip")) {
    return fail(kCmd, "--static-line / --alarm-line need --gpio-chip", 2);
  }
  fo.chip = a.get("--gpio-chip");
  fo.static_line = a.get("--static-line");
  fo.alarm_line = a.get("--alarm-line");
  fo.quiet = a.has("--quiet");
  return 0;
}

// Opens one GPIO line of `chip` for the node; false (with the reason printed) when it cannot.
bool open_line(const std::string& chip, const std::string& name, hal::LineMode mode,
               hal::GpioLine& line) {
  hal::LineConfig lc;
  lc.chip = chip.c_str();
  lc.line = name.c_str();
  lc.consumer = "imu-fw";
  lc.mode = mode;
  if (line.open(lc) != hal::GpioStatus::kOk) {
    fail(kCmd, line.error());
    return false;
  }
  return true;
}

// The loop until the stream ends, with SIGINT and SIGTERM stopping it.
node::LoopEnd run_until_end(node::Node& nd, hal::CanSocket& sock, const FwOptions& fo) {
  g_stop.store(false);
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: poll() returns EINTR and the loop sees the flag
  struct sigaction old_int {};
  struct sigaction old_term {};
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);
  node::LoopOptions lo;
  lo.idle_ms = static_cast<int>(fo.idle_ms);
  lo.exit_idle_ms = static_cast<int>(fo.exit_idle_s * 1000.0);
  lo.exit_on_link_down = true;
  lo.peer_timeout_ms = static_cast<int>(fo.peer_timeout_s * 1000.0);
  lo.stop = &g_stop;
  const node::LoopEnd end = node::run_node_loop(nd, sock, lo);
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  return end;
}

// The stream's counters, then each carried channel's final ADEV table.
void print_summary(const node::Node& n, const hal::CanSocket& sock, node::LoopEnd end) {
  const node::NodeStats& st = n.stats();
  const hal::RxStats& rs = n.rx_stats();
  std::printf("imu-fw: stream ended (%s): %llu samples, %llu missing, %llu frames, "
              "%llu crc errors, %llu before config, %llu telemetry frames (%llu failed), "
              "kernel drops %llu, peers dropped for not reading %llu\n",
              node::to_string(end), static_cast<unsigned long long>(st.samples),
              static_cast<unsigned long long>(st.missing),
              static_cast<unsigned long long>(rs.frames),
              static_cast<unsigned long long>(rs.crc_errors),
              static_cast<unsigned long long>(st.samples_before_config),
              static_cast<unsigned long long>(st.telemetry_frames),
              static_cast<unsigned long long>(st.telemetry_failures),
              static_cast<unsigned long long>(sock.stats().kernel_drops),
              static_cast<unsigned long long>(sock.stats().tx_stall_disconnects));
  if (!n.have_config()) {
    return;
  }
  AdevPoint pts[node::kMaxAdevPoints];
  for (std::size_t c = 0; c < node::kChannels; ++c) {
    const std::size_t np = n.adev().channel(c).snapshot(pts, node::kMaxAdevPoints);
    bool nonzero = false;
    for (std::size_t i = 0; i < np; ++i) {
      nonzero = nonzero || pts[i].adev > 0.0;
    }
    if (!nonzero) {
      continue;  // channel not carried by this stream (all zero counts)
    }
    std::printf("\nfinal ADEV of %s [%s] (bias %.4e, std %.2e, alarm %s):\n", kChannelNames[c],
                c < 3 ? "m/s^2" : "rad/s", static_cast<double>(n.bias(c)),
                std::sqrt(static_cast<double>(n.bias_var(c))), n.alarm() ? "on" : "off");
    // The same columns as `imu-sim adev` (the VM test compares the two tables line by line).
    std::printf("%12s %10s %12s %12s %12s %10s %10s\n", "tau_s", "af", "adev", "ci_lo",
                "ci_hi", "edf", "n_terms");
    for (std::size_t i = 0; i < np; ++i) {
      std::printf("%12.4g %10llu %12.4e %12.4e %12.4e %10.4g %10llu\n", pts[i].tau_s,
                  static_cast<unsigned long long>(pts[i].af), pts[i].adev, pts[i].ci_lo,
                  pts[i].ci_hi, pts[i].edf, static_cast<unsigned long long>(pts[i].n_terms));
    }
  }
}

}  // namespace

int fw_main(int argc, char** argv) {
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {
      {"--bus", true},       {"--gpio-chip", true},    {"--static-line", true},
      {"--alarm-line", true}, {"--N", true},           {"--B", true},
      {"--Tp", true},        {"--gyro-N", true},       {"--gyro-B", true},
      {"--gyro-Tp", true},   {"--listen-only", false}, {"--layout", true},
      {"--idle-ms", true},   {"--exit-idle-s", true},  {"--peer-timeout-s", true},
      {"--status-period", true},
      {"--adev-period", true}, {"--init-samples", true}, {"--quiet", false},
      {"--help", false},     {"--version", false}};
  if (!a.parse(argc, argv, specs, err)) {
    std::fputs(kFwUsage, stderr);
    return fail(kCmd, err, 2);
  }
  if (a.has("--help")) {
    std::fputs(kFwUsage, stdout);
    return 0;
  }
  if (a.has("--version")) {
    std::printf("imu-fw %s\n", IMU_VERSION);
    return 0;
  }
  NodeConfig nc;
  FwOptions fo;
  if (const int status = read_options(a, nc, fo); status != 0) {
    return status;
  }
  hal::GpioLine static_line;
  hal::GpioLine alarm_line;
  if (!fo.static_line.empty() &&
      !open_line(fo.chip, fo.static_line, hal::LineMode::kInput, static_line)) {
    return 1;
  }
  if (!fo.alarm_line.empty() &&
      !open_line(fo.chip, fo.alarm_line, hal::LineMode::kOutput, alarm_line)) {
    return 1;
  }
  hal::CanSocket sock;
  hal::BusOptions bo;
  bo.abort_wait = &g_stop;  // SIGTERM cuts a telemetry send's back-pressure wait short
  if (sock.open(fo.bus.c_str(), bo) != hal::IoStatus::kOk) {
    return fail(kCmd, std::string("cannot open bus: ") + sock.error());
  }
  if (fo.layout == "auto" && !sock.fd_capable()) {
    nc.layout = hal::Layout::kClassic;  // CAN interface with MTU 16: classic frames only
  }
  auto nd = std::make_unique<node::Node>();
  if (nd->configure(nc, sock, fo.static_line.empty() ? nullptr : &static_line,
                    fo.alarm_line.empty() ? nullptr : &alarm_line) != node::NodeStatus::kOk) {
    return fail(kCmd, "node configuration rejected (model parameters)", 2);
  }
  if (!fo.quiet) {
    std::fprintf(stderr, "imu-fw: listening on %s%s\n", fo.bus.c_str(),
                 nc.telemetry ? "" : " (listen only: no telemetry)");
  }
  const node::LoopEnd end = run_until_end(*nd, sock, fo);
  print_summary(*nd, sock, end);
  if (end == node::LoopEnd::kError) {
    return fail(kCmd, std::string("bus error: ") + sock.error());
  }
  if (end == node::LoopEnd::kPeerTimeout) {
    char secs[32];
    std::snprintf(secs, sizeof secs, "%g", fo.peer_timeout_s);
    return fail(kCmd, "no frame from the peer on " + fo.bus + " for " + secs +
                          " s (--peer-timeout-s): the peer is gone");
  }
  return 0;
}

}  // namespace imu::node

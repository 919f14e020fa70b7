// imu-can-probe: send or receive the IMU protocol on a bus, print statistics as key=value.
// For bring-up and the vcan VM test (candump / cansend are the independent peers there).
//   imu-can-probe --bus vcan0 --send 1000 [--layout fd|classic] [--rate-hz 1000] [--skip SEQ]
//   imu-can-probe --bus vcan0 --recv [--count N] [--timeout-ms 2000] [--print]
// --send first sends one config record (cfg_id 1, 100 Hz, ADIS16405 LSBs), then N samples with
// seq 0..N-1 (except --skip SEQ, to provoke a gap) and counts[c] = seq * (c + 1).
// --recv ends after N samples + missing, or when idle for timeout-ms; prints RxStats and
// LinkStats. --print also prints every sample, gap, model record (push or echo, version 1 or 2)
// and model signals record (push or echo) as it arrives. Exit: 0 ok, 1 runtime error, 2 usage,
// 3 bus cannot be opened.
#include <poll.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "imu/hal/linux/can_socket.hpp"
#include "imu/hal/rx_pump.hpp"

namespace {

using imu::hal::IoStatus;

int usage() {
  std::fprintf(stderr,
               "usage: imu-can-probe --bus NAME (--send N [--layout fd|classic] [--rate-hz R]"
               " [--skip SEQ] | --recv [--count N] [--timeout-ms MS] [--print])\n");
  return 2;
}

void print_link(const imu::hal::LinkStats& l) {
  std::printf(
      "link rx_frames=%llu rx_batches=%llu rx_truncated=%llu rx_no_timestamp=%llu "
      "kernel_drops=%llu link_down=%llu link_up=%llu tx_frames=%llu tx_backpressure=%llu "
      "tx_would_block=%llu tx_link_down=%llu sys_errors=%llu\n",
      static_cast<unsigned long long>(l.rx_frames), static_cast<unsigned long long>(l.rx_batches),
      static_cast<unsigned long long>(l.rx_truncated),
      static_cast<unsigned long long>(l.rx_no_timestamp),
      static_cast<unsigned long long>(l.kernel_drops), static_cast<unsigned long long>(l.link_down),
      static_cast<unsigned long long>(l.link_up), static_cast<unsigned long long>(l.tx_frames),
      static_cast<unsigned long long>(l.tx_backpressure),
      static_cast<unsigned long long>(l.tx_would_block),
      static_cast<unsigned long long>(l.tx_link_down),
      static_cast<unsigned long long>(l.sys_errors));
}

unsigned long long records(const imu::hal::RxStats& s, imu::hal::RecordKind k) {
  return static_cast<unsigned long long>(s.records[static_cast<std::size_t>(k)]);
}

void print_rx(const imu::hal::RxStats& s) {
  unsigned long long err_classes = 0;
  for (const auto c : s.err_class) {
    err_classes += c;
  }
  std::printf(
      "rx frames=%llu samples=%llu missing=%llu gaps=%llu crc_errors=%llu bad_mtu=%llu "
      "bad_dlc=%llu unknown_id=%llu remote=%llu error_frames=%llu err_class_bits=%llu "
      "duplicates=%llu late=%llu reordered=%llu truncated=%llu orphan_fragments=%llu "
      "resyncs=%llu configs=%llu models=%llu model_echoes=%llu model_signals=%llu "
      "model_signals_echoes=%llu\n",
      static_cast<unsigned long long>(s.frames), static_cast<unsigned long long>(s.samples),
      static_cast<unsigned long long>(s.missing), static_cast<unsigned long long>(s.gaps),
      static_cast<unsigned long long>(s.crc_errors), static_cast<unsigned long long>(s.bad_mtu),
      static_cast<unsigned long long>(s.bad_dlc), static_cast<unsigned long long>(s.unknown_id),
      static_cast<unsigned long long>(s.remote_frames),
      static_cast<unsigned long long>(s.error_frames), err_classes,
      static_cast<unsigned long long>(s.duplicates), static_cast<unsigned long long>(s.late),
      static_cast<unsigned long long>(s.reordered), static_cast<unsigned long long>(s.truncated),
      static_cast<unsigned long long>(s.orphan_fragments),
      static_cast<unsigned long long>(s.resyncs),
      static_cast<unsigned long long>(s.records[static_cast<std::size_t>(imu::hal::RecordKind::kConfig)]),
      records(s, imu::hal::RecordKind::kModel) + records(s, imu::hal::RecordKind::kModel2),
      records(s, imu::hal::RecordKind::kModelEcho) +
          records(s, imu::hal::RecordKind::kModelEcho2),
      records(s, imu::hal::RecordKind::kModelSignals),
      records(s, imu::hal::RecordKind::kModelSignalsEcho));
}

// A model record (push or echo, version 1 or 2) as key=value; version 1 has no filter and no
// oscillation (0).
void print_model(const imu::hal::ModelRecord& m, bool echo) {
  const auto d = [](float v) { return static_cast<double>(v); };
  std::printf(
      "%s version=%u channel=%u n_states=%u flags=%u n=%g q=%g gm_sb=%g,%g gm_tb_s=%g,%g k=%g "
      "bi=%g bi_tau_s=%g,%g n_filter_s=%g osc_sigma=%g osc_f0_hz=%g osc_beta_per_s=%g\n",
      echo ? "model_echo" : "model", static_cast<unsigned>(m.version),
      static_cast<unsigned>(m.channel), static_cast<unsigned>(m.n_states),
      static_cast<unsigned>(m.flags), d(m.n), d(m.q), d(m.gm_sb[0]), d(m.gm_sb[1]),
      d(m.gm_tb_s[0]), d(m.gm_tb_s[1]), d(m.k), d(m.bi), d(m.bi_tau_lo_s), d(m.bi_tau_hi_s),
      d(m.n_filter_s), d(m.osc_sigma), d(m.osc_f0_hz), d(m.osc_beta_per_s));
}

// A model signals record (push or echo) as key=value.
void print_signals(const imu::hal::ModelSignalsRecord& m, bool echo) {
  const auto d = [](float v) { return static_cast<double>(v); };
  std::printf("%s channel=%u flags=%u ramp_r=%g sin_a=%g,%g sin_f0_hz=%g,%g memory_s=%g\n",
              echo ? "model_signals_echo" : "model_signals", static_cast<unsigned>(m.channel),
              static_cast<unsigned>(m.flags), d(m.ramp_r), d(m.sin_a[0]), d(m.sin_a[1]),
              d(m.sin_f0_hz[0]), d(m.sin_f0_hz[1]), d(m.memory_s));
}

int send_all(imu::hal::CanSocket& bus, long n, imu::hal::Layout layout, double rate_hz, long skip) {
  imu::hal::EncodedFrames out{};
  imu::hal::ConfigRecord cfg{};
  cfg.cfg_id = 1;
  cfg.rate_hz = 100.0;
  for (std::size_t c = 0; c < 3; ++c) {
    cfg.lsb[c] = imu::hal::kAdisAccLsb_mps2;       // 3.33 mg
    cfg.lsb[c + 3] = imu::hal::kAdisGyroLsb_rps;  // 0.05 deg/s
  }
  imu::hal::encode(cfg, layout, 0, out);
  std::size_t failures = 0;
  for (std::size_t i = 0; i < out.count; ++i) {
    failures += bus.send(out.frame[i], 1000) == IoStatus::kOk ? 0U : 1U;
  }
  const int period_ms = rate_hz > 0.0 ? static_cast<int>(1000.0 / rate_hz) : 0;
  for (long k = 0; k < n; ++k) {
    if (k == skip) {
      continue;
    }
    imu::hal::SampleRecord s{};
    s.seq = static_cast<std::uint32_t>(k);
    s.t_sensor_ns = static_cast<std::uint64_t>(k) * 10'000'000ULL;
    s.cfg_id = 1;
    for (std::size_t c = 0; c < imu::hal::kChannels; ++c) {
      s.counts[c] = static_cast<std::int32_t>(k * static_cast<long>(c + 1));
    }
    imu::hal::encode(s, layout, out);
    for (std::size_t i = 0; i < out.count; ++i) {
      const IoStatus st = bus.send(out.frame[i], 1000);
      if (st != IoStatus::kOk) {
        ++failures;
        std::fprintf(stderr, "imu-can-probe: send seq %ld: %s %s\n", k, imu::hal::to_string(st),
                     bus.error());
        if (st == IoStatus::kLinkDown) {
          print_link(bus.stats());
          return 1;
        }
      }
    }
    if (period_ms > 0) {
      poll(nullptr, 0, period_ms);
    }
  }
  std::printf("sent samples=%ld failures=%zu\n", n - (skip >= 0 && skip < n ? 1 : 0), failures);
  print_link(bus.stats());
  return failures == 0 ? 0 : 1;
}

int recv_all(imu::hal::CanSocket& bus, long count, int timeout_ms, bool print) {
  imu::hal::Receiver<8> rx;
  static imu::hal::RxPump<8> pump;  // static: 5 KiB batch buffer off the stack
  long delivered = 0;
  for (;;) {
    const IoStatus st = pump.run_once(bus, rx, timeout_ms, [&](const imu::hal::RxEvent& e) {
      if (e.type == imu::hal::RxEvent::Type::kSample) {
        ++delivered;
        if (print) {
          std::printf("sample seq=%u c0=%d rx_ns=%llu\n", e.rec.sample.seq, e.rec.sample.counts[0],
                      static_cast<unsigned long long>(e.rx_time_ns));
        }
      } else if (e.type == imu::hal::RxEvent::Type::kMissing) {
        delivered += e.missing_count;
        if (print) {
          std::printf("missing first=%u n=%u\n", e.missing_first_seq, e.missing_count);
        }
      } else if (print && (e.type == imu::hal::RxEvent::Type::kModel ||
                           e.type == imu::hal::RxEvent::Type::kModelEcho)) {
        print_model(e.rec.model, e.type == imu::hal::RxEvent::Type::kModelEcho);
      } else if (print && (e.type == imu::hal::RxEvent::Type::kModelSignals ||
                           e.type == imu::hal::RxEvent::Type::kModelSignalsEcho)) {
        print_signals(e.rec.signals, e.type == imu::hal::RxEvent::Type::kModelSignalsEcho);
      }
    });
    if (st == IoStatus::kTimeout || (count > 0 && delivered >= count)) {
      break;
    }
    if (st != IoStatus::kOk && st != IoStatus::kLinkDown) {
      std::fprintf(stderr, "imu-can-probe: receive: %s %s\n", imu::hal::to_string(st), bus.error());
      return 1;
    }
  }
  print_rx(rx.stats());
  print_link(bus.stats());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const char* bus_name = nullptr;
  long send_n = -1;
  bool recv = false;
  bool print = false;
  long count = 0;
  long skip = -1;
  int timeout_ms = 2000;
  double rate_hz = 0.0;
  imu::hal::Layout layout = imu::hal::Layout::kFd;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const bool has_value = i + 1 < argc;
    if (std::strcmp(a, "--bus") == 0 && has_value) {
      bus_name = argv[++i];
    } else if (std::strcmp(a, "--send") == 0 && has_value) {
      send_n = std::atol(argv[++i]);
    } else if (std::strcmp(a, "--recv") == 0) {
      recv = true;
    } else if (std::strcmp(a, "--print") == 0) {
      print = true;
    } else if (std::strcmp(a, "--count") == 0 && has_value) {
      count = std::atol(argv[++i]);
    } else if (std::strcmp(a, "--skip") == 0 && has_value) {
      skip = std::atol(argv[++i]);
    } else if (std::strcmp(a, "--timeout-ms") == 0 && has_value) {
      timeout_ms = std::atoi(argv[++i]);
    } else if (std::strcmp(a, "--rate-hz") == 0 && has_value) {
      rate_hz = std::atof(argv[++i]);
    } else if (std::strcmp(a, "--layout") == 0 && has_value) {
      const char* l = argv[++i];
      if (std::strcmp(l, "classic") == 0) {
        layout = imu::hal::Layout::kClassic;
      } else if (std::strcmp(l, "fd") != 0) {
        return usage();
      }
    } else {
      return usage();
    }
  }
  if (bus_name == nullptr || (send_n < 0) == !recv) {
    return usage();
  }
  imu::hal::CanSocket bus;
  const IoStatus st = bus.open(bus_name);
  if (st != IoStatus::kOk) {
    std::fprintf(stderr, "imu-can-probe: %s [%s]\n", bus.error(), imu::hal::to_string(st));
    return 3;
  }
  if (send_n >= 0) {
    if (layout == imu::hal::Layout::kFd && !bus.fd_capable()) {
      std::fprintf(stderr, "imu-can-probe: bus '%s' is not CAN FD (mtu 16): use --layout classic\n",
                   bus_name);
      return 3;
    }
    return send_all(bus, send_n, layout, rate_hz, skip);
  }
  return recv_all(bus, count, timeout_ms, print);
}

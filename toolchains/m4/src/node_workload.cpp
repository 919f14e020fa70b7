// See node_workload.hpp. Compiled under fw/'s rules (imu_apply_fw_rules).
#include "node_workload.hpp"

#include "imu/hal/codec.hpp"
#include "imu/hal/sim/memory_frame_source.hpp"
#include "imu/node/node.hpp"
#include "largest_model.hpp"
#include "line.hpp"
#include "samples.hpp"

namespace imu::m4 {
namespace {

constexpr double kRateHz = 100.0;
constexpr double kUnitLsb = 1.0 / 1024.0;  // exact in binary
// 1 config + 6 model records + the samples, one CAN FD frame each.
constexpr std::size_t kMaxInputFrames = 1 + hal::kChannels + kNodeSamples;

constexpr std::size_t kMaxTx = 1024;  // telemetry frames kept (the run sends ~560)

// Telemetry is captured in RAM while the node runs (so the cost measured between the marks is
// the node's, not the harness's line formatting) and written out afterwards.
class CaptureSink final : public hal::FrameSink {
 public:
  [[nodiscard]] hal::IoStatus send(const hal::CanFrame& f, int /*timeout_ms*/) override;
  [[nodiscard]] std::size_t count() const { return count_; }
  [[nodiscard]] std::uint64_t dropped() const { return dropped_; }

 private:
  std::size_t count_ = 0;
  std::uint64_t dropped_ = 0;
};

hal::CanFrame g_tx[kMaxTx];

hal::IoStatus CaptureSink::send(const hal::CanFrame& f, int /*timeout_ms*/) {
  if (count_ >= kMaxTx) {
    ++dropped_;
    return hal::IoStatus::kWouldBlock;
  }
  g_tx[count_++] = f;
  return hal::IoStatus::kOk;
}

// CRC-32C chained over the telemetry frames' wire bytes: crc_i = crc32c(crc_{i-1} (4 bytes,
// little-endian) + frame bytes).
std::uint32_t crc_chain(std::uint32_t crc, const hal::CanFrame& f) {
  std::uint8_t buf[4 + sizeof(hal::CanFrame)] = {};
  for (std::size_t i = 0; i < 4; ++i) {
    buf[i] = static_cast<std::uint8_t>(crc >> (8U * i));
  }
  const std::size_t n = hal::wire_size(f);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(&f);  // NOLINT: the wire bytes
  for (std::size_t i = 0; i < n; ++i) {
    buf[4 + i] = bytes[i];
  }
  return hal::crc32c(buf, 4 + n);
}

// Static, not on the stack: the node and the input record are the image's RAM.
node::Node g_node;
hal::CanFrame g_frames[kMaxInputFrames];

bool append(const hal::EncodedFrames& fr, std::size_t& n) {
  for (std::size_t i = 0; i < fr.count; ++i) {
    if (n >= kMaxInputFrames) {
      return false;
    }
    g_frames[n++] = fr.frame[i];
  }
  return true;
}

// The workload's stream header: its ConfigRecord, then the largest model for every channel.
template <typename Take>
bool encode_header(Take take) {
  hal::EncodedFrames fr{};
  hal::ConfigRecord cfg{};
  cfg.cfg_id = 1;
  cfg.rate_hz = kRateHz;
  for (double& l : cfg.lsb) {
    l = kUnitLsb;
  }
  hal::encode(cfg, hal::Layout::kFd, 0, fr);
  bool ok = take(fr);
  for (std::uint8_t c = 0; c < hal::kChannels; ++c) {
    hal::encode(largest_model(c), false, hal::Layout::kFd, 0, fr);
    ok = take(fr) && ok;
  }
  return ok;
}

// The input record, encoded with the hal codec into the in-memory frame array: the header
// frames, then kNodeSamples samples. n_in: the frames written; false if they do not fit.
bool encode_record(std::size_t& n_in) {
  n_in = 0;
  bool ok = encode_header([&n_in](const hal::EncodedFrames& f) { return append(f, n_in); });
  hal::EncodedFrames fr{};
  SampleSource src[hal::kChannels] = {SampleSource(0), SampleSource(1), SampleSource(2),
                                      SampleSource(3), SampleSource(4), SampleSource(5)};
  for (std::uint32_t k = 0; k < kNodeSamples; ++k) {
    hal::SampleRecord s{};
    s.seq = k;
    s.t_sensor_ns = static_cast<std::uint64_t>(k) * 10000000U;
    s.cfg_id = 1;
    for (std::size_t c = 0; c < hal::kChannels; ++c) {
      s.counts[c] = src[c].next();
    }
    hal::encode(s, hal::Layout::kFd, fr);
    ok = ok && append(fr, n_in);
  }
  return ok;
}

}  // namespace

NodeRunStatus run_node_workload(NodeWriteFn write, NodeMarkFn mark, void* ctx) {
  std::size_t n_in = 0;
  if (!encode_record(n_in)) {
    return NodeRunStatus::kFrameOverflow;
  }

  CaptureSink sink;
  node::NodeConfig nc;
  nc.status_period_samples = 100;
  nc.adev_period_samples = 0;  // the full ADEV set once, at the end
  nc.init_samples = 100;
  nc.monitor_window = 100;
  Line<> line;
  line.str("IMU-NODE BEGIN samples=").u64(kNodeSamples).str(" frames_in=").u64(n_in);
  line.str(" sizeof_node=").u64(sizeof(node::Node)).str(" states=").u64(node::kNodeStates);
  // RAM per channel of what the node keeps per channel (the rest of sizeof(Node) is shared:
  // receiver, stats, discretisation workspace, push_frame buffer).
  line.str(" per_channel=").u64(sizeof(node::NodeAdev::Channel) +
                                sizeof(node::NodeFilter) +
                                sizeof(ScalarBiasKf<float>) + sizeof(ResidualMonitors<4>) +
                                sizeof(hal::ModelRecord) + sizeof(ModelParams) + sizeof(float) +
                                sizeof(double) + sizeof(std::size_t) + 2 * sizeof(bool));
  line.str(" kf8=").u64(sizeof(node::NodeFilter));
  line.str("\n");
  write(line.c_str(), ctx);
  if (g_node.configure(nc, sink, nullptr, nullptr) != node::NodeStatus::kOk) {
    return NodeRunStatus::kConfigRejected;
  }

  // Config and model records first (discretisation on target), then the samples between the
  // marks (phase 2 after every batch lets the target keep its 24-bit counter from wrapping).
  constexpr std::size_t kSetupFrames = 1 + hal::kChannels;
  hal::MemoryFrameSource setup(g_frames, kSetupFrames, 10000000U);
  hal::MemoryFrameSource samples(g_frames + kSetupFrames, n_in - kSetupFrames, 10000000U);
  hal::RxFrame batch[8];
  std::size_t got = 0;
  while (setup.receive(batch, 8, got, 0) == hal::IoStatus::kOk) {
    for (std::size_t i = 0; i < got; ++i) {
      g_node.on_frame(batch[i].frame, batch[i].nbytes, batch[i].rx_time_ns);
    }
  }

  if (mark != nullptr) {
    mark(0, ctx);
  }
  while (samples.receive(batch, 8, got, 0) == hal::IoStatus::kOk) {
    for (std::size_t i = 0; i < got; ++i) {
      g_node.on_frame(batch[i].frame, batch[i].nbytes, batch[i].rx_time_ns);
    }
    if (mark != nullptr) {
      mark(2, ctx);
    }
  }
  if (mark != nullptr) {
    mark(1, ctx);
  }
  g_node.finish();

  bool truncated = false;
  std::uint32_t crc = 0;
  for (std::size_t k = 0; k < sink.count(); ++k) {
    const hal::CanFrame& f = g_tx[k];
    crc = crc_chain(crc, f);
    Line<400> t;
    t.str("T ").u64(k).str(" id=").hex(f.can_id).str(" len=").u64(f.len).str(" ");
    for (std::size_t i = 0; i < f.len && i < sizeof f.data; ++i) {
      t.hex(f.data[i]);
    }
    t.str("\n");
    truncated = truncated || t.truncated();
    write(t.c_str(), ctx);
  }
  line.clear();
  line.str("IMU-NODE END tx=").u64(sink.count()).str(" dropped=").u64(sink.dropped());
  line.str(" crc=").hex(crc);
  line.str(" model_states=").u64(g_node.model_echo(2).n_states);
  line.str(" rejected=").u64(g_node.stats().model_rejected);
  line.str(" samples=").u64(g_node.stats().samples);
  const hal::RxStats& rs = g_node.rx_stats();
  line.str(" rx_frames=").u64(rs.frames).str(" crc_errors=").u64(rs.crc_errors);
  line.str(" bad_dlc=").u64(rs.bad_dlc).str(" unknown_id=").u64(rs.unknown_id);
  line.str(" rx_samples=").u64(rs.samples).str(" missing=").u64(rs.missing);
  line.str(" busy=").u64(rs.busy).str("\n");
  write(line.c_str(), ctx);
  return truncated || line.truncated() ? NodeRunStatus::kLineTruncated : NodeRunStatus::kOk;
}

namespace {

// Counts telemetry, keeps none (the steady-state run is long).
class CountSink final : public hal::FrameSink {
 public:
  [[nodiscard]] hal::IoStatus send(const hal::CanFrame& /*f*/, int /*timeout_ms*/) override {
    ++count_;
    return hal::IoStatus::kOk;
  }
  [[nodiscard]] std::uint64_t count() const { return count_; }

 private:
  std::uint64_t count_ = 0;
};

node::Node g_node_steady;
// The measured samples, encoded before the measurement (the encoding is not the node's cost).
constexpr std::size_t kSteadyFrames = 2 * kSteadySamples;
hal::CanFrame g_steady_frames[kSteadyFrames];

void feed(node::Node& n, const hal::EncodedFrames& fr, std::uint64_t& rx_ns) {
  for (std::size_t i = 0; i < fr.count; ++i) {
    rx_ns += 10000000U;
    n.on_frame(fr.frame[i], static_cast<std::uint32_t>(hal::wire_size(fr.frame[i])), rx_ns);
  }
}

}  // namespace

NodeRunStatus run_node_steady(NodeWriteFn write, NodeMarkFn mark, void* ctx) {
  CountSink sink;
  node::NodeConfig nc;
  nc.status_period_samples = 100;
  nc.adev_period_samples = 0;
  nc.init_samples = 100;
  nc.monitor_window = 100;
  if (g_node_steady.configure(nc, sink, nullptr, nullptr) != node::NodeStatus::kOk) {
    return NodeRunStatus::kConfigRejected;
  }
  std::uint64_t rx_ns = 0;
  (void)encode_header([&rx_ns](const hal::EncodedFrames& f) {
    feed(g_node_steady, f, rx_ns);
    return true;
  });
  hal::EncodedFrames fr{};
  SampleSource src[hal::kChannels] = {SampleSource(0), SampleSource(1), SampleSource(2),
                                      SampleSource(3), SampleSource(4), SampleSource(5)};
  std::size_t n_measured = 0;
  for (std::uint32_t k = 0; k < kSteadyWarmSamples + kSteadySamples; ++k) {
    hal::SampleRecord s{};
    s.seq = k;
    s.t_sensor_ns = static_cast<std::uint64_t>(k) * 10000000U;
    s.cfg_id = 1;
    for (std::size_t c = 0; c < hal::kChannels; ++c) {
      s.counts[c] = src[c].next();
    }
    hal::encode(s, hal::Layout::kFd, fr);
    if (k < kSteadyWarmSamples) {
      feed(g_node_steady, fr, rx_ns);
      continue;
    }
    for (std::size_t i = 0; i < fr.count; ++i) {
      if (n_measured >= kSteadyFrames) {
        return NodeRunStatus::kFrameOverflow;
      }
      g_steady_frames[n_measured++] = fr.frame[i];
    }
  }
  if (mark != nullptr) {
    mark(0, ctx);
  }
  for (std::size_t i = 0; i < n_measured; ++i) {
    rx_ns += 10000000U;
    const hal::CanFrame& f = g_steady_frames[i];
    g_node_steady.on_frame(f, static_cast<std::uint32_t>(hal::wire_size(f)), rx_ns);
    if (mark != nullptr && i % 8 == 7) {
      mark(2, ctx);
    }
  }
  if (mark != nullptr) {
    mark(1, ctx);
  }
  std::size_t steady = 0;
  for (std::size_t c = 0; c < hal::kChannels; ++c) {
    steady += g_node_steady.filter_steady(c) ? 1U : 0U;
  }
  Line<> line;
  line.str("IMU-NODE STEADY warm=").u64(kSteadyWarmSamples).str(" samples=").u64(kSteadySamples);
  line.str(" steady_channels=").u64(steady).str(" tx=").u64(sink.count()).str(" bias=");
  for (std::size_t c = 0; c < hal::kChannels; ++c) {
    line.f32(g_node_steady.bias(c)).str(c + 1 < hal::kChannels ? "," : "\n");
  }
  write(line.c_str(), ctx);
  return line.truncated() ? NodeRunStatus::kLineTruncated : NodeRunStatus::kOk;
}

}  // namespace imu::m4

// Tests of the firmware node core (host_sim/node/node.hpp) through its public API: frames in,
// telemetry frames out through a capturing FrameSink, GPIO through hal::MemoryLine.
#include "imu/node/node.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "imu/hal/codec.hpp"
#include "imu/hal/receiver.hpp"
#include "imu/noise_sim.hpp"

namespace {

using imu::hal::CanFrame;
using imu::hal::EncodedFrames;
using imu::node::Node;
using imu::node::NodeConfig;

/// Captures telemetry and decodes it with the HAL's own receiver.
class CaptureSink final : public imu::hal::FrameSink {
 public:
  imu::hal::IoStatus send(const CanFrame& f, int /*timeout_ms*/) override {
    if (refuse) {
      return imu::hal::IoStatus::kLinkDown;
    }
    frames.push_back(f);
    return imu::hal::IoStatus::kOk;
  }
  /// Decode every captured frame into events (clears the capture).
  std::vector<imu::hal::RxEvent> events() {
    std::vector<imu::hal::RxEvent> out;
    for (const CanFrame& f : frames) {
      (void)rx.push_drain(f, imu::hal::wire_size(f), 0,
                          [&out](const imu::hal::RxEvent& e) { out.push_back(e); });
    }
    frames.clear();
    return out;
  }
  std::vector<CanFrame> frames;
  imu::hal::Receiver<8> rx;
  bool refuse = false;
};

std::size_t count_type(const std::vector<imu::hal::RxEvent>& ev, imu::hal::RxEvent::Type t) {
  std::size_t n = 0;
  for (const auto& e : ev) {
    n += e.type == t ? 1U : 0U;
  }
  return n;
}

class NodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    node_ = std::make_unique<Node>();
    static_line_.set(true);
    cfg_.status_period_samples = 100;
    cfg_.adev_period_samples = 1000;
    cfg_.init_samples = 100;
    cfg_.monitor_window = 100;
    ASSERT_EQ(node_->configure(cfg_, sink_, &static_line_, &alarm_line_),
              imu::node::NodeStatus::kOk);
  }

  void send_config(double rate_hz = 100.0, double lsb = 1e-3, std::uint8_t id = 1) {
    imu::hal::ConfigRecord c{};
    c.cfg_id = id;
    c.rate_hz = rate_hz;
    for (double& l : c.lsb) {
      l = lsb;
    }
    EncodedFrames fr{};
    imu::hal::encode(c, imu::hal::Layout::kFd, 0, fr);
    push(fr);
  }
  void send_sample(std::uint32_t seq, const std::int32_t (&counts)[6], std::uint8_t id = 1) {
    imu::hal::SampleRecord s{};
    s.seq = seq;
    s.cfg_id = id;
    for (std::size_t c = 0; c < 6; ++c) {
      s.counts[c] = counts[c];
    }
    EncodedFrames fr{};
    imu::hal::encode(s, imu::hal::Layout::kFd, fr);
    push(fr);
  }
  void push(const EncodedFrames& fr) {
    for (std::size_t i = 0; i < fr.count; ++i) {
      node_->on_frame(fr.frame[i], imu::hal::wire_size(fr.frame[i]), 0);
    }
  }

  NodeConfig cfg_;
  CaptureSink sink_;
  imu::hal::MemoryLine static_line_;
  imu::hal::MemoryLine alarm_line_;
  std::unique_ptr<Node> node_;
};

TEST_F(NodeTest, RejectsBadConfig) {
  Node n;
  NodeConfig c;
  c.status_period_samples = 0;
  EXPECT_EQ(n.configure(c, sink_, nullptr, nullptr), imu::node::NodeStatus::kBadConfig);
  c = NodeConfig{};
  c.model[4].b = -1.0;
  EXPECT_EQ(n.configure(c, sink_, nullptr, nullptr), imu::node::NodeStatus::kBadConfig);
  c = NodeConfig{};
  c.monitor_window = 3;
  EXPECT_EQ(n.configure(c, sink_, nullptr, nullptr), imu::node::NodeStatus::kBadConfig);
}

TEST_F(NodeTest, SamplesBeforeConfigAreCountedAndIgnored) {
  const std::int32_t c[6] = {1, 2, 3, 4, 5, 6};
  send_sample(0, c);
  send_sample(1, c);
  EXPECT_EQ(node_->stats().samples_before_config, 2U);
  EXPECT_EQ(node_->stats().samples, 0U);
  send_config();
  send_sample(2, c);
  EXPECT_EQ(node_->stats().samples, 1U);
  EXPECT_TRUE(node_->have_config());
}

TEST_F(NodeTest, AdevEqualsDirectEstimatorOnTheSameCounts) {
  send_config(100.0, 2e-3);
  imu::GaussianRng rng(7);
  imu::OnlineAdev<8, 22> ref(0.01, 2e-3);
  const std::uint32_t n = 5000;
  for (std::uint32_t k = 0; k < n; ++k) {
    const auto v = static_cast<std::int32_t>(std::lround(1000.0 * rng.normal()));
    const std::int32_t c[6] = {v, 0, -v, 1, 2, 3};
    send_sample(k, c);
    ref.push(v);
  }
  imu::AdevPoint a[96];
  imu::AdevPoint b[96];
  const std::size_t na = node_->adev().channel(0).snapshot(a, 96);
  const std::size_t nb = ref.snapshot(b, 96);
  ASSERT_EQ(na, nb);
  ASSERT_GT(na, 20U);
  for (std::size_t i = 0; i < na; ++i) {
    // Same estimator, same counts, same order of additions: identical up to the last bit;
    // 1e-14 relative only guards against a different but equivalent summation.
    EXPECT_NEAR(a[i].adev, b[i].adev, 1e-14 * b[i].adev) << "tau " << b[i].tau_s;
    EXPECT_DOUBLE_EQ(a[i].tau_s, b[i].tau_s);
  }
  EXPECT_EQ(node_->stats().samples, n);
  EXPECT_EQ(node_->stats().missing, 0U);
}

TEST_F(NodeTest, TelemetryPeriodsAndFinalSet) {
  send_config();
  const std::int32_t c[6] = {5, -3, 7, 1, 1, 1};
  for (std::uint32_t k = 0; k < 250; ++k) {
    std::int32_t v[6];
    for (std::size_t i = 0; i < 6; ++i) {
      v[i] = c[i] + static_cast<std::int32_t>(k % 7);
    }
    send_sample(k, v);
  }
  // 250 samples, status every 100: two status sets (stats, bias, monitor), no ADEV yet.
  auto ev = sink_.events();
  EXPECT_EQ(count_type(ev, imu::hal::RxEvent::Type::kStats), 2U);
  EXPECT_EQ(count_type(ev, imu::hal::RxEvent::Type::kBias), 2U);
  EXPECT_EQ(count_type(ev, imu::hal::RxEvent::Type::kMonitor), 2U);
  EXPECT_EQ(count_type(ev, imu::hal::RxEvent::Type::kAdev), 0U);
  ASSERT_EQ(ev.front().type, imu::hal::RxEvent::Type::kStats);
  EXPECT_EQ(ev.front().rec.stats.samples, 100U);
  // Idle: the final set, stats first, then every channel's full curve.
  node_->on_idle();
  ev = sink_.events();
  ASSERT_FALSE(ev.empty());
  EXPECT_EQ(ev.front().type, imu::hal::RxEvent::Type::kStats);
  EXPECT_EQ(ev.front().rec.stats.samples, 250U);
  std::size_t per_channel[6] = {};
  for (const auto& e : ev) {
    if (e.type == imu::hal::RxEvent::Type::kAdev) {
      ASSERT_LT(e.rec.adev.channel, 6U);
      ++per_channel[e.rec.adev.channel];
      EXPECT_LT(e.rec.adev.index, e.rec.adev.n_points);
    }
  }
  imu::AdevPoint p[96];
  const std::size_t np = node_->adev().channel(2).snapshot(p, 96);
  for (std::size_t n : per_channel) {
    EXPECT_EQ(n, np);
  }
  // Nothing new: a second idle sends nothing.
  node_->on_idle();
  EXPECT_TRUE(sink_.frames.empty());
  EXPECT_EQ(node_->stats().adev_sets, 1U);
}

TEST_F(NodeTest, SequenceGapBecomesMissing) {
  send_config();
  const std::int32_t c[6] = {1, 1, 1, 1, 1, 1};
  for (std::uint32_t k = 0; k < 50; ++k) {
    send_sample(k, c);
  }
  for (std::uint32_t k = 80; k < 120; ++k) {  // 30 samples lost
    send_sample(k, c);
  }
  node_->on_idle();
  EXPECT_EQ(node_->stats().missing, 30U);
  EXPECT_EQ(node_->stats().samples, 90U);
  EXPECT_EQ(node_->adev().channel(0).missing_samples(), 30U);
  EXPECT_EQ(node_->adev().channel(0).gaps(), 1U);
}

TEST_F(NodeTest, StepRaisesAlarmLineOnlyOnActiveChannels) {
  send_config(100.0, 1e-4);
  imu::GaussianRng rng(3);
  // Channel 2 carries white noise of the model's size (N = 3.3e-3 at 100 Hz: 0.033 per
  // sample = 330 counts), channels 0/1/3..5 are zero (absent). A step of 0.5 m/s^2 (15 sigma)
  // after 2000 samples must trip the CUSUM.
  for (std::uint32_t k = 0; k < 4000; ++k) {
    const double v = 0.033 * rng.normal() + (k >= 2000 ? 0.5 : 0.0);
    const std::int32_t c[6] = {0, 0, static_cast<std::int32_t>(std::lround(v / 1e-4)), 0, 0, 0};
    send_sample(k, c);
    if (k == 1999) {
      EXPECT_FALSE(node_->alarm()) << "no alarm before the step";
    }
  }
  EXPECT_TRUE(node_->active(2));
  EXPECT_FALSE(node_->active(0));
  EXPECT_TRUE(node_->alarm());
  EXPECT_TRUE(node_->monitors(2).cusum.alarm());
  bool line = false;
  ASSERT_EQ(alarm_line_.read(line), imu::hal::GpioStatus::kOk);
  EXPECT_TRUE(line);
}

TEST_F(NodeTest, NotStaticMeansNoFilterUpdate) {
  static_line_.set(false);
  send_config(100.0, 1e-4);
  for (std::uint32_t k = 0; k < 1000; ++k) {
    // Constant 0.2 after the 100-sample init window: a static filter would follow it.
    const std::int32_t v = k < 100 ? 0 : 2000;
    const std::int32_t c[6] = {v + 1, 1, 1, 1, 1, 1};
    send_sample(k, c);
  }
  EXPECT_FALSE(node_->is_static());
  // Not updated: the bias estimate stays at its prior 0 exactly (prediction only scales it).
  EXPECT_FLOAT_EQ(node_->bias(0), 0.0F) << "bias moved without static updates";
}

TEST_F(NodeTest, RefusedTelemetryIsCounted) {
  send_config();
  sink_.refuse = true;
  const std::int32_t c[6] = {1, 2, 3, 4, 5, 6};
  for (std::uint32_t k = 0; k < 100; ++k) {
    send_sample(k, c);
  }
  EXPECT_EQ(node_->stats().telemetry_failures, 3U);  // stats, bias, monitor: one frame each
  EXPECT_EQ(node_->stats().last_send_status, imu::hal::IoStatus::kLinkDown);
}

}  // namespace

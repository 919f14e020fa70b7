// Tests of the firmware node (fw/node, imu/node/node.hpp) through its public API: frames in,
// telemetry frames out through a capturing FrameSink, GPIO through hal::MemoryLine.
#include "imu/node/node.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <iterator>
#include <memory>
#include <utility>
#include <vector>

#include "imu/hal/codec.hpp"
#include "imu/hal/sim/memory_line.hpp"
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
    ++tries;
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
  std::size_t tries = 0;  ///< send() calls, refused or not
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
  // One step, one detection: the node moved the known signal to the new level (the init
  // window's mean, ~0, + 0.5; the size comes from the few updates between the step and the
  // alarm, sd ~0.033 / sqrt(5)) and the re-armed CUSUM stayed quiet for the remaining 1990.
  const imu::node::Node::LevelShifts& ls = node_->level_shifts(2);
  EXPECT_EQ(ls.count, 1U);
  EXPECT_NEAR(static_cast<double>(ls.last_update), 1900.0, 16.0);  // update 1900 = sample 2000
  EXPECT_NEAR(node_->known_signal(2), 0.5F, 0.06F);
  EXPECT_FALSE(node_->monitors(2).cusum.alarm()) << "re-armed after the detection";
  bool line = false;
  ASSERT_EQ(alarm_line_.read(line), imu::hal::GpioStatus::kOk);
  EXPECT_TRUE(line) << "the line stays set once a level shift was detected";
}

// A step of one noise sd, the size real IMUs show (one LSB of a coarse accelerometer): the
// CUSUM takes a few hundred updates to see it, over which the CUSUM's own start estimate (where
// its sum last was zero) can lie thousands of updates earlier. The step locator's start and
// size must still put the known signal on the new level: one detection, not a train of them.
// A clean run of the same length has none.
TEST_F(NodeTest, OneSigmaStepIsOneDetectionAndTheKnownSignalFollows) {
  for (const bool with_step : {false, true}) {
    SetUp();
    send_config(100.0, 1e-4);
    imu::GaussianRng rng(with_step ? 7 : 8);
    for (std::uint32_t k = 0; k < 30000; ++k) {
      const double v = 0.033 * rng.normal() + (with_step && k >= 10000 ? 0.033 : 0.0);
      const std::int32_t c[6] = {0, 0, static_cast<std::int32_t>(std::lround(v / 1e-4)), 0, 0, 0};
      send_sample(k, c);
    }
    const imu::node::Node::LevelShifts& ls = node_->level_shifts(2);
    if (!with_step) {
      EXPECT_EQ(ls.count, 0U);
      continue;
    }
    EXPECT_EQ(ls.count, 1U);
    EXPECT_NEAR(static_cast<double>(ls.last_update), 9900.0, 200.0);
    // The init window's mean has sd 0.033 / sqrt(100) = 0.0033; the size estimate's, over the
    // ~250 updates to the alarm, about 0.002.
    EXPECT_NEAR(node_->known_signal(2), 0.033F, 0.012F);
  }
}

// Each active channel's monitors travel on their own: the summary MonitorRecord gives the worst
// channel, which a report then showed as the selected channel's. Channel 2 steps, channel 3 is
// white noise of its model's size, the others are absent (no record).
TEST_F(NodeTest, EachActiveChannelSendsItsOwnMonitors) {
  send_config(100.0, 1e-5);
  imu::GaussianRng rng(41);
  for (std::uint32_t k = 0; k < 4000; ++k) {
    const double acc = 0.033 * rng.normal() + (k >= 2000 ? 0.5 : 0.0);
    const double gyro = 5.8e-3 * rng.normal();  // N = 5.8e-4 at 100 Hz: the default gyro model
    const std::int32_t c[6] = {0, 0, static_cast<std::int32_t>(std::lround(acc / 1e-5)),
                               static_cast<std::int32_t>(std::lround(gyro / 1e-5)), 0, 0};
    send_sample(k, c);
  }
  const auto ev = sink_.events();
  imu::hal::ChannelMonitorRecord last[6] = {};
  std::size_t seen[6] = {};
  for (const auto& e : ev) {
    if (e.type == imu::hal::RxEvent::Type::kChannelMonitor) {
      ASSERT_LT(e.rec.channel_monitor.channel, 6U);
      last[e.rec.channel_monitor.channel] = e.rec.channel_monitor;
      ++seen[e.rec.channel_monitor.channel];
    }
  }
  EXPECT_EQ(seen[0] + seen[1] + seen[4] + seen[5], 0U) << "records for absent channels";
  EXPECT_EQ(seen[2], count_type(ev, imu::hal::RxEvent::Type::kMonitor));
  EXPECT_EQ(seen[3], seen[2]);
  const imu::hal::ChannelMonitorRecord& step = last[2];
  const imu::hal::ChannelMonitorRecord& clean = last[3];
  EXPECT_NE(step.flags & imu::hal::kChanMonCusum, 0U);
  EXPECT_EQ(step.flags & imu::hal::kChanMonCusumDown, 0U) << "the step is upward";
  // The step is at update 1900 (after the 100 init samples); with the small slack (0.025) the
  // alarming sum may have left zero some hundreds of updates before it.
  EXPECT_GT(step.cusum_step_update, 1000U);
  EXPECT_LT(step.cusum_step_update, 2100U);
  EXPECT_EQ(clean.flags & imu::hal::kChanMonCusum, 0U);
  EXPECT_EQ(clean.n_states, 1U);
  EXPECT_EQ(clean.flags & imu::hal::kChanMonPushed, 0U);
  EXPECT_EQ(clean.blocks, 39U);  // 3900 updates in blocks of 100
  EXPECT_EQ(clean.updates, 3900U);
  // The whole-run NIS mean of white noise under its own model: 1 within a few sd of the
  // chi-square mean (sd sqrt(2 / 3900) = 0.023), and the record says so for this channel only.
  EXPECT_NEAR(clean.nis_mean, 1.0F, 0.12F);
  // The step shows in the stepped channel's NIS for the few updates before the node moved its
  // known signal (15 sigma: ~225 per update), far above the clean channel's 1 +- 0.023.
  EXPECT_GT(step.nis_mean, 1.5F) << "a 15-sigma step must show in the stepped channel's NIS";
  EXPECT_EQ(step.cusum_detections, 1U);
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
  // stats, bias, monitor, one channel monitor per active channel (6), rejects: one frame each
  EXPECT_EQ(node_->stats().telemetry_failures, 10U);
  EXPECT_EQ(node_->stats().last_send_status, imu::hal::IoStatus::kLinkDown);
}

// ---- Hostile bus : each of these failed before its fix. ----

// A valid sample whose sequence number jumps 2^31 - 16 ahead: one missing run of that length.
// It used to cost 2^31 prediction steps of six filters (tens of seconds); now mark_missing is
// O(levels) and ScalarBiasKf::predict(n) O(1). Bound: 0.5 s for nine frames and an idle flush
// (a few hundred microseconds measured), generous for a loaded machine and still 50x below the
// old cost.
TEST_F(NodeTest, SequenceJumpOfTwoToThe31IsConstantTime) {
  send_config();
  const std::int32_t c[6] = {3, 1, 1, 1, 1, 1};
  for (std::uint32_t k = 0; k < 200; ++k) {  // past init_samples (100): the filters run
    send_sample(k, c);
  }
  const std::uint32_t jump = 0x7FFFFFF0U;  // "ahead" for the receiver (below 2^31)
  const auto t0 = std::chrono::steady_clock::now();
  for (std::uint32_t k = 0; k < 9; ++k) {
    send_sample(200 + jump + k, c);
  }
  node_->on_idle();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(s, 0.5);
  EXPECT_EQ(node_->stats().missing, jump);
  EXPECT_EQ(node_->stats().samples, 209U);
  EXPECT_EQ(node_->adev().channel(0).missing_samples(), jump);
  EXPECT_EQ(node_->adev().channel(0).gaps(), 1U);
  EXPECT_TRUE(std::isfinite(node_->bias_var(0)));
  EXPECT_GT(node_->bias_var(0), 0.0F);
}

// A ConfigRecord with a new cfg_id but the values in use must not wipe the estimators (it did:
// any new id restarted the stream). A change of any value still does.
TEST_F(NodeTest, NewConfigIdWithTheSameValuesKeepsTheStream) {
  send_config(100.0, 1e-3, 1);
  const std::int32_t c[6] = {3, 1, 4, 1, 5, 9};
  for (std::uint32_t k = 0; k < 500; ++k) {
    send_sample(k, c, 1);
  }
  send_config(100.0, 1e-3, 2);
  EXPECT_EQ(node_->adev().channel(0).samples(), 500U);
  EXPECT_EQ(node_->stats().restarts, 0U);
  EXPECT_EQ(node_->stats().config_same_values, 1U);
  EXPECT_EQ(node_->sensor_config().cfg_id, 2U);
  for (std::uint32_t k = 500; k < 600; ++k) {
    send_sample(k, c, 2);
  }
  EXPECT_EQ(node_->adev().channel(0).samples(), 600U);
  send_config(100.0, 2e-3, 3);  // a new LSB: a new stream
  EXPECT_EQ(node_->stats().restarts, 1U);
  EXPECT_EQ(node_->adev().channel(0).samples(), 0U);
}

// Rates and LSBs outside [0.1 Hz, 100 kHz] and [1e-12, 1e3] are refused and counted; before,
// anything > 0 and < 1e6 passed (LSB 1e-300: every figure 0; rate 1e-300: every tau infinite).
TEST_F(NodeTest, ConfigOutOfRangeIsRefusedAndCounted) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double cases[][2] = {{1e-300, 1e-3}, {100.0, 1e-300}, {1e300, 1e-3}, {100.0, 1e300},
                             {0.05, 1e-3},   {2e5, 1e-3},     {nan, 1e-3},   {100.0, nan},
                             {100.0, inf},   {100.0, -1e-3},  {100.0, 1e4},  {100.0, 1e-13}};
  std::uint8_t id = 10;
  for (const auto& cs : cases) {
    send_config(cs[0], cs[1], id++);
  }
  EXPECT_FALSE(node_->have_config());
  EXPECT_EQ(node_->stats().bad_config, std::size(cases));
  send_config(imu::node::kMinRateHz, imu::node::kMinLsb, id++);  // the limits are accepted
  EXPECT_TRUE(node_->have_config());
  send_config(imu::node::kMaxRateHz, imu::node::kMaxLsb, id++);
  EXPECT_EQ(node_->stats().restarts, 1U);
  EXPECT_EQ(node_->stats().bad_config, std::size(cases));
}

// After a refused config (id 2, rate out of range) the samples of the config in use (id 1)
// are valid: they were counted as cfg_mismatch against the refused record's id.
TEST_F(NodeTest, ARefusedConfigLeavesTheSamplesOfTheConfigInUseValid) {
  send_config(100.0, 1e-3, 1);
  const std::int32_t c[6] = {3, 1, 4, 1, 5, 9};
  for (std::uint32_t k = 0; k < 100; ++k) {
    send_sample(k, c, 1);
  }
  send_config(1e-300, 1e-3, 2);
  EXPECT_EQ(node_->stats().bad_config, 1U);
  for (std::uint32_t k = 100; k < 200; ++k) {
    send_sample(k, c, 1);
  }
  EXPECT_EQ(node_->rx_stats().cfg_mismatch, 0U);
  EXPECT_EQ(node_->adev().channel(0).samples(), 200U);
  send_sample(200, c, 7);  // a sample of no config at all still counts
  EXPECT_EQ(node_->rx_stats().cfg_mismatch, 1U);
}

// Model parameters that are finite and positive but absurd used to pass configure() (checked
// at 100 Hz only, where first_order_gm_from_asd returned kOk with phi = 1, a NaN or an infinite
// Qn) and left the filters unconfigured. Also the range limits and the rate limits.
TEST_F(NodeTest, AbsurdModelParametersAreRefused) {
  const imu::node::ChannelModel bad[] = {{3.3e-3, 9e-4, 1e-300}, {3.3e-3, 9e-4, 1e300},
                                         {1e300, 9e-4, 300.0},   {3.3e-3, 1e300, 300.0},
                                         {1e-300, 9e-4, 300.0},  {3.3e-3, 9e-4, 0.01},
                                         {3.3e-3, 9e-4, 1e9}};
  for (const auto& m : bad) {
    Node n;
    NodeConfig c;
    c.model[3] = m;
    EXPECT_EQ(n.configure(c, sink_, nullptr, nullptr), imu::node::NodeStatus::kBadConfig)
        << m.n << " " << m.b << " " << m.tp_s;
    EXPECT_FALSE(imu::node::model_in_range(m));
  }
  // The range ends are accepted, and so is the default model.
  EXPECT_TRUE(imu::node::model_in_range({1e-12, 1e-12, imu::node::kMinTpS}));
  EXPECT_TRUE(imu::node::model_in_range({1e3, 1e3, imu::node::kMaxTpS}));
  Node n;
  EXPECT_EQ(n.configure(NodeConfig{}, sink_, nullptr, nullptr), imu::node::NodeStatus::kOk);
}

// Every refusal is in telemetry: the RejectsRecord after each status set, and the kernel's
// drop count (passed in by the host loop) in StatsRecord::kernel_drops, which was always 0.
TEST_F(NodeTest, RefusalsAndKernelDropsAreSentInTelemetry) {
  const std::int32_t c[6] = {1, 2, 3, 4, 5, 6};
  send_sample(0, c);              // before any config: ignored, counted
  send_config(1e-300, 1e-3, 7);   // refused
  send_config(100.0, 1e-3, 1);
  send_config(100.0, 1e-3, 2);    // same values, new id
  CanFrame rtr{};
  rtr.can_id = imu::hal::kIdSampleFd | imu::hal::kCanRtrFlag;
  node_->on_frame(rtr, imu::hal::kCanMtu, 0);
  node_->set_link_counters(17, 2);
  sink_.frames.clear();
  for (std::uint32_t k = 1; k <= 100; ++k) {
    send_sample(k, c, 2);
  }
  const auto ev = sink_.events();
  ASSERT_EQ(count_type(ev, imu::hal::RxEvent::Type::kRejects), 1U);
  for (const auto& e : ev) {
    if (e.type == imu::hal::RxEvent::Type::kStats) {
      EXPECT_EQ(e.rec.stats.kernel_drops, 17U);
    } else if (e.type == imu::hal::RxEvent::Type::kRejects) {
      const imu::hal::RejectsRecord& r = e.rec.rejects;
      EXPECT_EQ(r.bad_config, 1U);
      EXPECT_EQ(r.config_same_values, 1U);
      EXPECT_EQ(r.samples_before_config, 1U);
      EXPECT_EQ(r.remote_frames, 1U);
      EXPECT_EQ(r.peer_refused, 2U);
      EXPECT_EQ(r.model_rejected, 0U);
      EXPECT_EQ(r.telemetry_failures, 0U);
    }
  }
}

// Once the sink says the link is down, the rest of the telemetry is counted as failed without
// being tried: on a loopback listener each try waited send_timeout_ms (2 s) for a new peer, so a
// dead peer kept imu-fw alive for minutes. A received frame means a peer again.
TEST_F(NodeTest, TelemetryIsNotRetriedPerFrameWhileTheLinkIsDown) {
  send_config();
  sink_.refuse = true;
  const std::int32_t c[6] = {1, 2, 3, 4, 5, 6};
  for (std::uint32_t k = 0; k < 100; ++k) {
    send_sample(k, c);
  }
  node_->on_idle();  // a full set: status plus six ADEV curves, all refused
  EXPECT_EQ(sink_.tries, 1U);
  EXPECT_GT(node_->stats().telemetry_failures, 10U);
  sink_.refuse = false;
  for (std::uint32_t k = 100; k < 200; ++k) {
    send_sample(k, c);
  }
  EXPECT_EQ(sink_.tries, 11U);  // the next status set (10 records: 6 channels active) went out
  EXPECT_EQ(node_->stats().telemetry_frames, 10U);
}

}  // namespace

namespace {

imu::hal::ModelRecord echo_of(const std::vector<imu::hal::RxEvent>& ev, std::size_t chan) {
  imu::hal::ModelRecord last{};
  for (const auto& e : ev) {
    if (e.type == imu::hal::RxEvent::Type::kModelEcho && e.rec.model.channel == chan) {
      last = e.rec.model;
    }
  }
  return last;
}

}  // namespace

// A pushed model is validated completely before it is swapped in; a refused
// one keeps the old model and is counted; the echo says what runs.
TEST_F(NodeTest, PushedModelIsValidatedSwappedAndEchoed) {
  send_config(100.0, 1e-4);
  auto push_model = [this](const imu::hal::ModelRecord& m) {
    EncodedFrames fr{};
    imu::hal::encode(m, false, imu::hal::Layout::kFd, 0, fr);
    push(fr);
  };
  imu::hal::ModelRecord good{};
  good.version = imu::hal::kModelVersion1;
  good.channel = 2;
  good.n = 3.3e-3F;
  good.gm_sb[0] = 2.68e-8F;
  good.gm_tb_s[0] = 158.7F;
  good.k = 1.4e-4F;  // GM + RRW: 2 states
  push_model(good);
  auto ev = sink_.events();
  imu::hal::ModelRecord e = echo_of(ev, 2);
  EXPECT_EQ(e.flags & imu::hal::kModelPushed, imu::hal::kModelPushed);
  EXPECT_EQ(e.n_states, 2U);
  EXPECT_EQ(e.version, imu::hal::kModelVersion1) << "a version 1 push is echoed in version 1";
  EXPECT_EQ(node_->stats().model_rejected, 0U);
  EXPECT_EQ(echo_of(ev, 1).n_states, 1U) << "other channels keep the first-order one-state model";
  EXPECT_EQ(echo_of(ev, 1).flags, 0U);

  imu::hal::ModelRecord nan_rec = good;
  nan_rec.k = std::numeric_limits<float>::quiet_NaN();
  imu::hal::ModelRecord too_big = good;  // 2 GM + RRW + a flicker bank over 7 decades > 8
  too_big.gm_sb[1] = 1e-6F;
  too_big.gm_tb_s[1] = 0.2F;
  too_big.bi = 1e-3F;
  too_big.bi_tau_lo_s = 0.01F;
  too_big.bi_tau_hi_s = 1e5F;
  imu::hal::ModelRecord no_white = good;
  no_white.n = 0.0F;
  imu::hal::ModelRecord neg_tb = good;
  neg_tb.gm_tb_s[0] = -1.0F;
  std::uint64_t refused = 0;
  for (const auto& bad : {nan_rec, too_big, no_white, neg_tb}) {
    push_model(bad);
    ++refused;
    EXPECT_EQ(node_->stats().model_rejected, refused);
    e = echo_of(sink_.events(), 2);
    EXPECT_EQ(e.n_states, 2U) << "the old model stays";
    EXPECT_NEAR(e.k, 1.4e-4F, 1e-9F);  // the record travels as float32: bit-exact here
  }
  // The filter runs: 2000 samples of white noise give a finite bias and variance.
  imu::GaussianRng rng(5);
  for (std::uint32_t k = 0; k < 2000; ++k) {
    const std::int32_t c[6] = {0, 0, static_cast<std::int32_t>(std::lround(0.033 * rng.normal() / 1e-4)),
                               0, 0, 0};
    send_sample(k, c);
  }
  EXPECT_TRUE(std::isfinite(node_->bias(2)));
  EXPECT_GT(node_->bias_var(2), 0.0F);
  std::printf("RAM: sizeof(NodeFilter) = %zu bytes per channel (%zu process states), "
              "sizeof(Node) = %zu\n",
              sizeof(imu::node::NodeFilter), imu::node::kNodeProcessStates, sizeof(Node));
}

namespace {

std::uint32_t fbits(float v) {
  std::uint32_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// Every field of two model records, bit for bit (n_states and flags aside).
void expect_same_model(const imu::hal::ModelRecord& a, const imu::hal::ModelRecord& b) {
  const float fa[] = {a.n, a.q, a.gm_sb[0], a.gm_tb_s[0], a.gm_sb[1], a.gm_tb_s[1], a.k, a.bi,
                      a.bi_tau_lo_s, a.bi_tau_hi_s, a.n_filter_s, a.osc_sigma, a.osc_f0_hz,
                      a.osc_beta_per_s};
  const float fb[] = {b.n, b.q, b.gm_sb[0], b.gm_tb_s[0], b.gm_sb[1], b.gm_tb_s[1], b.k, b.bi,
                      b.bi_tau_lo_s, b.bi_tau_hi_s, b.n_filter_s, b.osc_sigma, b.osc_f0_hz,
                      b.osc_beta_per_s};
  for (std::size_t i = 0; i < std::size(fa); ++i) {
    EXPECT_EQ(fbits(fa[i]), fbits(fb[i])) << "field " << i;
  }
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.channel, b.channel);
}

// The version 2 model of the tests: white noise through a 2 ms output filter (1 state), one GM
// (1), a 6 Hz oscillation 0.5 Hz wide (2): 4 states.
imu::hal::ModelRecord model_v2(std::uint8_t channel) {
  imu::hal::ModelRecord m{};
  m.version = imu::hal::kModelVersion2;
  m.channel = channel;
  m.n = 3.3e-3F;
  m.gm_sb[0] = 2.68e-8F;
  m.gm_tb_s[0] = 158.7F;
  m.n_filter_s = 2e-3F;
  m.osc_sigma = 0.02F;
  m.osc_f0_hz = 6.0F;
  m.osc_beta_per_s = 1.57F;
  return m;
}

}  // namespace

// A version 2 push with the output filter and the oscillation runs: the node validates and
// discretises it, echoes it in version 2 (0x252) with every field bit for bit and the states
// it runs (GM 1 + filter 1 + oscillation 2), and the filter runs on samples. A version 1 push
// after it is echoed in version 1 again; channels never pushed are echoed in version 1.
TEST_F(NodeTest, PushedModelVersion2RunsTheOutputFilterAndTheOscillation) {
  send_config(100.0, 1e-4);
  const imu::hal::ModelRecord m = model_v2(2);
  EncodedFrames fr{};
  imu::hal::encode(m, false, imu::hal::Layout::kClassic, 3, fr);  // 10 classic frames
  ASSERT_EQ(fr.count, 10U);
  push(fr);
  EXPECT_EQ(node_->stats().model_rejected, 0U);
  EXPECT_EQ(node_->stats().models_accepted, 1U);
  bool v2_frame = false;
  for (const CanFrame& f : sink_.frames) {
    v2_frame = v2_frame || f.can_id == imu::hal::kIdModelEcho2Fd;
  }
  EXPECT_TRUE(v2_frame) << "the echo of a version 2 push is a version 2 record";
  auto ev = sink_.events();
  const imu::hal::ModelRecord e = echo_of(ev, 2);
  EXPECT_EQ(e.flags, imu::hal::kModelPushed);
  EXPECT_EQ(e.n_states, 4U);
  expect_same_model(e, m);
  EXPECT_EQ(node_->model_echo(2).n_states, 4U);
  EXPECT_EQ(echo_of(ev, 1).version, imu::hal::kModelVersion1) << "channel 1 was never pushed";
  imu::ModelParams p{};
  ASSERT_TRUE(imu::node::model_record_valid(m, p));
  EXPECT_DOUBLE_EQ(p.n_filter_s, static_cast<double>(m.n_filter_s));
  EXPECT_DOUBLE_EQ(p.osc_sigma, static_cast<double>(m.osc_sigma));
  EXPECT_DOUBLE_EQ(p.osc_f0_hz, static_cast<double>(m.osc_f0_hz));
  EXPECT_DOUBLE_EQ(p.osc_beta_per_s, static_cast<double>(m.osc_beta_per_s));

  // The filter runs: white noise plus a 6 Hz tone give a finite bias and a positive variance.
  imu::GaussianRng rng(9);
  for (std::uint32_t k = 0; k < 2000; ++k) {
    const double x = 0.033 * rng.normal() + 0.02 * std::sin(2.0 * 3.141592653589793 * 6.0 * k / 100.0);
    const std::int32_t c[6] = {0, 0, static_cast<std::int32_t>(std::lround(x / 1e-4)), 0, 0, 0};
    send_sample(k, c);
  }
  EXPECT_TRUE(std::isfinite(node_->bias(2)));
  EXPECT_GT(node_->bias_var(2), 0.0F);
  EXPECT_GT(node_->monitors(2).cusum.updates(), 1000U);  // the updates after the first 100

  // A new rate rebuilds it (the oscillation and the filter at 1 kHz) and keeps it.
  send_config(1000.0, 1e-4, 2);
  EXPECT_EQ(node_->stats().model_rejected, 0U);
  EXPECT_EQ(node_->model_echo(2).n_states, 4U);

  // A version 1 push on the same channel: echoed in version 1, the new terms gone.
  imu::hal::ModelRecord v1{};
  v1.version = imu::hal::kModelVersion1;
  v1.channel = 2;
  v1.n = 3.3e-3F;
  v1.k = 1.4e-4F;
  imu::hal::encode(v1, false, imu::hal::Layout::kFd, 0, fr);
  (void)sink_.events();
  push(fr);
  const imu::hal::ModelRecord e1 = echo_of(sink_.events(), 2);
  EXPECT_EQ(e1.version, imu::hal::kModelVersion1);
  EXPECT_EQ(e1.n_states, 1U);
  EXPECT_EQ(fbits(e1.osc_sigma) | fbits(e1.n_filter_s), 0U);
}

// Each version 2 field out of its range, one at a time, is refused and counted; the model
// running (the version 2 one) stays and is echoed unchanged.
TEST_F(NodeTest, PushedModelVersion2RangesAreEnforced) {
  send_config(100.0, 1e-4);
  const imu::hal::ModelRecord good = model_v2(2);
  auto push_model = [this](const imu::hal::ModelRecord& m) {
    EncodedFrames fr{};
    imu::hal::encode(m, false, imu::hal::Layout::kFd, 0, fr);
    push(fr);
  };
  push_model(good);
  ASSERT_EQ(node_->stats().model_rejected, 0U);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  struct Bad {
    const char* what;
    float imu::hal::ModelRecord::*field;
    float value;
  };
  using R = imu::hal::ModelRecord;
  const Bad bad[] = {
      {"n_filter_s NaN", &R::n_filter_s, nan},
      {"n_filter_s inf", &R::n_filter_s, inf},
      {"n_filter_s < 0", &R::n_filter_s, -2e-3F},
      {"n_filter_s < 1e-6", &R::n_filter_s, 5e-7F},
      {"n_filter_s > 1e3", &R::n_filter_s, 2e3F},
      {"osc_sigma NaN", &R::osc_sigma, nan},
      {"osc_sigma < 0", &R::osc_sigma, -0.02F},
      {"osc_sigma < 1e-15", &R::osc_sigma, 5e-16F},
      {"osc_sigma > 1e3", &R::osc_sigma, 2e3F},
      {"osc_f0_hz NaN", &R::osc_f0_hz, nan},
      {"osc_f0_hz < 0", &R::osc_f0_hz, -1.0F},
      {"osc_f0_hz > 5e4", &R::osc_f0_hz, 6e4F},
      {"osc_beta_per_s inf", &R::osc_beta_per_s, inf},
      {"osc_beta_per_s 0", &R::osc_beta_per_s, 0.0F},
      {"osc_beta_per_s < 1e-6", &R::osc_beta_per_s, 5e-7F},
      {"osc_beta_per_s > 1e6", &R::osc_beta_per_s, 2e6F},
  };
  std::uint64_t refused = 0;
  const auto expect_refused = [&](const imu::hal::ModelRecord& m, const char* what) {
    push_model(m);
    ++refused;
    EXPECT_EQ(node_->stats().model_rejected, refused) << what;
    const imu::hal::ModelRecord e = echo_of(sink_.events(), 2);
    EXPECT_EQ(e.n_states, 4U) << what << ": the old model stays";
    expect_same_model(e, good);
    EXPECT_EQ(node_->stats().models_accepted, 1U) << what;
  };
  for (const Bad& b : bad) {
    imu::hal::ModelRecord m = good;
    m.*b.field = b.value;
    expect_refused(m, b.what);
  }
  // An absent oscillation (sigma 0) must have f0 = beta = 0.
  for (const bool f0 : {true, false}) {
    imu::hal::ModelRecord m = good;
    m.osc_sigma = 0.0F;
    m.osc_f0_hz = f0 ? 6.0F : 0.0F;
    m.osc_beta_per_s = f0 ? 0.0F : 1.57F;
    expect_refused(m, f0 ? "f0 without an oscillation" : "beta without an oscillation");
  }
  // N is still required with an output filter (it is the white noise's density).
  imu::hal::ModelRecord no_n = good;
  no_n.n = 0.0F;
  expect_refused(no_n, "no white noise");
  // The edges of the ranges are accepted (both ends included).
  for (const auto& edge : {std::pair<float R::*, float>{&R::n_filter_s, 1e-6F},
                           std::pair<float R::*, float>{&R::osc_f0_hz, 0.0F}}) {
    imu::hal::ModelRecord m = good;
    m.*edge.first = edge.second;
    imu::ModelParams p{};
    EXPECT_TRUE(imu::node::model_record_valid(m, p));
  }
  // In memory only (a version 1 record has no slot for them on the wire): version 1 with a
  // filter or an oscillation is not valid.
  imu::hal::ModelRecord v1 = good;
  v1.version = imu::hal::kModelVersion1;
  imu::ModelParams p{};
  EXPECT_FALSE(imu::node::model_record_valid(v1, p));
  v1.n_filter_s = 0.0F;
  v1.osc_sigma = v1.osc_f0_hz = v1.osc_beta_per_s = 0.0F;
  EXPECT_TRUE(imu::node::model_record_valid(v1, p));
}

// The state count with the version 2 terms: the filter 1, the oscillation 2, so 2 GM + RRW +
// filter + oscillation = 6 leaves room for a flicker bank of 2 members (8 states) and no more.
TEST_F(NodeTest, PushedModelVersion2StatesAreCountedAgainstTheFilter) {
  imu::hal::ModelRecord m = model_v2(1);
  m.gm_sb[1] = 1e-6F;
  m.gm_tb_s[1] = 0.2F;
  m.k = 1.4e-4F;
  m.bi = 1e-3F;
  m.bi_tau_lo_s = 1.0F;
  bool saw_8 = false;
  bool saw_9 = false;
  for (const float hi : {1.5F, 3.0F, 10.0F, 30.0F, 100.0F, 1e3F}) {
    m.bi_tau_hi_s = hi;
    imu::GmParam bank[imu::kMaxFlickerGm] = {};
    const std::size_t nb = imu::flicker_bank(1e-3, 1.0, static_cast<double>(hi), bank);
    ASSERT_GT(nb, 0U);
    imu::ModelParams p{};
    EXPECT_EQ(imu::node::model_record_valid(m, p), 6 + nb <= imu::node::kNodeProcessStates)
        << "flicker bank of " << nb;
    saw_8 = saw_8 || 6 + nb == 8;
    saw_9 = saw_9 || 6 + nb == 9;
  }
  EXPECT_TRUE(saw_8 && saw_9) << "the ranges tried reach both sides of the limit";
  // Over the wire: a 9-state model is refused and counted, the channel keeps its default.
  send_config(100.0, 1e-4);
  m.bi_tau_hi_s = 1e3F;
  EncodedFrames fr{};
  imu::hal::encode(m, false, imu::hal::Layout::kFd, 0, fr);
  push(fr);
  EXPECT_EQ(node_->stats().model_rejected, 1U);
  const imu::hal::ModelRecord e = echo_of(sink_.events(), 1);
  EXPECT_EQ(e.flags, 0U);
  EXPECT_EQ(e.n_states, 1U);
  EXPECT_EQ(e.version, imu::hal::kModelVersion2) << "answered in the version pushed";
}

namespace {

imu::hal::ModelSignalsRecord signals_echo_of(const std::vector<imu::hal::RxEvent>& ev,
                                             std::size_t chan, std::size_t& count) {
  imu::hal::ModelSignalsRecord last{};
  count = 0;
  for (const auto& e : ev) {
    if (e.type == imu::hal::RxEvent::Type::kModelSignalsEcho && e.rec.signals.channel == chan) {
      last = e.rec.signals;
      ++count;
    }
  }
  return last;
}

}  // namespace

// The deterministic terms travel in their own record before the channel's ModelRecord: the
// node runs them as states beside the stochastic terms (ramp 2, each sinusoid 2), echoes them,
// counts them against its states, refuses what is out of range, and keeps them across a rate
// change; a later ModelRecord without them replaces the whole model.
TEST_F(NodeTest, DeterministicTermsRunWithTheModelTheyCameWith) {
  send_config(100.0, 1e-4);
  const auto push_model = [this](const imu::hal::ModelRecord& m) {
    EncodedFrames fr{};
    imu::hal::encode(m, false, imu::hal::Layout::kFd, 0, fr);
    push(fr);
  };
  const auto push_signals = [this](const imu::hal::ModelSignalsRecord& s) {
    EncodedFrames fr{};
    imu::hal::encode(s, false, imu::hal::Layout::kClassic, 3, fr);
    push(fr);
  };
  imu::hal::ModelRecord m{};
  m.version = imu::hal::kModelVersion2;
  m.channel = 2;
  m.n = 3.3e-3F;
  m.gm_sb[0] = 2.68e-8F;
  m.gm_tb_s[0] = 158.7F;
  imu::hal::ModelSignalsRecord s{};
  s.channel = 2;
  s.ramp_r = -2e-6F;
  s.sin_a[0] = 0.01F;
  s.sin_f0_hz[0] = 0.37F;
  s.memory_s = 3600.0F;
  push_signals(s);
  EXPECT_EQ(node_->stats().model_rejected, 0U);
  push_model(m);
  EXPECT_EQ(node_->stats().models_accepted, 1U);
  std::vector<imu::hal::RxEvent> ev = sink_.events();
  std::size_t echoes = 0;
  imu::hal::ModelSignalsRecord se = signals_echo_of(ev, 2, echoes);
  EXPECT_EQ(echoes, 1U);
  EXPECT_EQ(se.flags, imu::hal::kModelPushed);
  EXPECT_EQ(se.ramp_r, s.ramp_r);
  EXPECT_EQ(se.sin_f0_hz[0], s.sin_f0_hz[0]);
  EXPECT_EQ(se.memory_s, s.memory_s);
  EXPECT_EQ(echo_of(ev, 2).n_states, 5U) << "GM 1 + ramp 2 + sinusoid 2";
  (void)signals_echo_of(ev, 1, echoes);
  EXPECT_EQ(echoes, 0U) << "channels without deterministic terms send no signals echo";

  // Out of range (a second sinusoid without a first; a NaN; a memory under 1 s): refused at
  // once, the model running stays.
  imu::hal::ModelSignalsRecord second_only{};
  second_only.channel = 2;
  second_only.sin_a[1] = 0.01F;
  second_only.sin_f0_hz[1] = 1.0F;
  imu::hal::ModelSignalsRecord nan_sig = s;
  nan_sig.sin_f0_hz[0] = std::numeric_limits<float>::quiet_NaN();
  imu::hal::ModelSignalsRecord short_memory = s;
  short_memory.memory_s = 0.5F;
  std::uint64_t refused = 0;
  for (const auto& bad : {second_only, nan_sig, short_memory}) {
    push_signals(bad);
    EXPECT_EQ(node_->stats().model_rejected, ++refused);
  }
  ev = sink_.events();
  EXPECT_EQ(echo_of(ev, 2).n_states, 5U);

  // The model with them over the node's states: refused, counted, the old model stays.
  imu::hal::ModelRecord big = m;
  big.k = 1.4e-4F;
  big.bi = 1e-3F;
  big.bi_tau_lo_s = 1.0F;
  big.bi_tau_hi_s = 100.0F;  // 4 members: 1 + 1 + 4 + 4 = 10 > 8 with the signals
  imu::ModelParams alone{};
  ASSERT_TRUE(imu::node::model_record_valid(big, alone)) << "8 states without the signals";
  push_signals(s);
  push_model(big);
  EXPECT_EQ(node_->stats().model_rejected, ++refused);
  ev = sink_.events();
  EXPECT_EQ(echo_of(ev, 2).n_states, 5U);

  // A rate change rebuilds the model with its deterministic terms.
  send_config(200.0, 1e-4, 2);
  EXPECT_EQ(node_->stats().restarts, 1U);
  EXPECT_EQ(node_->stats().model_rejected, refused);
  EXPECT_EQ(node_->signals_echo(2).flags, imu::hal::kModelPushed);
  EXPECT_EQ(node_->signals_echo(2).sin_a[0], s.sin_a[0]);
  EXPECT_EQ(node_->model_echo(2).n_states, 5U);

  // A ModelRecord with nothing pushed before it replaces the whole model: no signals now.
  push_model(m);
  EXPECT_EQ(node_->model_echo(2).n_states, 1U);
  EXPECT_EQ(node_->signals_echo(2).flags, 0U);
  EXPECT_EQ(node_->stats().models_accepted, 2U);
}

// The firmware node core: what the IMU co-processor runs, as a plain C++17 class.
//
// Frames are pushed in (on_frame); the node reassembles them through hal::Receiver, feeds every
// sample to the online ADEV of the six channels (imu::MultiAdev) and to one scalar bias Kalman
// filter per channel (imu::ScalarBiasKf<float>, the first-order model) with its residual
// monitors (imu::ResidualMonitors), drives the alarm output while any monitor fires, and sends
// telemetry frames (hal codec records) to a FrameSink:
//   every status_period_samples:  StatsRecord, BiasRecord, MonitorRecord (the summary), one
//                                 ChannelMonitorRecord per active channel, RejectsRecord (in
//                                 that order);
//   every adev_period_samples:    the same, then the full ADEV curve of every channel;
//   at on_idle() / finish():      the same full set if samples arrived since the last one.
// A consumer that knows how many samples it sent recognises the final curves as the first
// complete ADEV set after a StatsRecord with samples + missing >= that number.
//
// Samples are interpreted with the last ConfigRecord (rate, LSB per channel); samples before
// the first ConfigRecord are counted (stats.samples_before_config) and ignored. A ConfigRecord
// outside the accepted ranges (config_in_range) is refused and counted (bad_config). One with a
// new cfg_id and different values restarts the estimators (a new stream); one with a new cfg_id
// and the same values only adopts the id (config_same_values). Missing samples reported by the
// receiver go to MultiAdev::mark_missing (O(levels)) and ScalarBiasKf::predict(n) (O(1)): a
// forged sequence number 2^31 ahead costs the same as one lost sample (a pushed model: at most
// kMaxGapSteps predictions).
// Pushed models (ModelRecord): see on_model in node.cpp and host_sim/README.md; a
// channel runs either the first-order model (ScalarBiasKf) or its pushed model's NodeFilter.
// Filter: the known signal of each channel (gravity + initial bias) is the mean of its first
// init_samples samples; the filter then estimates the bias relative to it, updating only while
// the static input is active (no input: always static). A channel whose counts have all been 0
// since the stream started is inactive (no filter, no monitor, no alarm): a real sensor channel
// is never exactly zero, a channel absent from a recording is. The static input is read once per
// status period, not per sample (one GPIO ioctl per period).
//
// Memory: sizeof(Node) is the whole state (62.8 kB on x86-64, mostly six OnlineAdev<8,22> and
// six NodeFilters for pushed models); no
// heap, no exceptions, no OS calls: the library is compiled with fw/src/fw_prelude.hpp. Not
// re-entrant on one instance. Cost per sample: 6 ADEV pushes (amortised ~12 multiply-adds each)
// + 6 scalar filter steps + monitors; a full ADEV telemetry set is 6 snapshots (O(96 * 8)) and
// up to 6 * 96 frames.
#ifndef IMU_NODE_NODE_HPP
#define IMU_NODE_NODE_HPP

#include <cstddef>
#include <cstdint>

#include "imu/averaged_kf.hpp"
#include "imu/bias_kf.hpp"
#include "imu/error_model.hpp"
#include "imu/hal/codec.hpp"
#include "imu/hal/frame_io.hpp"
#include "imu/hal/digital_line.hpp"
#include "imu/hal/receiver.hpp"
#include "imu/online_adev.hpp"
#include "imu/residual_monitor.hpp"

namespace imu::node {

inline constexpr std::size_t kChannels = hal::kChannels;
using NodeAdev = MultiAdev<kChannels, 8, 22>;
inline constexpr std::size_t kMaxAdevPoints = NodeAdev::Channel::kMaxPoints;
static_assert(kMaxAdevPoints <= 255, "AdevRecord::index is 8 bits");

/// The example's parameters of one channel's first-order model (imu::first_order_gm_from_asd).
struct ChannelModel {
  double n;     ///< white noise N [unit/sqrt(Hz)]
  double b;     ///< bias instability B [unit]
  double tp_s;  ///< delay of the model's ADEV peak [s]
};

// Accepted ranges (both ends included). ConfigRecord: 0.1 Hz .. 100 kHz covers every IMU
// output rate; an LSB of 1e-12 .. 1e3 channel units (m/s^2, rad/s) per count keeps every
// count * LSB and its square normal in float (int32 full scale * 1e3 = 2e12; 1e-12^2 = 1e-24
// > FLT_MIN) and is 6 orders below / above any real sensor. ChannelModel: N and B in
// 1e-12 .. 1e3 channel units, Tp in 0.1 s .. 1e8 s (3 years); the model must also give a valid
// filter at both rate limits.
inline constexpr double kMinRateHz = 0.1;
inline constexpr double kMaxRateHz = 1e5;
inline constexpr double kMinLsb = 1e-12;
inline constexpr double kMaxLsb = 1e3;
inline constexpr double kMinModelNoise = 1e-12;
inline constexpr double kMaxModelNoise = 1e3;
inline constexpr double kMinTpS = 0.1;
inline constexpr double kMaxTpS = 1e8;

/// True if every parameter is in the ranges above and the first-order model and its filter
/// are valid at kMinRateHz and kMaxRateHz. O(1) (two small matrix exponentials).
[[nodiscard]] bool model_in_range(const ChannelModel& m);
/// Largest pushed model the node runs: kNodeProcessStates states of its terms (e.g. 2 GM + RRW +
/// a flicker bank of at most 5 decades) and one more, the sample mean over its interval: the
/// node observes the model through an averaging sampler (imu::discretize_averaged), as the
/// sensor delivers it and as the fit's AVAR formulas describe it. Filters are NodeFilter
/// (imu::AveragedKf, computed on the model's block structure): a model with fewer states costs
/// less.
inline constexpr std::size_t kNodeProcessStates = 8;
inline constexpr std::size_t kNodeStates = kNodeProcessStates + 1;
using NodeFilter = AveragedKf<float, kNodeProcessStates>;
/// Accepted ranges of a pushed ModelRecord (both ends included, zero = term absent where noted):
/// N in 1e-12 .. 1e3 (required: the filter needs measurement noise, and with an output filter N
/// is still the white noise's density, the filter only shapes it); Q, K, B in 0 or
/// 1e-15 .. 1e3; a GM's Sb in 0 or 1e-30 .. 1e6 with Tb in 1e-3 .. 1e8 s; the flicker range
/// 1e-3 .. 1e8 s with lo < hi. Version 2 only (0 in version 1): the output filter's time
/// constant in 0 or 1e-6 .. 1e3 s; the oscillation absent (sigma, f0 and beta all 0) or sigma
/// in 1e-15 .. 1e3, f0 in 0 .. 5e4 Hz, beta in 1e-6 .. 1e6 per s. The deterministic terms
/// travel in a ModelSignalsRecord (model_signals_valid).
inline constexpr float kMaxPushedTbS = 1e8F;
inline constexpr float kMinPushedTbS = 1e-3F;
inline constexpr float kMinPushedFilterS = 1e-6F;
inline constexpr float kMaxPushedFilterS = 1e3F;
inline constexpr float kMaxPushedOscF0Hz = 5e4F;
inline constexpr float kMinPushedOscBetaPerS = 1e-6F;
inline constexpr float kMaxPushedOscBetaPerS = 1e6F;
/// Lags of each channel's whiteness monitor (ResidualMonitors: Box-Pierce over lags 1..4).
inline constexpr std::size_t kMonitorLags = 4;
using NodeMonitors = ResidualMonitors<kMonitorLags>;
/// Missing samples beyond this are predicted as this many steps (the GM states have forgotten
/// everything long before; RRW variance is capped by the filter): a 2^31 jump stays O(1).
inline constexpr std::uint64_t kMaxGapSteps = 4096;

/// Accepted ranges of a pushed ModelSignalsRecord (both ends included): |R| in 0 or
/// 1e-15 .. 1e3; each sinusoid absent (A = f0 = 0) or A in 1e-15 .. 1e3 with f0 in
/// (0, 5e4] Hz, the second only beside the first; the memory 0 (constant terms) or
/// 1 .. 1e8 s.
inline constexpr float kMinSignalMemoryS = 1.0F;
inline constexpr float kMaxSignalMemoryS = 1e8F;

/// Filter states of a model the node would build from p: the output filter, each GM, each
/// flicker bank member and the walk 1; ramp, each sinusoid and the oscillation 2 (what
/// imu::build_model makes). The sample mean is not counted. O(1).
[[nodiscard]] std::size_t pushed_states(const ModelParams& p);

/// Validate a pushed model record (version 1 or 2) and build its parameters: every field finite
/// and in the ranges above, and the model (flicker bank rebuilt by imu::flicker_bank; the
/// output filter 1 state, the oscillation 2) has at least one state and at most
/// kNodeProcessStates - reserved_states (the states of the deterministic terms that go with it).
/// Does not discretise. O(1).
[[nodiscard]] bool model_record_valid(const hal::ModelRecord& r, ModelParams& out,
                                      std::size_t reserved_states = 0);
/// States of the deterministic terms of r (ramp 2, each sinusoid 2), whether valid or not. O(1).
[[nodiscard]] std::size_t signal_states(const hal::ModelSignalsRecord& r);
/// Validate a pushed ModelSignalsRecord (every field finite and in the ranges above) and add
/// its terms to p (ramp, sinusoids, signal_memory_s): false, p unchanged, if a field is out of
/// range or the model with them would exceed kNodeProcessStates. O(1).
[[nodiscard]] bool model_signals_valid(const hal::ModelSignalsRecord& r, ModelParams& p);
/// Build and discretise a pushed model at rate_hz (Van Loan per term, averaging sampler):
/// n_states process states + the sample mean in out; false if any step fails. O(n^4) flops for
/// the initial covariance, a few thousand at the largest model.
[[nodiscard]] bool discretize_pushed(const ModelParams& p, double rate_hz,
                                     DiscreteModel<kNodeStates>& out, std::size_t& n_states);

/// True if the rate and every LSB are in the ranges above. O(1).
[[nodiscard]] bool config_in_range(const hal::ConfigRecord& c);

/// Defaults: accelerometers the first-order model (N = 3.3e-3 m/s/sqrt(s), B = 9e-4 m/s^2,
/// Tp = 300 s); gyros the ADIS16405 datasheet's typical angle random walk 2 deg/sqrt(h)
/// (5.8e-4 rad/s/sqrt(Hz)) and in-run bias stability 0.007 deg/s (1.2e-4 rad/s), Tp = 300 s.
/// Replace them with a fitted model for real use.
struct NodeConfig {
  std::uint32_t status_period_samples = 100;   ///< stats, bias, monitor (1 s at 100 Hz); >= 1
  std::uint32_t adev_period_samples = 6000;    ///< full ADEV curves (60 s at 100 Hz); 0: never
  std::uint32_t init_samples = 1000;           ///< known-signal average per channel; >= 1
  std::uint32_t monitor_window = 1000;         ///< residual monitor block, updates; >= 16
  ChannelModel model[kChannels] = {{3.3e-3, 9e-4, 300.0}, {3.3e-3, 9e-4, 300.0},
                                   {3.3e-3, 9e-4, 300.0}, {5.8e-4, 1.2e-4, 300.0},
                                   {5.8e-4, 1.2e-4, 300.0}, {5.8e-4, 1.2e-4, 300.0}};
  hal::Layout layout = hal::Layout::kFd;       ///< telemetry frame layout
  int send_timeout_ms = 2000;                  ///< per telemetry frame (back-pressure wait)
  bool telemetry = true;                       ///< false: listen only (e.g. a canplayer replay)
};

enum class NodeStatus : std::uint8_t {
  kOk = 0,
  kBadConfig,  ///< a period or window out of range, or a channel model rejected
};

/// Counters of the node itself (the receiver's are in rx_stats()).
struct NodeStats {
  std::uint64_t samples = 0;                ///< samples processed (after the first config)
  std::uint64_t missing = 0;                ///< samples marked missing
  std::uint64_t samples_before_config = 0;  ///< ignored: no ConfigRecord yet
  std::uint64_t configs = 0;                ///< ConfigRecords received
  std::uint64_t restarts = 0;               ///< ConfigRecords with a new cfg_id after the first
  std::uint64_t bad_config = 0;             ///< ConfigRecords refused (config_in_range)
  std::uint64_t config_same_values = 0;     ///< new cfg_id, same values: id adopted, no restart
  std::uint64_t model_rejected = 0;         ///< pushed models refused (old model kept)
  std::uint64_t models_accepted = 0;        ///< pushed models swapped in
  std::uint64_t saturated = 0;              ///< samples with a sat_mask bit set
  std::uint64_t telemetry_frames = 0;       ///< frames sent
  std::uint64_t telemetry_failures = 0;     ///< frames the sink refused or not tried (link down)
  std::uint64_t status_sets = 0;            ///< stats/bias/monitor triples sent
  std::uint64_t adev_sets = 0;              ///< full ADEV telemetry sets sent
  std::uint64_t gpio_errors = 0;            ///< static input read / alarm write failures
  std::uint64_t alarm_changes = 0;          ///< alarm output transitions
  hal::IoStatus last_send_status = hal::IoStatus::kOk;
};

class Node {
 public:
  Node() = default;

  /// Set up (and reset) the node. tx receives telemetry; static_in / alarm_out may be null
  /// (always static / no alarm line). The referenced objects must outlive the node. O(1).
  [[nodiscard]] NodeStatus configure(const NodeConfig& cfg, hal::FrameSink& tx,
                                     hal::DigitalInput* static_in, hal::DigitalOutput* alarm_out);

  /// One received frame (nbytes as delivered by the transport). O(frame + events).
  void on_frame(const hal::CanFrame& f, std::size_t nbytes, std::uint64_t rx_time_ns);

  /// The bus was idle: release samples held in the reorder window and, if samples arrived since
  /// the last full telemetry set, send one. O(full set).
  void on_idle();

  /// End of stream: same as on_idle(). Telemetry is not sent if the sink is gone (counted).
  void finish() { on_idle(); }

  /// Send stats, bias, monitor and rejects records now. O(1) frames.
  void send_status();

  /// Counters of the transport that the node core cannot read itself, passed in by the host
  /// loop (node_loop) after each batch and sent in telemetry: the kernel's cumulative receive
  /// queue drops (SO_RXQ_OVFL, StatsRecord::kernel_drops) and loopback peers refused
  /// (RejectsRecord::peer_refused). O(1).
  void set_link_counters(std::uint64_t kernel_drops, std::uint64_t peer_refused) {
    kernel_drops_ = kernel_drops;
    peer_refused_ = peer_refused;
  }
  /// Send status and every channel's ADEV curve now.
  void send_full();

  [[nodiscard]] const NodeAdev& adev() const { return adev_; }
  [[nodiscard]] const NodeStats& stats() const { return stats_; }
  [[nodiscard]] const hal::RxStats& rx_stats() const { return rx_.stats(); }
  [[nodiscard]] bool have_config() const { return have_cfg_; }
  [[nodiscard]] const hal::ConfigRecord& sensor_config() const { return cfg_; }
  /// Bias estimate (channel units, relative to the known signal) and its variance.
  [[nodiscard]] float bias(std::size_t c) const {
    return pushed_[c] ? kfn_[c].bias() : kf_[c].bias();
  }
  [[nodiscard]] float bias_var(std::size_t c) const {
    return pushed_[c] ? kfn_[c].bias_variance() : kf_[c].variance();
  }
  /// What channel c runs: the first-order one-state model (flags 0, n_states 1) or a pushed one.
  /// In the version of the channel's last push (version 1 before any), and in version 2
  /// whenever the model it runs was pushed in version 2 (version 1 may not describe it).
  [[nodiscard]] hal::ModelRecord model_echo(std::size_t c) const;
  /// The deterministic terms channel c runs with its pushed model (flags kModelPushed), or a
  /// record with every term 0 and flags 0 when it runs none.
  [[nodiscard]] hal::ModelSignalsRecord signals_echo(std::size_t c) const;
  /// Channel c runs a pushed model whose filter has frozen its steady-state gain.
  [[nodiscard]] bool filter_steady(std::size_t c) const { return pushed_[c] && kfn_[c].steady(); }
  [[nodiscard]] float known_signal(std::size_t c) const { return known_[c]; }
  [[nodiscard]] const NodeMonitors& monitors(std::size_t c) const { return mon_[c]; }
  /// Level shifts the channel's CUSUM detected since the stream (re)started. At each one the
  /// node moves the channel's known signal by the step's size and re-arms the CUSUM, so one
  /// step is one detection and the filter goes on from the new level (a latched alarm would
  /// leave the filter off by the step and the monitor blind for the rest of the run). Start and
  /// size come from the monitors' StepLocator: the mean innovation after the start. What the filter's
  /// states took up of the step before the alarm stays in them and decays with the model (the
  /// states' change cannot be told from their own motion: a sinusoid's, a Gauss-Markov term's).
  struct LevelShifts {
    std::uint32_t count = 0;
    std::uint64_t last_update = 0;  ///< the update after which the last detected step began
    float last_size = 0.0F;         ///< the known signal's move then (channel units, signed)
  };
  [[nodiscard]] const LevelShifts& level_shifts(std::size_t c) const { return shifts_[c]; }
  /// The channel has carried a non-zero count since the stream (re)started. Inactive channels
  /// (e.g. absent from a one-channel recording) run no filter and raise no alarm.
  [[nodiscard]] bool active(std::size_t c) const { return active_[c]; }
  [[nodiscard]] bool alarm() const { return alarm_; }
  [[nodiscard]] bool is_static() const { return static_; }

 private:
  void on_event(const hal::RxEvent& e);
  void on_config(const hal::ConfigRecord& c);
  void on_sample(const hal::SampleRecord& s);
  void on_missing(std::uint32_t n);
  void on_model(const hal::ModelRecord& r);
  void on_model_signals(const hal::ModelSignalsRecord& r);
  [[nodiscard]] bool pushed_params(std::size_t c, ModelParams& p) const;
  void send_models();
  void send_channel_monitors();
  bool build_pushed(std::size_t c, const ModelParams& p);
  void apply_missing();
  void after_sample();
  void restart_estimators();
  void send_adev();
  void send_frames(const hal::EncodedFrames& fr);
  void update_alarm();
  void read_static();
  // The filter of scratch_dm_ for channel c, swapped in only if it configures. Not inlined:
  // its staging filter (1.2 kB on the M4) is then not on the stack during discretisation.
  [[gnu::noinline]] bool install_filter(std::size_t c);
  void accommodate_step(std::size_t c, float innovation_var);

  NodeConfig cfg_node_{};
  hal::FrameSink* tx_ = nullptr;
  hal::DigitalInput* static_in_ = nullptr;
  hal::DigitalOutput* alarm_out_ = nullptr;
  hal::Receiver<8> rx_;
  NodeAdev adev_;
  ScalarBiasKf<float> kf_[kChannels];
  // Pushed models: per channel the record and its filter; pushed_ selects kfn_ over kf_. RAM
  // per channel: sizeof(NodeFilter) (printed by the test) + the record. A new rate
  // rebuilds the filter from the record (model_record_valid gives its parameters again).
  NodeFilter kfn_[kChannels];
  hal::ModelRecord model_rec_[kChannels] = {};
  std::size_t model_states_[kChannels] = {};
  bool pushed_[kChannels] = {};
  bool echo_v2_[kChannels] = {};  // the channel's last push was version 2: echo in version 2
  // Deterministic terms: those the channel runs (with its pushed model), and those pushed and
  // waiting for the channel's next ModelRecord.
  hal::ModelSignalsRecord signals_rec_[kChannels] = {};
  hal::ModelSignalsRecord pending_signals_[kChannels] = {};
  bool has_signals_[kChannels] = {};
  bool pending_[kChannels] = {};
  DiscreteModel<kNodeStates> scratch_dm_{};  // discretisation workspace (not on the stack)
  NodeMonitors mon_[kChannels];
  LevelShifts shifts_[kChannels] = {};
  float known_[kChannels] = {};
  bool active_[kChannels] = {};  // a non-zero count was seen since the stream started
  std::int64_t init_sum_[kChannels] = {};  // counts of the known-signal average
  std::uint32_t init_count_ = 0;
  std::uint64_t pending_missing_ = 0;  // reported missing, not yet applied
  std::uint64_t kernel_drops_ = 0;     // from the host loop (set_link_counters)
  std::uint64_t peer_refused_ = 0;
  // The sink said kLinkDown: further telemetry is counted as failed without being tried (each
  // try may wait send_timeout_ms) until the next received frame shows a peer again.
  bool tx_down_ = false;
  double lsb_[kChannels] = {};
  float lsb_f_[kChannels] = {};  // the same in the filters' precision
  hal::ConfigRecord cfg_{};
  bool have_cfg_ = false;
  bool configured_ = false;
  bool static_ = true;
  bool alarm_ = false;
  bool dirty_ = false;  // samples since the last full set
  std::uint32_t last_seq_ = 0;
  std::uint32_t since_status_ = 0;
  std::uint32_t since_adev_ = 0;
  std::uint8_t transfer_id_ = 0;
  NodeStats stats_{};
};

}  // namespace imu::node

#endif  // IMU_NODE_NODE_HPP

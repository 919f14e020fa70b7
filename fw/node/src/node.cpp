// The firmware node core (see node.hpp). Compiled with fw/src/fw_prelude.hpp force-included.
#include "imu/node/node.hpp"

namespace imu::node {
namespace {

float to_f32(double v) { return static_cast<float>(v); }

std::uint32_t sat_u32(std::uint64_t v) {
  return v > 0xFFFFFFFFULL ? 0xFFFFFFFFU : static_cast<std::uint32_t>(v);
}

bool in_range(double v, double lo, double hi) { return v >= lo && v <= hi; }  // false for NaN

// Exact equality without operator== on doubles (-Wfloat-equal): neither is less nor greater.
// Both records passed config_in_range (no NaN), so this is value equality; any change of the
// rate or an LSB, however small, is a new stream.
bool same_value(double x, double y) { return !(x < y) && !(x > y); }

bool same_values(const hal::ConfigRecord& a, const hal::ConfigRecord& b) {
  bool same = same_value(a.rate_hz, b.rate_hz);
  for (std::size_t c = 0; c < kChannels; ++c) {
    same = same && same_value(a.lsb[c], b.lsb[c]);
  }
  return same;
}

bool finite_f(float v) { return std::isfinite(v); }
// Exactly 0 (finite inputs: neither below nor above).
bool is_zero(float v) { return !(v < 0.0F) && !(v > 0.0F); }
// 0 (term absent) or in [lo, hi].
bool zero_or(float v, float lo, float hi) { return !(v > 0.0F) ? !(v < 0.0F) : (v >= lo && v <= hi); }

}  // namespace

std::size_t pushed_states(const ModelParams& p) {
  std::size_t states = p.n_gm + (p.k > 0.0 ? 1U : 0U) + (p.n_filter_s > 0.0 ? 1U : 0U) +
                       (p.osc_sigma > 0.0 ? 2U : 0U) + (p.r > 0.0 || p.r < 0.0 ? 2U : 0U) +
                       (p.sin_a > 0.0 ? 2U : 0U) + (p.sin2_a > 0.0 ? 2U : 0U);
  if (p.bi > 0.0) {
    GmParam bank[kMaxFlickerGm] = {};
    states += flicker_bank(p.bi, p.bi_tau_lo_s, p.bi_tau_hi_s, bank);
  }
  return states;
}

bool model_record_valid(const hal::ModelRecord& r, ModelParams& out,
                        std::size_t reserved_states) {
  const float vals[] = {r.n,          r.q,         r.gm_sb[0],   r.gm_tb_s[0],    r.gm_sb[1],
                        r.gm_tb_s[1], r.k,         r.bi,         r.bi_tau_lo_s,   r.bi_tau_hi_s,
                        r.n_filter_s, r.osc_sigma, r.osc_f0_hz,  r.osc_beta_per_s};
  for (const float v : vals) {
    if (!finite_f(v)) {
      return false;
    }
  }
  const bool v1 = r.version == hal::kModelVersion1;
  if ((!v1 && r.version != hal::kModelVersion2) || r.channel >= kChannels ||
      !(r.n >= 1e-12F && r.n <= 1e3F) || !zero_or(r.q, 1e-15F, 1e3F) ||
      !zero_or(r.k, 1e-15F, 1e3F) || !zero_or(r.bi, 1e-15F, 1e3F)) {
    return false;
  }
  // Version 2's terms. A version 1 record has no slot for them on the wire (parsed as 0).
  const bool filter = r.n_filter_s > 0.0F;
  const bool osc = r.osc_sigma > 0.0F;
  if (!zero_or(r.n_filter_s, kMinPushedFilterS, kMaxPushedFilterS) ||
      !zero_or(r.osc_sigma, 1e-15F, 1e3F) || (v1 && (filter || osc))) {
    return false;
  }
  if (osc ? !(r.osc_f0_hz >= 0.0F && r.osc_f0_hz <= kMaxPushedOscF0Hz &&
              r.osc_beta_per_s >= kMinPushedOscBetaPerS &&
              r.osc_beta_per_s <= kMaxPushedOscBetaPerS)
          : !(is_zero(r.osc_f0_hz) && is_zero(r.osc_beta_per_s))) {
    return false;  // an absent oscillation has f0 = beta = 0
  }
  ModelParams p{};
  p.n = static_cast<double>(r.n);
  p.q = static_cast<double>(r.q);
  p.k = static_cast<double>(r.k);
  p.n_filter_s = static_cast<double>(r.n_filter_s);
  p.osc_sigma = static_cast<double>(r.osc_sigma);
  p.osc_f0_hz = static_cast<double>(r.osc_f0_hz);
  p.osc_beta_per_s = static_cast<double>(r.osc_beta_per_s);
  for (std::size_t i = 0; i < 2; ++i) {
    if (!zero_or(r.gm_sb[i], 1e-30F, 1e6F)) {
      return false;
    }
    if (r.gm_sb[i] > 0.0F) {
      if (!(r.gm_tb_s[i] >= kMinPushedTbS && r.gm_tb_s[i] <= kMaxPushedTbS)) {
        return false;
      }
      p.gm[p.n_gm].sb = static_cast<double>(r.gm_sb[i]);
      p.gm[p.n_gm].tb_s = static_cast<double>(r.gm_tb_s[i]);
      ++p.n_gm;
    }
  }
  if (r.bi > 0.0F) {
    if (!(r.bi_tau_lo_s >= kMinPushedTbS && r.bi_tau_hi_s <= kMaxPushedTbS &&
          r.bi_tau_lo_s < r.bi_tau_hi_s)) {
      return false;
    }
    p.bi = static_cast<double>(r.bi);
    p.bi_tau_lo_s = static_cast<double>(r.bi_tau_lo_s);
    p.bi_tau_hi_s = static_cast<double>(r.bi_tau_hi_s);
    GmParam bank[kMaxFlickerGm] = {};
    if (flicker_bank(p.bi, p.bi_tau_lo_s, p.bi_tau_hi_s, bank) == 0) {
      return false;
    }
  }
  const std::size_t states = pushed_states(p);
  if (states == 0 || reserved_states > kNodeProcessStates ||
      states > kNodeProcessStates - reserved_states) {
    return false;  // no bias state to estimate, or more than the node's filter holds
  }
  out = p;
  return true;
}

std::size_t signal_states(const hal::ModelSignalsRecord& r) {
  return (r.ramp_r > 0.0F || r.ramp_r < 0.0F ? 2U : 0U) + (r.sin_a[0] > 0.0F ? 2U : 0U) +
         (r.sin_a[1] > 0.0F ? 2U : 0U);
}

bool model_signals_valid(const hal::ModelSignalsRecord& r, ModelParams& p) {
  const float vals[] = {r.ramp_r, r.sin_a[0], r.sin_a[1], r.sin_f0_hz[0], r.sin_f0_hz[1],
                        r.memory_s};
  for (const float v : vals) {
    if (!finite_f(v)) {
      return false;
    }
  }
  if (r.channel >= kChannels || !zero_or(std::fabs(r.ramp_r), 1e-15F, 1e3F) ||
      !zero_or(r.memory_s, kMinSignalMemoryS, kMaxSignalMemoryS)) {
    return false;
  }
  for (std::size_t i = 0; i < 2; ++i) {
    const bool present = r.sin_a[i] > 0.0F;
    const bool ok = present ? r.sin_a[i] <= 1e3F && r.sin_a[i] >= 1e-15F &&
                                  r.sin_f0_hz[i] > 0.0F && r.sin_f0_hz[i] <= kMaxPushedOscF0Hz
                            : is_zero(r.sin_a[i]) && is_zero(r.sin_f0_hz[i]);
    if (!ok) {
      return false;
    }
  }
  if (r.sin_a[1] > 0.0F && !(r.sin_a[0] > 0.0F)) {
    return false;  // the second only beside the first
  }
  ModelParams q = p;
  q.r = static_cast<double>(r.ramp_r);
  q.sin_a = static_cast<double>(r.sin_a[0]);
  q.sin_f0_hz = static_cast<double>(r.sin_f0_hz[0]);
  q.sin2_a = static_cast<double>(r.sin_a[1]);
  q.sin2_f0_hz = static_cast<double>(r.sin_f0_hz[1]);
  q.signal_memory_s = static_cast<double>(r.memory_s);
  if (pushed_states(q) > kNodeProcessStates) {
    return false;
  }
  p = q;
  return true;
}

bool discretize_pushed(const ModelParams& p, double rate_hz, DiscreteModel<kNodeStates>& out,
                       std::size_t& n_states) {
  ContinuousModel<kNodeStates> cm{};
  if (!(rate_hz > 0.0) || build_model(p, cm) != ModelStatus::kOk || cm.n_states == 0 ||
      cm.n_states > kNodeProcessStates ||
      discretize_averaged(cm, 1.0 / rate_hz, out) != ModelStatus::kOk) {
    return false;
  }
  n_states = out.n_states - 1;  // the model's states (the echo's n_states); + the sample mean
  return true;
}

bool model_in_range(const ChannelModel& m) {
  if (!in_range(m.n, kMinModelNoise, kMaxModelNoise) ||
      !in_range(m.b, kMinModelNoise, kMaxModelNoise) || !in_range(m.tp_s, kMinTpS, kMaxTpS)) {
    return false;
  }
  // The filter is built at the rate of each ConfigRecord: it must be valid at both ends of the
  // accepted rates, so that no accepted ConfigRecord leaves a channel without a filter.
  FirstOrderGm gm{};
  ScalarBiasKf<float> kf;
  for (const double rate_hz : {kMinRateHz, kMaxRateHz}) {
    if (first_order_gm_from_asd(m.n, m.b, m.tp_s, rate_hz, gm) != ModelStatus::kOk ||
        kf.configure(gm, 0.0) != KfStatus::kOk) {
      return false;
    }
  }
  return true;
}

bool config_in_range(const hal::ConfigRecord& c) {
  bool valid = in_range(c.rate_hz, kMinRateHz, kMaxRateHz);
  for (const double lsb : c.lsb) {
    valid = valid && in_range(lsb, kMinLsb, kMaxLsb);
  }
  return valid;
}

NodeStatus Node::configure(const NodeConfig& cfg, hal::FrameSink& tx, hal::DigitalInput* static_in,
                           hal::DigitalOutput* alarm_out) {
  configured_ = false;
  if (cfg.status_period_samples == 0 || cfg.init_samples == 0 || cfg.monitor_window < 16) {
    return NodeStatus::kBadConfig;
  }
  for (const ChannelModel& m : cfg.model) {
    if (!model_in_range(m)) {
      return NodeStatus::kBadConfig;
    }
  }
  cfg_node_ = cfg;
  tx_ = &tx;
  static_in_ = static_in;
  alarm_out_ = alarm_out;
  rx_.reset();
  stats_ = NodeStats{};
  have_cfg_ = false;
  cfg_ = hal::ConfigRecord{};
  static_ = true;
  alarm_ = false;
  dirty_ = false;
  since_status_ = 0;
  since_adev_ = 0;
  transfer_id_ = 0;
  kernel_drops_ = 0;
  peer_refused_ = 0;
  tx_down_ = false;
  configured_ = true;
  restart_estimators();
  if (alarm_out_ != nullptr && alarm_out_->write(false) != hal::GpioStatus::kOk) {
    ++stats_.gpio_errors;
  }
  return NodeStatus::kOk;
}

void Node::restart_estimators() {
  adev_.reset();
  for (std::size_t c = 0; c < kChannels; ++c) {
    known_[c] = 0.0F;
    active_[c] = false;
    init_sum_[c] = 0;
    shifts_[c] = LevelShifts{};
    (void)mon_[c].configure(cfg_node_.monitor_window);  // window checked in configure()
  }
  init_count_ = 0;
  pending_missing_ = 0;
}

void Node::on_frame(const hal::CanFrame& f, std::size_t nbytes, std::uint64_t rx_time_ns) {
  if (!configured_) {
    return;
  }
  tx_down_ = false;  // a frame arrived: there is a peer to send telemetry to again
  (void)rx_.push_drain(f, nbytes, rx_time_ns, [this](const hal::RxEvent& e) { on_event(e); });
}

void Node::on_idle() {
  if (!configured_) {
    return;
  }
  (void)rx_.flush_drain([this](const hal::RxEvent& e) { on_event(e); });
  apply_missing();
  if (dirty_) {
    send_full();
  }
}

void Node::on_event(const hal::RxEvent& e) {
  switch (e.type) {
    case hal::RxEvent::Type::kConfig:
      on_config(e.rec.config);
      break;
    case hal::RxEvent::Type::kSample:
      on_sample(e.rec.sample);
      break;
    case hal::RxEvent::Type::kMissing:
      on_missing(e.missing_count);
      break;
    case hal::RxEvent::Type::kModel:
      on_model(e.rec.model);
      break;
    case hal::RxEvent::Type::kModelSignals:
      on_model_signals(e.rec.signals);
      break;
    case hal::RxEvent::Type::kModelEcho:
    case hal::RxEvent::Type::kAdev:
    case hal::RxEvent::Type::kBias:
    case hal::RxEvent::Type::kMonitor:
    case hal::RxEvent::Type::kChannelMonitor:
    case hal::RxEvent::Type::kStats:
    case hal::RxEvent::Type::kRejects:
    case hal::RxEvent::Type::kModelSignalsEcho:
      break;  // another node's telemetry on a shared bus: not ours to process
  }
}

void Node::on_config(const hal::ConfigRecord& c) {
  ++stats_.configs;
  if (have_cfg_ && c.cfg_id == cfg_.cfg_id) {
    return;  // the periodic repeat
  }
  if (!config_in_range(c)) {
    ++stats_.bad_config;
    rx_.use_config(cfg_, have_cfg_);  // samples are still checked against the config in use
    return;
  }
  if (have_cfg_ && same_values(c, cfg_)) {
    // A new cfg_id with the values in use: nothing the estimators depend on changed, so the
    // stream goes on (a sender restart or a forged frame must not wipe hours of ADEV).
    cfg_.cfg_id = c.cfg_id;
    ++stats_.config_same_values;
    return;
  }
  if (have_cfg_) {
    ++stats_.restarts;
    if (dirty_) {
      send_full();  // the old stream's results before they are reset
    }
  }
  cfg_ = c;
  have_cfg_ = true;
  const double ts_s = 1.0 / c.rate_hz;
  for (std::size_t c_i = 0; c_i < kChannels; ++c_i) {
    lsb_[c_i] = c.lsb[c_i];
    lsb_f_[c_i] = to_f32(c.lsb[c_i]);
    adev_.channel(c_i).configure(ts_s, c.lsb[c_i]);
    const ChannelModel& m = cfg_node_.model[c_i];
    FirstOrderGm gm{};
    if (first_order_gm_from_asd(m.n, m.b, m.tp_s, c.rate_hz, gm) != ModelStatus::kOk ||
        kf_[c_i].configure(gm, 0.0) != KfStatus::kOk) {
      ++stats_.model_rejected;  // cannot happen: model_in_range() checked both rate limits
    }
    ModelParams p{};
    if (pushed_[c_i] && !(pushed_params(c_i, p) && build_pushed(c_i, p))) {
      pushed_[c_i] = false;  // valid at the old rate, not at this one: back to the example's
      has_signals_[c_i] = false;
      ++stats_.model_rejected;
    }
  }
  restart_estimators();
}

bool Node::build_pushed(std::size_t c, const ModelParams& p) {
  std::size_t n = 0;
  if (!discretize_pushed(p, cfg_.rate_hz, scratch_dm_, n) || !install_filter(c)) {
    return false;
  }
  model_states_[c] = n;
  return true;
}

bool Node::install_filter(std::size_t c) {
  NodeFilter kf;
  if (kf.configure(scratch_dm_, static_cast<double>(known_[c])) != KfStatus::kOk) {
    return false;
  }
  kf.set_steady_state(true);  // frozen gain once converged, back to time-varying after a gap
  kfn_[c] = kf;  // only now: a refused model leaves the running filter untouched
  return true;
}

bool Node::pushed_params(std::size_t c, ModelParams& p) const {
  return model_record_valid(model_rec_[c], p, has_signals_[c] ? signal_states(signals_rec_[c]) : 0U) &&
         (!has_signals_[c] || model_signals_valid(signals_rec_[c], p));
}

void Node::on_model_signals(const hal::ModelSignalsRecord& r) {
  ModelParams p{};  // the terms alone: their ranges (the state count is checked with the model)
  if (r.channel >= kChannels || !model_signals_valid(r, p)) {
    ++stats_.model_rejected;
    send_models();
    return;
  }
  pending_signals_[r.channel] = r;  // applied with the channel's next ModelRecord
  pending_[r.channel] = true;
}

void Node::on_model(const hal::ModelRecord& r) {
  if (r.channel < kChannels) {  // the receiver refused any other
    echo_v2_[r.channel] = r.version == hal::kModelVersion2;  // answer in the version pushed
  }
  // The deterministic terms pushed for this channel go with this record, whatever its fate.
  const bool with_signals = r.channel < kChannels && pending_[r.channel];
  const hal::ModelSignalsRecord signals = with_signals ? pending_signals_[r.channel]
                                                       : hal::ModelSignalsRecord{};
  if (r.channel < kChannels) {
    pending_[r.channel] = false;
  }
  ModelParams p{};
  if (!model_record_valid(r, p, with_signals ? signal_states(signals) : 0U) ||
      (with_signals && !model_signals_valid(signals, p))) {
    ++stats_.model_rejected;
    send_models();
    return;
  }
  const std::size_t c = r.channel;
  // Validate the discretisation at the rate in use, or at both rate limits before a config.
  std::size_t n = 0;
  bool ok = true;
  if (have_cfg_) {
    ok = discretize_pushed(p, cfg_.rate_hz, scratch_dm_, n);
  } else {
    for (const double rate_hz : {kMinRateHz, kMaxRateHz}) {
      ok = ok && discretize_pushed(p, rate_hz, scratch_dm_, n);
    }
  }
  if (!ok || (have_cfg_ && !build_pushed(c, p))) {
    ++stats_.model_rejected;
    send_models();
    return;
  }
  model_rec_[c] = r;
  model_states_[c] = n;
  signals_rec_[c] = signals;
  has_signals_[c] = with_signals;
  pushed_[c] = true;
  ++stats_.models_accepted;
  (void)mon_[c].configure(cfg_node_.monitor_window);  // innovations of a new filter
  send_models();
}

hal::ModelRecord Node::model_echo(std::size_t c) const {
  hal::ModelRecord e{};
  if (pushed_[c]) {
    e = model_rec_[c];
    e.n_states = static_cast<std::uint8_t>(model_states_[c]);
    e.flags = hal::kModelPushed;
  } else {
    const ChannelModel& m = cfg_node_.model[c];
    FirstOrderGm gm{};
    (void)first_order_gm_from_asd(m.n, m.b, m.tp_s, have_cfg_ ? cfg_.rate_hz : 100.0, gm);
    e.n = to_f32(m.n);
    e.gm_sb[0] = to_f32(gm.sb);
    e.gm_tb_s[0] = to_f32(gm.tb_s);
    e.n_states = 1;
  }
  // The version of the channel's last push (the host that sent it reads it), and version 2
  // whenever the model it runs came in version 2 (version 1 may not hold it).
  const bool v2 = echo_v2_[c] || (pushed_[c] && model_rec_[c].version == hal::kModelVersion2);
  e.version = v2 ? hal::kModelVersion2 : hal::kModelVersion1;
  e.channel = static_cast<std::uint8_t>(c);
  return e;
}

hal::ModelSignalsRecord Node::signals_echo(std::size_t c) const {
  hal::ModelSignalsRecord e{};
  if (pushed_[c] && has_signals_[c]) {
    e = signals_rec_[c];
    e.flags = hal::kModelPushed;
  }
  e.channel = static_cast<std::uint8_t>(c);
  return e;
}

void Node::send_models() {
  if (!cfg_node_.telemetry) {
    return;
  }
  hal::EncodedFrames fr{};
  for (std::size_t c = 0; c < kChannels; ++c) {
    hal::encode(model_echo(c), true, cfg_node_.layout, transfer_id_++, fr);
    send_frames(fr);
    if (pushed_[c] && has_signals_[c]) {  // only channels that run deterministic terms
      hal::encode(signals_echo(c), true, cfg_node_.layout, transfer_id_++, fr);
      send_frames(fr);
    }
  }
}

void Node::on_sample(const hal::SampleRecord& s) {
  if (!have_cfg_) {
    ++stats_.samples_before_config;
    return;
  }
  apply_missing();
  if (s.sat_mask != 0) {
    ++stats_.saturated;
  }
  last_seq_ = s.seq;
  adev_.push_frame(s.counts);  // buffered, bit-identical to push(); flushed by every read
  for (std::size_t c = 0; c < kChannels; ++c) {
    active_[c] = active_[c] || s.counts[c] != 0;
  }
  if (init_count_ < cfg_node_.init_samples) {
    for (std::size_t c = 0; c < kChannels; ++c) {
      init_sum_[c] += s.counts[c];  // exact: counts, not their values
    }
    ++init_count_;
    if (init_count_ == cfg_node_.init_samples) {
      for (std::size_t c = 0; c < kChannels; ++c) {
        known_[c] = to_f32(static_cast<double>(init_sum_[c]) / static_cast<double>(init_count_) *
                           lsb_[c]);
        kf_[c].set_known_signal(known_[c]);
        kfn_[c].set_known_signal(known_[c]);
      }
    }
  } else {
    for (std::size_t c = 0; c < kChannels; ++c) {
      if (!active_[c]) {
        continue;  // never carried data (e.g. a one-channel recording): no filter, no alarm
      }
      // In float, like the filter (no software double per sample on an FPU of single
      // precision): two roundings, a relative error of at most 1.2e-7 (1.2e-6 m/s^2 on
      // gravity), orders below any IMU's noise per sample.
      const float z = static_cast<float>(s.counts[c]) * lsb_f_[c];
      const KfStep<float> st = pushed_[c] ? kfn_[c].step(z, static_) : kf_[c].step(z, static_);
      if (st.updated) {
        mon_[c].push(st.innovation, st.innovation_var);
        if (mon_[c].cusum.alarm()) {
          accommodate_step(c, st.innovation_var);
        }
      }
    }
    update_alarm();
  }
  ++stats_.samples;
  after_sample();
}

// A CUSUM alarm is a level shift: count it, move the known signal to the new level
// (LevelShifts) and re-arm the CUSUM.
void Node::accommodate_step(std::size_t c, float innovation_var) {
  const StepLocator<>::Estimate est = mon_[c].take_step();
  const float size = est.mean * std::sqrt(innovation_var);
  LevelShifts& ls = shifts_[c];
  ls.last_size = 0.0F;
  if (est.updates > 0 && std::isfinite(size)) {
    ls.last_size = size;
    known_[c] += size;
    kf_[c].set_known_signal(known_[c]);
    kfn_[c].set_known_signal(known_[c]);
  }
  ls.count = ls.count < UINT32_MAX ? ls.count + 1U : ls.count;
  ls.last_update = mon_[c].cusum.updates() - est.updates;
}

void Node::on_missing(std::uint32_t n) {
  if (!have_cfg_) {
    return;
  }
  // The receiver may report one run of lost samples as several consecutive events: collect
  // them and apply the run once, before the next sample (one gap for the estimators).
  pending_missing_ += n;
  dirty_ = true;
}

void Node::apply_missing() {
  const std::uint64_t n = pending_missing_;
  if (n == 0) {
    return;
  }
  pending_missing_ = 0;
  stats_.missing += n;
  adev_.mark_missing(n);  // O(levels), any n
  if (init_count_ >= cfg_node_.init_samples) {
    for (auto& kf : kf_) {
      kf.predict(n);  // n predictions without a measurement, constant time for any n
    }
    const std::uint64_t steps = n < kMaxGapSteps ? n : kMaxGapSteps;
    for (std::size_t c = 0; c < kChannels; ++c) {
      for (std::uint64_t i = 0; pushed_[c] && i < steps; ++i) {
        (void)kfn_[c].step(0.0F, false);
      }
    }
  }
}

void Node::after_sample() {
  dirty_ = true;
  ++since_status_;
  ++since_adev_;
  const bool adev_due =
      cfg_node_.adev_period_samples != 0 && since_adev_ >= cfg_node_.adev_period_samples;
  if (adev_due) {
    send_full();
  } else if (since_status_ >= cfg_node_.status_period_samples) {
    send_status();
  }
}

void Node::read_static() {
  if (static_in_ == nullptr) {
    static_ = true;
    return;
  }
  bool active = static_;
  if (static_in_->read(active) == hal::GpioStatus::kOk) {
    static_ = active;
  } else {
    ++stats_.gpio_errors;  // keep the last known level
  }
}

void Node::update_alarm() {
  bool any = false;
  for (std::size_t c = 0; c < kChannels; ++c) {
    any = any || (active_[c] && (mon_[c].any_alarm() || shifts_[c].count > 0));
  }
  if (any == alarm_) {
    return;
  }
  alarm_ = any;
  ++stats_.alarm_changes;
  if (alarm_out_ != nullptr && alarm_out_->write(any) != hal::GpioStatus::kOk) {
    ++stats_.gpio_errors;
  }
}

void Node::send_frames(const hal::EncodedFrames& fr) {
  bool stalled = false;  // a frame of this record waited send_timeout_ms in vain
  for (std::size_t i = 0; i < fr.count; ++i) {
    if (tx_down_ || stalled) {
      // Not tried: the link was down at the last try, or the peer took no frame of this record
      // (each try would wait send_timeout_ms again).
      ++stats_.telemetry_failures;
      continue;
    }
    const hal::IoStatus st = tx_->send(fr.frame[i], cfg_node_.send_timeout_ms);
    stats_.last_send_status = st;
    if (st == hal::IoStatus::kOk) {
      ++stats_.telemetry_frames;
    } else {
      ++stats_.telemetry_failures;
      tx_down_ = st == hal::IoStatus::kLinkDown;
      stalled = st == hal::IoStatus::kWouldBlock;
    }
  }
}

void Node::send_status() {
  since_status_ = 0;
  read_static();
  if (!cfg_node_.telemetry) {
    return;
  }
  const hal::RxStats& rs = rx_.stats();
  hal::StatsRecord st{};
  st.frames = sat_u32(rs.frames);
  st.samples = sat_u32(stats_.samples);
  st.missing = sat_u32(stats_.missing);
  st.crc_errors = sat_u32(rs.crc_errors);
  st.bad_mtu_or_dlc = sat_u32(rs.bad_mtu + rs.bad_dlc);
  st.unknown_id = sat_u32(rs.unknown_id);
  st.duplicates = sat_u32(rs.duplicates);
  st.truncated = sat_u32(rs.truncated);
  st.error_frames = sat_u32(rs.error_frames);
  st.kernel_drops = sat_u32(kernel_drops_);
  hal::EncodedFrames fr{};
  hal::encode(st, cfg_node_.layout, transfer_id_++, fr);
  send_frames(fr);

  hal::BiasRecord b{};
  b.seq = last_seq_;
  for (std::size_t c = 0; c < kChannels; ++c) {
    b.bias[c] = bias(c);
    b.var[c] = bias_var(c);
  }
  b.flags = static_ ? hal::kBiasStatic : std::uint8_t{0};
  hal::encode(b, cfg_node_.layout, transfer_id_++, fr);
  send_frames(fr);

  hal::MonitorRecord m{};
  m.seq = last_seq_;
  float nis_max_dev = -1.0F;
  float white_ratio = 0.0F;
  bool cusum_any = false;
  bool white_any = false;
  for (std::size_t c = 0; c < kChannels; ++c) {
    if (!active_[c]) {
      continue;
    }
    const NodeMonitors& mc = mon_[c];
    const float mean = mc.nis.blocks() > 0 ? mc.nis.last_block_mean() : mc.nis.running_mean();
    const float dev = std::fabs(mean - 1.0F);
    if (dev > nis_max_dev) {
      nis_max_dev = dev;
      m.nis_mean = mean;  // the channel whose NIS mean is furthest from 1
    }
    const float ratio = mc.whiteness.box_pierce_ratio();
    white_ratio = ratio > white_ratio ? ratio : white_ratio;
    white_any = white_any || mc.whiteness.flag();
    if (shifts_[c].count > 0) {
      cusum_any = true;
      m.cusum_mask = static_cast<std::uint8_t>(m.cusum_mask | (1U << c));
    }
  }
  m.whiteness = white_ratio;
  m.flags = static_cast<std::uint16_t>((cusum_any ? hal::kMonitorCusum : 0U) |
                                       (white_any ? hal::kMonitorWhiteness : 0U) |
                                       (alarm_ ? hal::kMonitorAlarmLine : 0U));
  hal::encode(m, cfg_node_.layout, transfer_id_++, fr);
  send_frames(fr);
  send_channel_monitors();

  hal::RejectsRecord rj{};
  rj.bad_config = sat_u32(stats_.bad_config);
  rj.config_same_values = sat_u32(stats_.config_same_values);
  rj.model_rejected = sat_u32(stats_.model_rejected);
  rj.samples_before_config = sat_u32(stats_.samples_before_config);
  rj.cfg_mismatch = sat_u32(rs.cfg_mismatch);
  rj.late = sat_u32(rs.late);
  rj.resyncs = sat_u32(rs.resyncs);
  rj.remote_frames = sat_u32(rs.remote_frames);
  rj.bad_fragment = sat_u32(rs.bad_fragment);
  rj.orphan_fragments = sat_u32(rs.orphan_fragments);
  rj.busy = sat_u32(rs.busy);
  rj.telemetry_failures = sat_u32(stats_.telemetry_failures);
  rj.gpio_errors = sat_u32(stats_.gpio_errors);
  rj.peer_refused = sat_u32(peer_refused_);
  rj.bad_record = sat_u32(rs.bad_record);
  hal::encode(rj, cfg_node_.layout, transfer_id_++, fr);
  send_frames(fr);
  ++stats_.status_sets;
}

void Node::send_channel_monitors() {
  hal::EncodedFrames fr{};
  for (std::size_t c = 0; c < kChannels; ++c) {
    if (!active_[c]) {
      continue;
    }
    const NodeMonitors& mc = mon_[c];
    hal::ChannelMonitorRecord r{};
    r.channel = static_cast<std::uint8_t>(c);
    r.n_states = static_cast<std::uint8_t>(pushed_[c] ? model_states_[c] : 1U);
    const LevelShifts& ls = shifts_[c];
    const bool down = ls.count > 0 && ls.last_size < 0.0F;
    r.flags = static_cast<std::uint8_t>((ls.count > 0 ? hal::kChanMonCusum : 0U) |
                                        (down ? hal::kChanMonCusumDown : 0U) |
                                        (mc.whiteness.flag() ? hal::kChanMonWhiteness : 0U) |
                                        (pushed_[c] ? hal::kChanMonPushed : 0U));
    r.seq = last_seq_;
    r.updates = sat_u32(mc.cusum.updates());
    r.nis_mean = mc.nis.overall_mean();
    r.nis_last_block = mc.nis.last_block_mean();
    r.whiteness = mc.whiteness.box_pierce_ratio();
    r.blocks = mc.nis.blocks();
    r.nis_flagged = mc.nis.flagged_blocks();
    r.white_flagged = mc.whiteness.flagged_blocks();
    r.cusum_detections = static_cast<std::uint8_t>(ls.count < 255U ? ls.count : 255U);
    r.cusum_step_update = ls.count > 0 ? sat_u32(ls.last_update) : 0U;
    hal::encode(r, cfg_node_.layout, transfer_id_++, fr);
    send_frames(fr);
  }
}

void Node::send_adev() {
  since_adev_ = 0;
  dirty_ = false;
  if (!cfg_node_.telemetry) {
    return;
  }
  hal::EncodedFrames fr{};
  for (std::size_t c = 0; c < kChannels; ++c) {
    // One point at a time (no buffer of kMaxAdevPoints points in RAM).
    const std::size_t n = adev_.channel(c).point_count();
    std::size_t i = 0;
    adev_.channel(c).for_each_point([&](const AdevPoint& p) {
      hal::AdevRecord r{};
      r.channel = static_cast<std::uint8_t>(c);
      r.index = static_cast<std::uint8_t>(i++);
      r.n_points = static_cast<std::uint8_t>(n);
      r.tau_s = to_f32(p.tau_s);
      r.adev = to_f32(p.adev);
      r.ci_lo = to_f32(p.ci_lo);
      r.ci_hi = to_f32(p.ci_hi);
      r.n_terms = sat_u32(p.n_terms);
      hal::encode(r, cfg_node_.layout, transfer_id_++, fr);
      send_frames(fr);
      return i < n;
    });
  }
  ++stats_.adev_sets;
}

void Node::send_full() {
  send_status();
  send_models();
  send_adev();
}

}  // namespace imu::node

// The firmware node core (see node.hpp). Compiled with fw/src/fw_prelude.hpp force-included.
#include "imu/node/node.hpp"

namespace imu::node {
namespace {

float to_f32(double v) { return static_cast<float>(v); }

std::uint32_t sat_u32(std::uint64_t v) {
  return v > 0xFFFFFFFFULL ? 0xFFFFFFFFU : static_cast<std::uint32_t>(v);
}

}  // namespace

NodeStatus Node::configure(const NodeConfig& cfg, hal::FrameSink& tx, hal::DigitalInput* static_in,
                           hal::DigitalOutput* alarm_out) {
  configured_ = false;
  if (cfg.status_period_samples == 0 || cfg.init_samples == 0 || cfg.monitor_window < 16) {
    return NodeStatus::kBadConfig;
  }
  for (const ChannelModel& m : cfg.model) {
    FirstOrderGm gm{};
    // The rate is not known yet; 100 Hz only checks that the parameters are valid.
    if (first_order_gm_from_asd(m.n, m.b, m.tp_s, 100.0, gm) != ModelStatus::kOk) {
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
    init_sum_[c] = 0.0;
    (void)mon_[c].configure(cfg_node_.monitor_window);  // window checked in configure()
  }
  init_count_ = 0;
  pending_missing_ = 0;
}

void Node::on_frame(const hal::CanFrame& f, std::size_t nbytes, std::uint64_t rx_time_ns) {
  if (!configured_) {
    return;
  }
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
    case hal::RxEvent::Type::kAdev:
    case hal::RxEvent::Type::kBias:
    case hal::RxEvent::Type::kMonitor:
    case hal::RxEvent::Type::kStats:
      break;  // another node's telemetry on a shared bus: not ours to process
  }
}

void Node::on_config(const hal::ConfigRecord& c) {
  ++stats_.configs;
  if (have_cfg_ && c.cfg_id == cfg_.cfg_id) {
    return;  // the periodic repeat
  }
  bool valid = c.rate_hz > 0.0 && c.rate_hz < 1e6;
  for (double lsb : c.lsb) {
    valid = valid && lsb > 0.0 && lsb < 1e6;
  }
  if (!valid) {
    ++stats_.bad_config;
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
    adev_.channel(c_i).configure(ts_s, c.lsb[c_i]);
    const ChannelModel& m = cfg_node_.model[c_i];
    FirstOrderGm gm{};
    if (first_order_gm_from_asd(m.n, m.b, m.tp_s, c.rate_hz, gm) != ModelStatus::kOk ||
        kf_[c_i].configure(gm, 0.0) != KfStatus::kOk) {
      ++stats_.bad_config;  // cannot happen for parameters checked in configure()
    }
  }
  restart_estimators();
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
      init_sum_[c] += static_cast<double>(s.counts[c]) * lsb_[c];
    }
    ++init_count_;
    if (init_count_ == cfg_node_.init_samples) {
      for (std::size_t c = 0; c < kChannels; ++c) {
        known_[c] = to_f32(init_sum_[c] / static_cast<double>(init_count_));
        kf_[c].set_known_signal(known_[c]);
      }
    }
  } else {
    for (std::size_t c = 0; c < kChannels; ++c) {
      if (!active_[c]) {
        continue;  // never carried data (e.g. a one-channel recording): no filter, no alarm
      }
      const auto z = to_f32(static_cast<double>(s.counts[c]) * lsb_[c]);
      const KfStep<float> st = kf_[c].step(z, static_);
      if (st.updated) {
        mon_[c].push(st.innovation, st.innovation_var);
      }
    }
    update_alarm();
  }
  ++stats_.samples;
  after_sample();
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
  adev_.mark_missing(n);
  if (init_count_ >= cfg_node_.init_samples) {
    for (std::uint64_t i = 0; i < n; ++i) {
      for (auto& kf : kf_) {
        (void)kf.step(0.0F, false);  // prediction only: no measurement
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
    any = any || (active_[c] && mon_[c].any_alarm());
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
  for (std::size_t i = 0; i < fr.count; ++i) {
    const hal::IoStatus st = tx_->send(fr.frame[i], cfg_node_.send_timeout_ms);
    stats_.last_send_status = st;
    if (st == hal::IoStatus::kOk) {
      ++stats_.telemetry_frames;
    } else {
      ++stats_.telemetry_failures;
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
  st.kernel_drops = 0;  // the transport's counter; the host loop reports it separately
  hal::EncodedFrames fr{};
  hal::encode(st, cfg_node_.layout, transfer_id_++, fr);
  send_frames(fr);

  hal::BiasRecord b{};
  b.seq = last_seq_;
  for (std::size_t c = 0; c < kChannels; ++c) {
    b.bias[c] = kf_[c].bias();
    b.var[c] = kf_[c].variance();
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
    const ResidualMonitors<4>& mc = mon_[c];
    const float mean = mc.nis.blocks() > 0 ? mc.nis.last_block_mean() : mc.nis.running_mean();
    const float dev = std::fabs(mean - 1.0F);
    if (dev > nis_max_dev) {
      nis_max_dev = dev;
      m.nis_mean = mean;  // the channel whose NIS mean is furthest from 1
    }
    const float ratio = mc.whiteness.box_pierce() / mc.whiteness.box_pierce_bound();
    white_ratio = ratio > white_ratio ? ratio : white_ratio;
    white_any = white_any || mc.whiteness.flag();
    if (mc.cusum.alarm()) {
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
  ++stats_.status_sets;
}

void Node::send_adev() {
  since_adev_ = 0;
  dirty_ = false;
  if (!cfg_node_.telemetry) {
    return;
  }
  hal::EncodedFrames fr{};
  for (std::size_t c = 0; c < kChannels; ++c) {
    const std::size_t n = adev_.channel(c).snapshot(points_, kMaxAdevPoints);
    for (std::size_t i = 0; i < n; ++i) {
      hal::AdevRecord r{};
      r.channel = static_cast<std::uint8_t>(c);
      r.index = static_cast<std::uint8_t>(i);
      r.n_points = static_cast<std::uint8_t>(n);
      r.tau_s = to_f32(points_[i].tau_s);
      r.adev = to_f32(points_[i].adev);
      r.ci_lo = to_f32(points_[i].ci_lo);
      r.ci_hi = to_f32(points_[i].ci_hi);
      r.n_terms = sat_u32(points_[i].n_terms);
      hal::encode(r, cfg_node_.layout, transfer_id_++, fr);
      send_frames(fr);
    }
  }
  ++stats_.adev_sets;
}

void Node::send_full() {
  send_status();
  send_adev();
}

}  // namespace imu::node

// Implementation of imu/hal/codec.hpp. Compiled with fw/src/fw_prelude.hpp force-included and
// -fno-exceptions -fno-rtti, like fw/: no heap, no stdio, no OS.
#include "imu/hal/codec.hpp"

namespace imu::hal {
namespace {

// CRC-32C table, reflected polynomial 0x82F63B78, built at compile time.
struct CrcTable {
  std::uint32_t v[256];
};
constexpr CrcTable make_crc_table() {
  CrcTable t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) {
      c = (c & 1U) != 0 ? (c >> 1) ^ 0x82F63B78U : c >> 1;
    }
    t.v[i] = c;
  }
  return t;
}
constexpr CrcTable kCrcTable = make_crc_table();

// Little-endian writers/readers, byte by byte (host independent, no alignment needed).
class Writer {
 public:
  explicit Writer(std::uint8_t* buf) : p_(buf) {}
  void u8(std::uint8_t v) { p_[n_++] = v; }
  void u16(std::uint16_t v) {
    u8(static_cast<std::uint8_t>(v));
    u8(static_cast<std::uint8_t>(v >> 8));
  }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
      u8(static_cast<std::uint8_t>(v >> (8 * i)));
    }
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) {
      u8(static_cast<std::uint8_t>(v >> (8 * i)));
    }
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(float v) {
    std::uint32_t b = 0;
    __builtin_memcpy(&b, &v, sizeof b);  // IEEE 754 binary32 bit pattern
    u32(b);
  }
  void f64(double v) {
    std::uint64_t b = 0;
    __builtin_memcpy(&b, &v, sizeof b);  // IEEE 754 binary64 bit pattern
    u64(b);
  }
  void zeros(std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      u8(0);
    }
  }
  /// Append the CRC-32C of everything written so far.
  void crc() { u32(crc32c(p_, n_)); }
  [[nodiscard]] std::size_t size() const { return n_; }

 private:
  std::uint8_t* p_;
  std::size_t n_ = 0;
};

class Reader {
 public:
  explicit Reader(const std::uint8_t* buf) : p_(buf) {}
  std::uint8_t u8() { return p_[n_++]; }
  std::uint16_t u16() {
    const auto lo = static_cast<std::uint16_t>(u8());
    const auto hi = static_cast<std::uint16_t>(u8());
    return static_cast<std::uint16_t>(lo | static_cast<std::uint16_t>(hi << 8));
  }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) {
      v |= static_cast<std::uint32_t>(u8()) << (8 * i);
    }
    return v;
  }
  std::uint64_t u64() {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) {
      v |= static_cast<std::uint64_t>(u8()) << (8 * i);
    }
    return v;
  }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  float f32() {
    const std::uint32_t b = u32();
    float v = 0.0F;
    __builtin_memcpy(&v, &b, sizeof v);
    return v;
  }
  double f64() {
    const std::uint64_t b = u64();
    double v = 0.0;
    __builtin_memcpy(&v, &b, sizeof v);
    return v;
  }
  void skip(std::size_t n) { n_ += n; }

 private:
  const std::uint8_t* p_;
  std::size_t n_ = 0;
};

void clear_frame(CanFrame& f) {
  f.can_id = 0;
  f.len = 0;
  f.flags = 0;
  f.res0 = 0;
  f.res1 = 0;
  for (auto& b : f.data) {
    b = 0;
  }
}

void frame_record(const std::uint8_t* rec, std::size_t len, RecordKind kind, Layout layout,
                  std::uint8_t transfer_id, EncodedFrames& out) {
  const std::uint32_t id = fd_id(kind);
  if (layout == Layout::kFd) {
    CanFrame& f = out.frame[0];
    clear_frame(f);
    f.can_id = id;
    f.len = fd_len_for(len);
    f.flags = kCanFdFdf | kCanFdBrs;
    for (std::size_t i = 0; i < len; ++i) {
      f.data[i] = rec[i];
    }
    out.count = 1;
    return;
  }
  const std::size_t n = (len + kClassicPayload - 1) / kClassicPayload;
  for (std::size_t k = 0; k < n; ++k) {
    CanFrame& f = out.frame[k];
    clear_frame(f);
    f.can_id = id + 1;
    f.len = 8;
    f.data[0] = static_cast<std::uint8_t>(((transfer_id & 0x0FU) << 4) | (k & 0x0FU));
    for (std::size_t i = 0; i < kClassicPayload; ++i) {
      const std::size_t src = k * kClassicPayload + i;
      f.data[1 + i] = src < len ? rec[src] : 0;  // last fragment padded with zeros
    }
  }
  out.count = n;
}

}  // namespace

std::uint8_t fd_len_for(std::size_t n) {
  constexpr std::uint8_t kLens[] = {12, 16, 20, 24, 32, 48, 64};
  if (n <= 8) {
    return static_cast<std::uint8_t>(n);
  }
  for (const std::uint8_t l : kLens) {
    if (n <= l) {
      return l;
    }
  }
  return 64;
}

std::uint32_t crc32c(const std::uint8_t* data, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFU;
  for (std::size_t i = 0; i < n; ++i) {
    c = kCrcTable.v[(c ^ data[i]) & 0xFFU] ^ (c >> 8);
  }
  return c ^ 0xFFFFFFFFU;
}

bool crc_ok(const std::uint8_t* buf, std::size_t len) {
  if (len < 4) {
    return false;
  }
  Reader r(buf + len - 4);
  return r.u32() == crc32c(buf, len - 4);
}

std::size_t record_len(RecordKind k) {
  switch (k) {
    case RecordKind::kConfig: return kConfigLen;
    case RecordKind::kSample: return kSampleLen;
    case RecordKind::kAdev: return kAdevLen;
    case RecordKind::kBias: return kBiasLen;
    case RecordKind::kMonitor: return kMonitorLen;
    case RecordKind::kStats: return kStatsLen;
    case RecordKind::kRejects: return kRejectsLen;
    case RecordKind::kModel:
    case RecordKind::kModelEcho: return kModelLen;
    case RecordKind::kChannelMonitor: return kChannelMonitorLen;
    case RecordKind::kModel2:
    case RecordKind::kModelEcho2: return kModel2Len;
    case RecordKind::kModelSignals:
    case RecordKind::kModelSignalsEcho: return kModelSignalsLen;
  }
  return 0;
}

std::uint32_t fd_id(RecordKind k) {
  switch (k) {
    case RecordKind::kConfig: return kIdConfigFd;
    case RecordKind::kSample: return kIdSampleFd;
    case RecordKind::kAdev: return kIdAdevFd;
    case RecordKind::kBias: return kIdBiasFd;
    case RecordKind::kMonitor: return kIdMonitorFd;
    case RecordKind::kStats: return kIdStatsFd;
    case RecordKind::kRejects: return kIdRejectsFd;
    case RecordKind::kModel: return kIdModelFd;
    case RecordKind::kModelEcho: return kIdModelEchoFd;
    case RecordKind::kChannelMonitor: return kIdChannelMonitorFd;
    case RecordKind::kModel2: return kIdModel2Fd;
    case RecordKind::kModelEcho2: return kIdModelEcho2Fd;
    case RecordKind::kModelSignals: return kIdModelSignalsFd;
    case RecordKind::kModelSignalsEcho: return kIdModelSignalsEchoFd;
  }
  return 0;
}

std::uint8_t model_version(RecordKind k) {
  switch (k) {
    case RecordKind::kModel:
    case RecordKind::kModelEcho: return kModelVersion1;
    case RecordKind::kModel2:
    case RecordKind::kModelEcho2: return kModelVersion2;
    case RecordKind::kConfig:
    case RecordKind::kSample:
    case RecordKind::kAdev:
    case RecordKind::kBias:
    case RecordKind::kMonitor:
    case RecordKind::kStats:
    case RecordKind::kRejects:
    case RecordKind::kChannelMonitor:
    case RecordKind::kModelSignals:
    case RecordKind::kModelSignalsEcho: return 0;
  }
  return 0;
}

bool kind_of_id(std::uint32_t can_id, RecordKind& kind, Layout& layout) {
  if ((can_id & (kCanEffFlag | kCanRtrFlag | kCanErrFlag)) != 0 || can_id > kCanSffMask) {
    return false;
  }
  constexpr RecordKind kAll[] = {RecordKind::kConfig, RecordKind::kSample, RecordKind::kAdev,
                                 RecordKind::kBias,   RecordKind::kMonitor, RecordKind::kStats,
                                 RecordKind::kRejects, RecordKind::kModel,
                                 RecordKind::kModelEcho, RecordKind::kChannelMonitor,
                                 RecordKind::kModel2,  RecordKind::kModelEcho2,
                                 RecordKind::kModelSignals, RecordKind::kModelSignalsEcho};
  for (const RecordKind k : kAll) {
    const std::uint32_t id = fd_id(k);
    if (can_id == id || can_id == id + 1) {
      kind = k;
      layout = can_id == id ? Layout::kFd : Layout::kClassic;
      return true;
    }
  }
  return false;
}

// ---- serialise -------------------------------------------------------------------------------

void serialize(const ConfigRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u8(r.cfg_id);
  w.u8(static_cast<std::uint8_t>(kChannels));
  w.u16(0);
  w.f64(r.rate_hz);
  for (const double l : r.lsb) {
    w.f64(l);
  }
  w.crc();
}

void serialize(const SampleRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u32(r.seq);
  w.u64(r.t_sensor_ns);
  for (const std::int32_t c : r.counts) {
    w.i32(c);
  }
  w.u8(r.cfg_id);
  w.u8(r.sat_mask);
  w.crc();
}

void serialize(const AdevRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u8(r.channel);
  w.u8(r.index);
  w.u8(r.n_points);
  w.u8(0);
  w.f32(r.tau_s);
  w.f32(r.adev);
  w.f32(r.ci_lo);
  w.f32(r.ci_hi);
  w.u32(r.n_terms);
  w.crc();
}

void serialize(const BiasRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u32(r.seq);
  for (const float b : r.bias) {
    w.f32(b);
  }
  for (const float v : r.var) {
    w.f32(v);
  }
  w.u8(r.flags);
  w.zeros(3);
  w.crc();
}

void serialize(const MonitorRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u32(r.seq);
  w.f32(r.nis_mean);
  w.f32(r.whiteness);
  w.u16(r.flags);
  w.u8(r.cusum_mask);
  w.u8(0);
  w.crc();
}

void serialize(const StatsRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u32(r.frames);
  w.u32(r.samples);
  w.u32(r.missing);
  w.u32(r.crc_errors);
  w.u32(r.bad_mtu_or_dlc);
  w.u32(r.unknown_id);
  w.u32(r.duplicates);
  w.u32(r.truncated);
  w.u32(r.error_frames);
  w.u32(r.kernel_drops);
  w.crc();
}

void serialize(const RejectsRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u32(r.bad_config);
  w.u32(r.config_same_values);
  w.u32(r.model_rejected);
  w.u32(r.samples_before_config);
  w.u32(r.cfg_mismatch);
  w.u32(r.late);
  w.u32(r.resyncs);
  w.u32(r.remote_frames);
  w.u32(r.bad_fragment);
  w.u32(r.orphan_fragments);
  w.u32(r.busy);
  w.u32(r.telemetry_failures);
  w.u32(r.gpio_errors);
  w.u32(r.peer_refused);
  w.u32(r.bad_record);
  w.crc();
}

void serialize(const ModelRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u8(r.version);
  w.u8(r.channel);
  w.u8(r.n_states);
  w.u8(r.flags);
  w.f32(r.n);
  w.f32(r.q);
  w.f32(r.gm_sb[0]);
  w.f32(r.gm_tb_s[0]);
  w.f32(r.gm_sb[1]);
  w.f32(r.gm_tb_s[1]);
  w.f32(r.k);
  w.f32(r.bi);
  w.f32(r.bi_tau_lo_s);
  w.f32(r.bi_tau_hi_s);
  if (r.version == kModelVersion2) {
    w.f32(r.n_filter_s);
    w.f32(r.osc_sigma);
    w.f32(r.osc_f0_hz);
    w.f32(r.osc_beta_per_s);
  }
  w.crc();
}

void serialize(const ChannelMonitorRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u8(r.channel);
  w.u8(r.n_states);
  w.u8(r.flags);
  w.u8(r.cusum_detections);
  w.u32(r.seq);
  w.u32(r.updates);
  w.f32(r.nis_mean);
  w.f32(r.nis_last_block);
  w.f32(r.whiteness);
  w.u32(r.blocks);
  w.u32(r.nis_flagged);
  w.u32(r.white_flagged);
  w.u32(r.cusum_step_update);
  w.crc();
}

void serialize(const ModelSignalsRecord& r, std::uint8_t* buf) {
  Writer w(buf);
  w.u8(r.channel);
  w.u8(r.flags);
  w.u16(0);
  w.f32(r.ramp_r);
  w.f32(r.sin_a[0]);
  w.f32(r.sin_a[1]);
  w.f32(r.sin_f0_hz[0]);
  w.f32(r.sin_f0_hz[1]);
  w.f32(r.memory_s);
  w.crc();
}

// ---- parse -----------------------------------------------------------------------------------

void parse(const std::uint8_t* buf, ConfigRecord& r) {
  Reader rd(buf);
  r.cfg_id = rd.u8();
  rd.skip(3);  // channel count (always 6 in this version) and reserved
  r.rate_hz = rd.f64();
  for (double& l : r.lsb) {
    l = rd.f64();
  }
}

void parse(const std::uint8_t* buf, SampleRecord& r) {
  Reader rd(buf);
  r.seq = rd.u32();
  r.t_sensor_ns = rd.u64();
  for (std::int32_t& c : r.counts) {
    c = rd.i32();
  }
  r.cfg_id = rd.u8();
  r.sat_mask = rd.u8();
}

void parse(const std::uint8_t* buf, AdevRecord& r) {
  Reader rd(buf);
  r.channel = rd.u8();
  r.index = rd.u8();
  r.n_points = rd.u8();
  rd.skip(1);
  r.tau_s = rd.f32();
  r.adev = rd.f32();
  r.ci_lo = rd.f32();
  r.ci_hi = rd.f32();
  r.n_terms = rd.u32();
}

void parse(const std::uint8_t* buf, BiasRecord& r) {
  Reader rd(buf);
  r.seq = rd.u32();
  for (float& b : r.bias) {
    b = rd.f32();
  }
  for (float& v : r.var) {
    v = rd.f32();
  }
  r.flags = rd.u8();
}

void parse(const std::uint8_t* buf, MonitorRecord& r) {
  Reader rd(buf);
  r.seq = rd.u32();
  r.nis_mean = rd.f32();
  r.whiteness = rd.f32();
  r.flags = rd.u16();
  r.cusum_mask = rd.u8();
}

void parse(const std::uint8_t* buf, StatsRecord& r) {
  Reader rd(buf);
  r.frames = rd.u32();
  r.samples = rd.u32();
  r.missing = rd.u32();
  r.crc_errors = rd.u32();
  r.bad_mtu_or_dlc = rd.u32();
  r.unknown_id = rd.u32();
  r.duplicates = rd.u32();
  r.truncated = rd.u32();
  r.error_frames = rd.u32();
  r.kernel_drops = rd.u32();
}

void parse(const std::uint8_t* buf, RejectsRecord& r) {
  Reader rd(buf);
  r.bad_config = rd.u32();
  r.config_same_values = rd.u32();
  r.model_rejected = rd.u32();
  r.samples_before_config = rd.u32();
  r.cfg_mismatch = rd.u32();
  r.late = rd.u32();
  r.resyncs = rd.u32();
  r.remote_frames = rd.u32();
  r.bad_fragment = rd.u32();
  r.orphan_fragments = rd.u32();
  r.busy = rd.u32();
  r.telemetry_failures = rd.u32();
  r.gpio_errors = rd.u32();
  r.peer_refused = rd.u32();
  r.bad_record = rd.u32();
}

void parse(const std::uint8_t* buf, ModelRecord& r) {
  Reader rd(buf);
  r.version = rd.u8();
  r.channel = rd.u8();
  r.n_states = rd.u8();
  r.flags = rd.u8();
  r.n = rd.f32();
  r.q = rd.f32();
  r.gm_sb[0] = rd.f32();
  r.gm_tb_s[0] = rd.f32();
  r.gm_sb[1] = rd.f32();
  r.gm_tb_s[1] = rd.f32();
  r.k = rd.f32();
  r.bi = rd.f32();
  r.bi_tau_lo_s = rd.f32();
  r.bi_tau_hi_s = rd.f32();
  const bool v2 = r.version == kModelVersion2;  // version 1 has no slot for these: 0
  r.n_filter_s = v2 ? rd.f32() : 0.0F;
  r.osc_sigma = v2 ? rd.f32() : 0.0F;
  r.osc_f0_hz = v2 ? rd.f32() : 0.0F;
  r.osc_beta_per_s = v2 ? rd.f32() : 0.0F;
}

void parse(const std::uint8_t* buf, ChannelMonitorRecord& r) {
  Reader rd(buf);
  r.channel = rd.u8();
  r.n_states = rd.u8();
  r.flags = rd.u8();
  r.cusum_detections = rd.u8();
  r.seq = rd.u32();
  r.updates = rd.u32();
  r.nis_mean = rd.f32();
  r.nis_last_block = rd.f32();
  r.whiteness = rd.f32();
  r.blocks = rd.u32();
  r.nis_flagged = rd.u32();
  r.white_flagged = rd.u32();
  r.cusum_step_update = rd.u32();
}

void parse(const std::uint8_t* buf, ModelSignalsRecord& r) {
  Reader rd(buf);
  r.channel = rd.u8();
  r.flags = rd.u8();
  rd.skip(2);  // reserved
  r.ramp_r = rd.f32();
  r.sin_a[0] = rd.f32();
  r.sin_a[1] = rd.f32();
  r.sin_f0_hz[0] = rd.f32();
  r.sin_f0_hz[1] = rd.f32();
  r.memory_s = rd.f32();
}

// ---- encode ----------------------------------------------------------------------------------

void encode(const ConfigRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out) {
  std::uint8_t buf[kConfigLen];
  serialize(r, buf);
  frame_record(buf, kConfigLen, RecordKind::kConfig, layout, transfer_id, out);
}

void encode(const SampleRecord& r, Layout layout, EncodedFrames& out) {
  std::uint8_t buf[kSampleLen];
  serialize(r, buf);
  frame_record(buf, kSampleLen, RecordKind::kSample, layout,
               static_cast<std::uint8_t>(r.seq & 0x0FU), out);
}

void encode(const AdevRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out) {
  std::uint8_t buf[kAdevLen];
  serialize(r, buf);
  frame_record(buf, kAdevLen, RecordKind::kAdev, layout, transfer_id, out);
}

void encode(const BiasRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out) {
  std::uint8_t buf[kBiasLen];
  serialize(r, buf);
  frame_record(buf, kBiasLen, RecordKind::kBias, layout, transfer_id, out);
}

void encode(const MonitorRecord& r, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out) {
  std::uint8_t buf[kMonitorLen];
  serialize(r, buf);
  frame_record(buf, kMonitorLen, RecordKind::kMonitor, layout, transfer_id, out);
}

void encode(const StatsRecord& r, Layout layout, std::uint8_t transfer_id, EncodedFrames& out) {
  std::uint8_t buf[kStatsLen];
  serialize(r, buf);
  frame_record(buf, kStatsLen, RecordKind::kStats, layout, transfer_id, out);
}

void encode(const RejectsRecord& r, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out) {
  std::uint8_t buf[kRejectsLen];
  serialize(r, buf);
  frame_record(buf, kRejectsLen, RecordKind::kRejects, layout, transfer_id, out);
}

void encode(const ModelRecord& r, bool echo, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out) {
  const bool v2 = r.version == kModelVersion2;
  const RecordKind kind = v2 ? (echo ? RecordKind::kModelEcho2 : RecordKind::kModel2)
                             : (echo ? RecordKind::kModelEcho : RecordKind::kModel);
  std::uint8_t buf[kModel2Len];
  serialize(r, buf);
  frame_record(buf, record_len(kind), kind, layout, transfer_id, out);
}

void encode(const ChannelMonitorRecord& r, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out) {
  std::uint8_t buf[kChannelMonitorLen];
  serialize(r, buf);
  frame_record(buf, kChannelMonitorLen, RecordKind::kChannelMonitor, layout, transfer_id, out);
}

void encode(const ModelSignalsRecord& r, bool echo, Layout layout, std::uint8_t transfer_id,
            EncodedFrames& out) {
  const RecordKind kind = echo ? RecordKind::kModelSignalsEcho : RecordKind::kModelSignals;
  std::uint8_t buf[kModelSignalsLen];
  serialize(r, buf);
  frame_record(buf, kModelSignalsLen, kind, layout, transfer_id, out);
}

}  // namespace imu::hal

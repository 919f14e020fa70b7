// imu/hal/codec.hpp: CRC, frame layouts (byte positions written out by hand from the protocol
// table in hal/README.md), record round trips in both layouts, LSB exactness.
#include "imu/hal/codec.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "imu/hal/receiver.hpp"
#include "imu/online_adev.hpp"
#include "imu/terms.hpp"

namespace {

using imu::hal::CanFrame;
using imu::hal::EncodedFrames;
using imu::hal::Layout;

std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

// Bit patterns: the codec copies float fields bit for bit, so the test compares the bits.
std::uint64_t bits(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}
std::uint32_t bits(float v) {
  std::uint32_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

imu::hal::SampleRecord make_sample() {
  imu::hal::SampleRecord s{};
  s.seq = 0x01020304U;
  s.t_sensor_ns = 0x1122334455667788ULL;
  const std::int32_t c[6] = {1, -1, 300, -300, 0x7FFFFFFF, -2147483647 - 1};
  for (int i = 0; i < 6; ++i) {
    s.counts[i] = c[i];
  }
  s.cfg_id = 7;
  s.sat_mask = 0x30;
  return s;
}

// Every event a fresh receiver gives for the frames of one encoded record.
std::vector<imu::hal::RxEvent> decode(const EncodedFrames& out) {
  imu::hal::Receiver<8> rx;
  std::vector<imu::hal::RxEvent> ev;
  for (std::size_t i = 0; i < out.count; ++i) {
    (void)rx.push_drain(out.frame[i], imu::hal::wire_size(out.frame[i]), 0,
                        [&ev](const imu::hal::RxEvent& e) { ev.push_back(e); });
  }
  return ev;
}

// The first frame of a CRC-valid record the receiver must refuse: no event, one bad_record, no
// CRC error.
void expect_refused(const EncodedFrames& out) {
  imu::hal::Receiver<8> rx;
  std::size_t got = 0;
  (void)rx.push_drain(out.frame[0], imu::hal::wire_size(out.frame[0]), 0,
                      [&got](const imu::hal::RxEvent&) { ++got; });
  EXPECT_EQ(got, 0U);
  EXPECT_EQ(rx.stats().bad_record, 1U);
  EXPECT_EQ(rx.stats().crc_errors, 0U);
}

TEST(Crc32c, CheckValueOfTheCatalogue) {
  // CRC catalogue (reveng) entry CRC-32/ISCSI: check = 0xE3069283 for "123456789".
  const char* msg = "123456789";
  EXPECT_EQ(imu::hal::crc32c(reinterpret_cast<const std::uint8_t*>(msg), 9), 0xE3069283U);
  // RFC 3720 B.4: 32 bytes of zeros -> 0x8A9136AA.
  std::uint8_t zeros[32] = {};
  EXPECT_EQ(imu::hal::crc32c(zeros, sizeof zeros), 0x8A9136AAU);
}

TEST(Codec, FdLengthsAreTheValidCanFdLengths) {
  EXPECT_EQ(imu::hal::fd_len_for(0), 0);
  EXPECT_EQ(imu::hal::fd_len_for(8), 8);
  EXPECT_EQ(imu::hal::fd_len_for(9), 12);
  EXPECT_EQ(imu::hal::fd_len_for(20), 20);
  EXPECT_EQ(imu::hal::fd_len_for(21), 24);
  EXPECT_EQ(imu::hal::fd_len_for(42), 48);
  EXPECT_EQ(imu::hal::fd_len_for(60), 64);
}

TEST(Codec, SampleFdFrameLayoutMatchesTheTable) {
  EncodedFrames out{};
  imu::hal::encode(make_sample(), Layout::kFd, out);
  ASSERT_EQ(out.count, 1U);
  const CanFrame& f = out.frame[0];
  EXPECT_EQ(f.can_id, 0x100U);
  EXPECT_EQ(f.len, 48);
  EXPECT_EQ(f.flags, imu::hal::kCanFdFdf | imu::hal::kCanFdBrs);
  EXPECT_EQ(imu::hal::wire_size(f), 72U);
  const std::uint8_t expect_head[] = {0x04, 0x03, 0x02, 0x01,                          // seq
                                      0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11,  // t_ns
                                      0x01, 0x00, 0x00, 0x00,                          // ax = 1
                                      0xFF, 0xFF, 0xFF, 0xFF,                          // ay = -1
                                      0x2C, 0x01, 0x00, 0x00,                          // az = 300
                                      0xD4, 0xFE, 0xFF, 0xFF,                          // gx = -300
                                      0xFF, 0xFF, 0xFF, 0x7F,                          // gy = max
                                      0x00, 0x00, 0x00, 0x80,                          // gz = min
                                      0x07, 0x30};                                     // cfg, sat
  ASSERT_EQ(sizeof expect_head, 38U);
  for (std::size_t i = 0; i < sizeof expect_head; ++i) {
    EXPECT_EQ(f.data[i], expect_head[i]) << "byte " << i;
  }
  EXPECT_EQ(le32(f.data + 38), imu::hal::crc32c(expect_head, 38));
  for (std::size_t i = 42; i < 64; ++i) {
    EXPECT_EQ(f.data[i], 0) << "padding byte " << i;
  }
}

TEST(Codec, SampleClassicFramesCarrySevenBytesAndACounter) {
  EncodedFrames fd{};
  EncodedFrames cc{};
  const auto s = make_sample();
  imu::hal::encode(s, Layout::kFd, fd);
  imu::hal::encode(s, Layout::kClassic, cc);
  ASSERT_EQ(cc.count, 6U);  // 42 bytes / 7
  for (std::size_t k = 0; k < cc.count; ++k) {
    const CanFrame& f = cc.frame[k];
    EXPECT_EQ(f.can_id, 0x101U);
    EXPECT_EQ(f.len, 8);
    EXPECT_EQ(f.flags, 0);
    EXPECT_EQ(imu::hal::wire_size(f), 16U);
    EXPECT_EQ(f.data[0], 0x40U | k) << "counter = seq & 0xF = 4, fragment k";
    for (std::size_t i = 0; i < 7; ++i) {
      EXPECT_EQ(f.data[1 + i], fd.frame[0].data[7 * k + i]);
    }
  }
}

TEST(Codec, FrameCountsPerRecordKind) {
  EncodedFrames out{};
  imu::hal::encode(imu::hal::ConfigRecord{}, Layout::kClassic, 0, out);
  EXPECT_EQ(out.count, 10U);  // 64 bytes
  imu::hal::encode(imu::hal::ConfigRecord{}, Layout::kFd, 0, out);
  EXPECT_EQ(out.frame[0].len, 64);
  imu::hal::encode(imu::hal::AdevRecord{}, Layout::kClassic, 0, out);
  EXPECT_EQ(out.count, 4U);  // 28 bytes
  imu::hal::encode(imu::hal::AdevRecord{}, Layout::kFd, 0, out);
  EXPECT_EQ(out.frame[0].len, 32);
  imu::hal::encode(imu::hal::BiasRecord{}, Layout::kClassic, 0, out);
  EXPECT_EQ(out.count, 9U);  // 60 bytes
  imu::hal::encode(imu::hal::MonitorRecord{}, Layout::kFd, 0, out);
  EXPECT_EQ(out.frame[0].len, 20);
  EXPECT_EQ(out.frame[0].can_id, 0x220U);
  imu::hal::encode(imu::hal::StatsRecord{}, Layout::kClassic, 3, out);
  EXPECT_EQ(out.count, 7U);  // 44 bytes
  EXPECT_EQ(out.frame[6].can_id, 0x231U);
  EXPECT_EQ(out.frame[6].data[0], 0x36U);
}

TEST(Codec, EveryRecordEndsWithItsCrc) {
  std::uint8_t buf[80];
  std::memset(buf, 0xA5, sizeof buf);
  imu::hal::ConfigRecord c{};
  c.rate_hz = 100.0;
  imu::hal::serialize(c, buf);
  EXPECT_TRUE(imu::hal::crc_ok(buf, imu::hal::kConfigLen));
  EXPECT_EQ(buf[imu::hal::kConfigLen], 0xA5) << "serialize wrote past the record";
  buf[10] ^= 0x01;
  EXPECT_FALSE(imu::hal::crc_ok(buf, imu::hal::kConfigLen));
  std::memset(buf, 0xA5, sizeof buf);
  imu::hal::serialize(imu::hal::MonitorRecord{}, buf);
  EXPECT_TRUE(imu::hal::crc_ok(buf, imu::hal::kMonitorLen));
  EXPECT_EQ(buf[imu::hal::kMonitorLen], 0xA5);
  std::memset(buf, 0xA5, sizeof buf);
  imu::hal::serialize(imu::hal::BiasRecord{}, buf);
  EXPECT_TRUE(imu::hal::crc_ok(buf, imu::hal::kBiasLen));
  EXPECT_EQ(buf[imu::hal::kBiasLen], 0xA5);
}

TEST(Codec, TelemetryRoundTripsExactly) {
  // float32 and float64 fields are copied bit for bit, so equality of bit patterns is expected.
  imu::hal::ConfigRecord c{};
  c.cfg_id = 3;
  c.rate_hz = 100.0;
  c.lsb[0] = 0.00333 * 9.80665;
  c.lsb[3] = 0.05 * 3.14159265358979323846 / 180.0;
  std::uint8_t buf[64];
  imu::hal::serialize(c, buf);
  imu::hal::ConfigRecord c2{};
  imu::hal::parse(buf, c2);
  EXPECT_EQ(c2.cfg_id, 3);
  EXPECT_EQ(bits(c2.lsb[0]), bits(c.lsb[0]));
  EXPECT_EQ(bits(c2.lsb[3]), bits(c.lsb[3]));
  EXPECT_EQ(bits(c2.rate_hz), bits(c.rate_hz));

  imu::hal::AdevRecord a{};
  a.channel = 5;
  a.index = 9;
  a.n_points = 40;
  a.tau_s = 0.32F;
  a.adev = 1.25e-3F;
  a.ci_lo = 1.2e-3F;
  a.ci_hi = 1.3e-3F;
  a.n_terms = 123456;
  imu::hal::serialize(a, buf);
  imu::hal::AdevRecord a2{};
  imu::hal::parse(buf, a2);
  EXPECT_EQ(a2.channel, 5);
  EXPECT_EQ(a2.index, 9);
  EXPECT_EQ(a2.n_points, 40);
  EXPECT_EQ(bits(a2.adev), bits(a.adev));
  EXPECT_EQ(bits(a2.ci_hi), bits(a.ci_hi));
  EXPECT_EQ(a2.n_terms, 123456U);

  imu::hal::StatsRecord st{};
  st.frames = 1;
  st.kernel_drops = 0xDEADBEEF;
  imu::hal::serialize(st, buf);
  imu::hal::StatsRecord st2{};
  imu::hal::parse(buf, st2);
  EXPECT_EQ(st2.frames, 1U);
  EXPECT_EQ(st2.kernel_drops, 0xDEADBEEFU);
}

// The RejectsRecord (added later): 64 bytes, FD id 0x240 (len 64), classic 0x241 in 10
// fragments; every field at its own offset (distinct values), through the Receiver in both layouts.
TEST(Codec, RejectsRecordRoundTripsInBothLayouts) {
  imu::hal::RejectsRecord r{};
  std::uint32_t* fields[] = {&r.bad_config,         &r.config_same_values, &r.model_rejected,
                             &r.samples_before_config, &r.cfg_mismatch,    &r.late,
                             &r.resyncs,            &r.remote_frames,      &r.bad_fragment,
                             &r.orphan_fragments,   &r.busy,               &r.telemetry_failures,
                             &r.gpio_errors,        &r.peer_refused,       &r.bad_record};
  static_assert(sizeof(fields) / sizeof(fields[0]) * 4 + 4 == imu::hal::kRejectsLen, "fields");
  std::uint32_t v = 0x01020304U;
  for (std::uint32_t* f : fields) {
    *f = v;
    v += 0x11111111U;
  }
  for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
    EncodedFrames out{};
    imu::hal::encode(r, layout, 5, out);
    if (layout == Layout::kFd) {
      ASSERT_EQ(out.count, 1U);
      EXPECT_EQ(out.frame[0].can_id, 0x240U);
      EXPECT_EQ(out.frame[0].len, 64);
    } else {
      ASSERT_EQ(out.count, 10U);
      EXPECT_EQ(out.frame[0].can_id, 0x241U);
    }
    imu::hal::Receiver<8> rx;
    std::size_t got = 0;
    for (std::size_t i = 0; i < out.count; ++i) {
      (void)rx.push_drain(out.frame[i], imu::hal::wire_size(out.frame[i]), 0,
                          [&](const imu::hal::RxEvent& e) {
                            ASSERT_EQ(e.type, imu::hal::RxEvent::Type::kRejects);
                            EXPECT_EQ(std::memcmp(&e.rec.rejects, &r, sizeof r), 0);
                            ++got;
                          });
    }
    EXPECT_EQ(got, 1U);
    EXPECT_EQ(rx.stats().records[static_cast<std::size_t>(imu::hal::RecordKind::kRejects)], 1U);
    EXPECT_EQ(rx.stats().crc_errors, 0U);
  }
}

TEST(Codec, IdentifierClassification) {
  imu::hal::RecordKind k{};
  Layout l{};
  ASSERT_TRUE(imu::hal::kind_of_id(0x101, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kSample);
  EXPECT_EQ(l, Layout::kClassic);
  ASSERT_TRUE(imu::hal::kind_of_id(0x080, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kConfig);
  EXPECT_EQ(l, Layout::kFd);
  EXPECT_FALSE(imu::hal::kind_of_id(0x102, k, l));
  EXPECT_FALSE(imu::hal::kind_of_id(0x100U | imu::hal::kCanEffFlag, k, l));
  EXPECT_FALSE(imu::hal::kind_of_id(0x100U | imu::hal::kCanRtrFlag, k, l));
}

// The sensor's own counts travel exactly: with the LSB announced in the config frame, a value
// stored as k * lsb (how the .mat data was produced) quantises back to k for every k in the
// +-16 g range, and int32 holds it with room to spare.
TEST(Codec, AdisCountsAreCarriedExactlyOverTheFullRange) {
  // The .mat files store acc_lsb = 0.0326561445 and gyro_lsb = 8.726646259971648e-4, which are
  // these two expressions evaluated in double (checked with a MAT reader when writing this).
  const double acc_lsb = 0.00333 * 9.80665;
  const double gyro_lsb = 0.05 * 3.14159265358979323846 / 180;
  EXPECT_EQ(bits(acc_lsb), bits(imu::hal::kAdisAccLsb_mps2));
  EXPECT_EQ(bits(gyro_lsb), bits(imu::hal::kAdisGyroLsb_rps));
  const auto acc_max = static_cast<std::int32_t>(16.0 * 9.80665 / acc_lsb) + 1;
  const auto gyro_max = static_cast<std::int32_t>(2000.0 / 0.05) + 1;
  for (std::int32_t k = -acc_max; k <= acc_max; ++k) {
    const auto q = imu::quantize(static_cast<double>(k) * acc_lsb, acc_lsb);
    ASSERT_EQ(q.counts, k);
    ASSERT_FALSE(q.saturated);
  }
  for (std::int32_t k = -gyro_max; k <= gyro_max; ++k) {
    const auto q = imu::quantize(static_cast<double>(k) * gyro_lsb, gyro_lsb);
    ASSERT_EQ(q.counts, k);
  }
}

// A double-precision record quantised with the fine LSBs: the added error is below 1 % of the
// smallest per-sample white-noise standard deviation measured on the ADIS16405 records
// (hal/README.md: acc_y 0.0268 m/s^2, gyro_x 0.00548 rad/s at 100 Hz), and +-16 g and
// +-2000 deg/s fit without saturation.
TEST(Codec, FineLsbAddsLessThanOnePercentOfWhiteNoise) {
  struct Case {
    double sigma;
    double lsb;
    double full_scale;
  };
  const Case cases[] = {{0.0268, imu::hal::kFineAccLsb_mps2, 16.0 * 9.80665},
                        {0.00548, imu::hal::kFineGyroLsb_rps, 2000.0 * 3.14159265358979 / 180}};
  std::mt19937_64 rng(12345);
  for (const Case& c : cases) {
    std::normal_distribution<double> noise(0.0, c.sigma);
    double sum_e2 = 0.0;
    constexpr int kN = 100000;
    for (int i = 0; i < kN; ++i) {
      const double x = noise(rng);
      const auto q = imu::quantize(x, c.lsb);
      ASSERT_FALSE(q.saturated);
      const double e = static_cast<double>(q.counts) * c.lsb - x;
      sum_e2 += e * e;
    }
    const double err_std = std::sqrt(sum_e2 / kN);
    EXPECT_LT(err_std, 0.01 * c.sigma);
    // Rounding error is uniform in +-lsb/2: its std is lsb/sqrt(12); 10 % covers the sampling
    // error of a std estimated from 1e5 samples (about 0.3 %) with a wide margin.
    EXPECT_NEAR(err_std, c.lsb / std::sqrt(12.0), 0.1 * c.lsb / std::sqrt(12.0));
    EXPECT_FALSE(imu::quantize(c.full_scale, c.lsb).saturated);
    EXPECT_FALSE(imu::quantize(-c.full_scale, c.lsb).saturated);
  }
}

}  // namespace

// ModelRecord version 1: 48 bytes, 0x090/0x091 as a push and 0x250/0x251 as the node's echo,
// every field back bit-exact in both layouts; an unknown version or a channel >= 6 is refused
// as bad_record even with a valid CRC.
TEST(Codec, ModelRecordRoundTripsAndRefusesBadVersionOrChannel) {
  imu::hal::ModelRecord r{};
  r.version = imu::hal::kModelVersion1;
  r.channel = 5;
  r.n_states = 7;
  r.flags = imu::hal::kModelPushed;
  float* const fields[] = {&r.n,         &r.q,  &r.gm_sb[0], &r.gm_tb_s[0],    &r.gm_sb[1],
                           &r.gm_tb_s[1], &r.k, &r.bi,       &r.bi_tau_lo_s, &r.bi_tau_hi_s};
  float v = 1.25e-3F;
  for (float* f : fields) {
    *f = v;
    v *= 3.5F;
  }
  for (const bool echo : {false, true}) {
    for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
      EncodedFrames out{};
      imu::hal::encode(r, echo, layout, 3, out);
      const std::uint32_t id = (echo ? 0x250U : 0x090U) + (layout == Layout::kFd ? 0U : 1U);
      ASSERT_EQ(out.count, layout == Layout::kFd ? 1U : 7U);
      EXPECT_EQ(out.frame[0].can_id, id);
      const auto ev = decode(out);
      ASSERT_EQ(ev.size(), 1U);
      const imu::hal::RxEvent& e = ev[0];
      ASSERT_EQ(e.type, echo ? imu::hal::RxEvent::Type::kModelEcho : imu::hal::RxEvent::Type::kModel);
      // Bit-exact: the wire bytes of what came back equal those sent.
      std::uint8_t a[imu::hal::kModelLen];
      std::uint8_t b[imu::hal::kModelLen];
      imu::hal::serialize(e.rec.model, a);
      imu::hal::serialize(r, b);
      EXPECT_EQ(std::memcmp(a, b, sizeof a), 0);
      EXPECT_EQ(e.rec.model.channel, 5U);
      EXPECT_EQ(e.rec.model.n_states, 7U);
    }
  }
  for (const int bad : {0, 1}) {
    imu::hal::ModelRecord b = r;
    if (bad == 0) {
      b.version = 3;  // no such version: written in the version 1 layout, refused
    } else {
      b.channel = 6;
    }
    EncodedFrames out{};
    imu::hal::encode(b, false, Layout::kFd, 0, out);
    expect_refused(out);
  }
}

namespace {

// A version 2 model record with every field distinct (the new four included).
imu::hal::ModelRecord model_v2() {
  imu::hal::ModelRecord r{};
  r.version = imu::hal::kModelVersion2;
  r.channel = 4;
  r.n_states = 8;
  r.flags = imu::hal::kModelPushed;
  float* const fields[] = {&r.n,          &r.q,          &r.gm_sb[0], &r.gm_tb_s[0],
                           &r.gm_sb[1],   &r.gm_tb_s[1], &r.k,        &r.bi,
                           &r.bi_tau_lo_s, &r.bi_tau_hi_s, &r.n_filter_s, &r.osc_sigma,
                           &r.osc_f0_hz,  &r.osc_beta_per_s};
  float v = 7.5e-4F;
  for (float* f : fields) {
    *f = v;
    v *= 2.75F;
  }
  return r;
}

// Little-endian writer of a record written out by hand from hal/README.md (not by the codec).
struct Bytes {
  std::vector<std::uint8_t> b;
  void u8(std::uint8_t v) { b.push_back(v); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
      b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
  }
  void f32(float v) { u32(bits(v)); }
  void crc() { u32(imu::hal::crc32c(b.data(), b.size())); }
};

// One FD frame carrying `rec` on `id`, len = the record's length (48 and 64 are FD lengths).
EncodedFrames fd_frame(std::uint32_t id, const std::vector<std::uint8_t>& rec) {
  EncodedFrames out{};
  CanFrame& f = out.frame[0];
  f.can_id = id;
  f.len = static_cast<std::uint8_t>(rec.size());
  f.flags = imu::hal::kCanFdFdf | imu::hal::kCanFdBrs;
  std::memcpy(f.data, rec.data(), rec.size());
  out.count = 1;
  return out;
}

}  // namespace

// ModelRecord version 2: 64 bytes (the version 1 fields, then n_filter_s, osc_sigma, osc_f0_hz,
// osc_beta_per_s, then the CRC), 0x092/0x093 as a push and 0x252/0x253 as the echo; one FD
// frame of len 64 or 10 classic frames; every field back bit for bit, arriving as the same
// kModel / kModelEcho events as version 1 with version 2.
TEST(Codec, ModelRecordVersion2RoundTripsInBothLayouts) {
  const imu::hal::ModelRecord r = model_v2();
  for (const bool echo : {false, true}) {
    for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
      EncodedFrames out{};
      imu::hal::encode(r, echo, layout, 11, out);
      const std::uint32_t id = (echo ? 0x252U : 0x092U) + (layout == Layout::kFd ? 0U : 1U);
      ASSERT_EQ(out.count, layout == Layout::kFd ? 1U : 10U);  // ceil(64 / 7)
      for (std::size_t i = 0; i < out.count; ++i) {
        EXPECT_EQ(out.frame[i].can_id, id);
        EXPECT_EQ(out.frame[i].len, layout == Layout::kFd ? 64U : 8U);
      }
      const auto ev = decode(out);
      ASSERT_EQ(ev.size(), 1U);
      const imu::hal::RxEvent& e = ev[0];
      ASSERT_EQ(e.type, echo ? imu::hal::RxEvent::Type::kModelEcho : imu::hal::RxEvent::Type::kModel);
      const imu::hal::ModelRecord& m = e.rec.model;
      EXPECT_EQ(m.version, imu::hal::kModelVersion2);
      EXPECT_EQ(m.channel, 4U);
      EXPECT_EQ(m.n_states, 8U);
      EXPECT_EQ(bits(m.n_filter_s), bits(r.n_filter_s));
      EXPECT_EQ(bits(m.osc_sigma), bits(r.osc_sigma));
      EXPECT_EQ(bits(m.osc_f0_hz), bits(r.osc_f0_hz));
      EXPECT_EQ(bits(m.osc_beta_per_s), bits(r.osc_beta_per_s));
      std::uint8_t a[imu::hal::kModel2Len];
      std::uint8_t b[imu::hal::kModel2Len];
      imu::hal::serialize(m, a);
      imu::hal::serialize(r, b);
      EXPECT_EQ(std::memcmp(a, b, sizeof a), 0);
    }
  }
  // The wire bytes, offset by offset, against the layout written out by hand.
  Bytes want;
  want.u8(2);
  want.u8(4);
  want.u8(8);
  want.u8(imu::hal::kModelPushed);
  for (const float v : {r.n, r.q, r.gm_sb[0], r.gm_tb_s[0], r.gm_sb[1], r.gm_tb_s[1], r.k, r.bi,
                        r.bi_tau_lo_s, r.bi_tau_hi_s, r.n_filter_s, r.osc_sigma, r.osc_f0_hz,
                        r.osc_beta_per_s}) {
    want.f32(v);
  }
  want.crc();
  ASSERT_EQ(want.b.size(), imu::hal::kModel2Len);
  std::uint8_t got[imu::hal::kModel2Len];
  imu::hal::serialize(r, got);
  EXPECT_EQ(std::memcmp(got, want.b.data(), want.b.size()), 0);
  EXPECT_EQ(le32(got + 60), imu::hal::crc32c(got, 60));
}

// A 48-byte version 1 record as old host tools and recorded candumps have it (bytes written by
// hand) still parses, in both layouts, with the version 2 fields 0; the codec writes the
// version 1 layout unchanged.
TEST(Codec, ModelRecordVersion1BytesStillParse) {
  Bytes v1;
  v1.u8(1);
  v1.u8(3);
  v1.u8(0);
  v1.u8(0);
  const float vals[] = {3.3e-3F, 1e-5F, 2.68e-8F, 158.7F, 0.0F, 0.0F, 1.4e-4F, 0.0F, 0.0F, 0.0F};
  for (const float v : vals) {
    v1.f32(v);
  }
  v1.crc();
  ASSERT_EQ(v1.b.size(), imu::hal::kModelLen);
  // FD as recorded, and the classic fragments (7 bytes each, counter 5) built by hand too.
  std::vector<EncodedFrames> as_sent{fd_frame(0x090, v1.b)};
  EncodedFrames classic{};
  classic.count = 7;
  for (std::size_t k = 0; k < 7; ++k) {
    CanFrame& f = classic.frame[k];
    f.can_id = 0x091;
    f.len = 8;
    f.data[0] = static_cast<std::uint8_t>((5U << 4) | k);
    for (std::size_t i = 0; i < 7; ++i) {
      f.data[1 + i] = 7 * k + i < v1.b.size() ? v1.b[7 * k + i] : 0;
    }
  }
  as_sent.push_back(classic);
  for (const EncodedFrames& frames : as_sent) {
    const auto ev = decode(frames);
    ASSERT_EQ(ev.size(), 1U);
    ASSERT_EQ(ev[0].type, imu::hal::RxEvent::Type::kModel);
    const imu::hal::ModelRecord& m = ev[0].rec.model;
    EXPECT_EQ(m.version, imu::hal::kModelVersion1);
    EXPECT_EQ(m.channel, 3U);
    EXPECT_EQ(bits(m.n), bits(3.3e-3F));
    EXPECT_EQ(bits(m.gm_tb_s[0]), bits(158.7F));
    EXPECT_EQ(bits(m.k), bits(1.4e-4F));
    EXPECT_EQ(bits(m.n_filter_s), 0U);
    EXPECT_EQ(bits(m.osc_sigma), 0U);
    EXPECT_EQ(bits(m.osc_f0_hz), 0U);
    EXPECT_EQ(bits(m.osc_beta_per_s), 0U);
  }
  // parse() clears the version 2 fields of a version 1 record whatever the struct held.
  imu::hal::ModelRecord m = model_v2();
  imu::hal::parse(v1.b.data(), m);
  EXPECT_EQ(m.version, 1U);
  EXPECT_EQ(bits(m.n_filter_s) | bits(m.osc_sigma) | bits(m.osc_f0_hz) | bits(m.osc_beta_per_s),
            0U);
  // Writing it again gives the same 48 bytes, in both layouts.
  std::uint8_t again[imu::hal::kModelLen];
  imu::hal::serialize(m, again);
  EXPECT_EQ(std::memcmp(again, v1.b.data(), sizeof again), 0);
  EncodedFrames out{};
  imu::hal::encode(m, false, Layout::kFd, 0, out);
  EXPECT_EQ(out.frame[0].can_id, 0x090U);
  EXPECT_EQ(out.frame[0].len, 48U);
  imu::hal::encode(m, false, Layout::kClassic, 5, out);
  ASSERT_EQ(out.count, 7U);
  for (std::size_t k = 0; k < 7; ++k) {
    EXPECT_EQ(std::memcmp(&out.frame[k], &classic.frame[k], imu::hal::kCanMtu), 0) << k;
  }
}

// Refusals of version 2 records, each counted: a CRC error (a flipped bit, FD and classic); a
// version byte that is not the identifier's (2 on the version 1 ids, 1 on the version 2 ids, 3),
// a channel >= 6 (bad_record, CRC valid); a 48-byte frame on the 64-byte identifier (bad_dlc).
TEST(Codec, ModelRecordVersion2ErrorsAreRefusedAndCounted) {
  const imu::hal::ModelRecord r = model_v2();
  for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
    for (const std::size_t byte : {0U, 41U, 52U, 63U}) {  // version, a v1 field, a v2 field, CRC
      EncodedFrames out{};
      imu::hal::encode(r, true, layout, 2, out);
      if (layout == Layout::kFd) {
        out.frame[0].data[byte] ^= 0x10U;
      } else {
        out.frame[byte / 7].data[1 + byte % 7] ^= 0x10U;
      }
      imu::hal::Receiver<8> rx;
      std::size_t got = 0;
      for (std::size_t i = 0; i < out.count; ++i) {
        (void)rx.push_drain(out.frame[i], imu::hal::wire_size(out.frame[i]), 0,
                            [&got](const imu::hal::RxEvent&) { ++got; });
      }
      EXPECT_EQ(got, 0U) << byte;
      EXPECT_EQ(rx.stats().crc_errors, 1U) << byte;
      EXPECT_EQ(rx.stats().records[static_cast<std::size_t>(imu::hal::RecordKind::kModelEcho2)],
                0U);
    }
  }
  // Version 2 bytes with the version byte 1 on 0x092, version 1 bytes with 2 on 0x090: CRC
  // recomputed, so only the version check can refuse them.
  std::uint8_t v2[imu::hal::kModel2Len];
  imu::hal::serialize(r, v2);
  v2[0] = 1;
  std::vector<std::uint8_t> w2(v2, v2 + 60);
  Bytes b2{w2};
  b2.crc();
  expect_refused(fd_frame(0x092, b2.b));
  imu::hal::ModelRecord r1 = r;
  r1.version = imu::hal::kModelVersion1;
  std::uint8_t v1[imu::hal::kModelLen];
  imu::hal::serialize(r1, v1);
  v1[0] = 2;
  Bytes b1{std::vector<std::uint8_t>(v1, v1 + 44)};
  b1.crc();
  expect_refused(fd_frame(0x090, b1.b));
  for (const int bad : {0, 1}) {
    imu::hal::ModelRecord b = r;
    if (bad == 0) {
      b.channel = 6;
    } else {
      b.version = 3;
    }
    EncodedFrames out{};
    imu::hal::encode(b, false, Layout::kFd, 0, out);
    expect_refused(out);
  }
  // A version 2 id with a 48-byte FD frame: the id fixes the length.
  imu::hal::Receiver<8> rx;
  EncodedFrames short_frame = fd_frame(0x092, std::vector<std::uint8_t>(v2, v2 + 48));
  EXPECT_EQ(rx.push(short_frame.frame[0], imu::hal::kCanFdMtu, 0), imu::hal::FrameVerdict::kBadDlc);
  EXPECT_EQ(rx.stats().bad_dlc, 1U);
  // The identifiers: both new kinds, FD and classic.
  imu::hal::RecordKind k{};
  Layout l{};
  ASSERT_TRUE(imu::hal::kind_of_id(0x093, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kModel2);
  EXPECT_EQ(l, Layout::kClassic);
  ASSERT_TRUE(imu::hal::kind_of_id(0x252, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kModelEcho2);
  EXPECT_EQ(l, Layout::kFd);
  EXPECT_EQ(imu::hal::record_len(imu::hal::RecordKind::kModel2), 64U);
  EXPECT_EQ(imu::hal::model_version(imu::hal::RecordKind::kModelEcho), 1U);
  EXPECT_EQ(imu::hal::model_version(imu::hal::RecordKind::kModelEcho2), 2U);
  EXPECT_EQ(imu::hal::model_version(imu::hal::RecordKind::kSample), 0U);
}

TEST(Codec, ChannelMonitorRecordRoundTripsAndRefusesABadChannel) {
  imu::hal::ChannelMonitorRecord r{};
  r.channel = 4;
  r.n_states = 6;
  r.flags = imu::hal::kChanMonCusum | imu::hal::kChanMonPushed;
  r.cusum_detections = 201;
  r.seq = 0xFEDCBA98U;
  r.updates = 1234567U;
  r.nis_mean = 1.0625F;
  r.nis_last_block = 0.96875F;
  r.whiteness = 3.5F;
  r.blocks = 1234U;
  r.nis_flagged = 17U;
  r.white_flagged = 99U;
  r.cusum_step_update = 765432U;
  for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
    EncodedFrames out{};
    imu::hal::encode(r, layout, 9, out);
    ASSERT_EQ(out.count, layout == Layout::kFd ? 1U : 7U);  // 44 bytes
    EXPECT_EQ(out.frame[0].can_id, layout == Layout::kFd ? 0x260U : 0x261U);
    const auto ev = decode(out);
    ASSERT_EQ(ev.size(), 1U);
    ASSERT_EQ(ev[0].type, imu::hal::RxEvent::Type::kChannelMonitor);
    std::uint8_t a[imu::hal::kChannelMonitorLen];
    std::uint8_t b[imu::hal::kChannelMonitorLen];
    imu::hal::serialize(ev[0].rec.channel_monitor, a);
    imu::hal::serialize(r, b);
    EXPECT_EQ(std::memcmp(a, b, sizeof a), 0);
    EXPECT_EQ(ev[0].rec.channel_monitor.cusum_step_update, 765432U);
    EXPECT_EQ(ev[0].rec.channel_monitor.cusum_detections, 201U);
    EXPECT_EQ(ev[0].rec.channel_monitor.white_flagged, 99U);
  }
  imu::hal::ChannelMonitorRecord b = r;
  b.channel = 6;  // no such channel: CRC-valid but refused, never an index out of range
  EncodedFrames out{};
  imu::hal::encode(b, Layout::kFd, 0, out);
  expect_refused(out);
}

namespace {

// A model signals record with every field distinct (a negative ramp: the slope is signed).
imu::hal::ModelSignalsRecord model_signals() {
  imu::hal::ModelSignalsRecord r{};
  r.channel = 5;
  r.flags = imu::hal::kModelPushed;
  r.ramp_r = -3.25e-5F;
  r.sin_a[0] = 1.5e-3F;
  r.sin_a[1] = 2.75e-4F;
  r.sin_f0_hz[0] = 50.0F;
  r.sin_f0_hz[1] = 100.0F;
  r.memory_s = 3600.5F;
  return r;
}

}  // namespace

// ModelSignalsRecord: 32 bytes (channel, flags, 2 reserved, ramp_r, sin_a[0], sin_a[1],
// sin_f0_hz[0], sin_f0_hz[1], memory_s, CRC), 0x094/0x095 as a push and 0x254/0x255 as the
// echo; one FD frame of len 32 or 5 classic frames; every field back bit for bit, as
// kModelSignals / kModelSignalsEcho events counted under their own kinds.
TEST(Codec, ModelSignalsRecordRoundTripsInBothLayouts) {
  const imu::hal::ModelSignalsRecord r = model_signals();
  for (const bool echo : {false, true}) {
    const imu::hal::RecordKind kind =
        echo ? imu::hal::RecordKind::kModelSignalsEcho : imu::hal::RecordKind::kModelSignals;
    const imu::hal::RecordKind other =
        echo ? imu::hal::RecordKind::kModelSignals : imu::hal::RecordKind::kModelSignalsEcho;
    for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
      EncodedFrames out{};
      imu::hal::encode(r, echo, layout, 13, out);
      const std::uint32_t id = (echo ? 0x254U : 0x094U) + (layout == Layout::kFd ? 0U : 1U);
      ASSERT_EQ(out.count, layout == Layout::kFd ? 1U : 5U);  // ceil(32 / 7)
      for (std::size_t i = 0; i < out.count; ++i) {
        EXPECT_EQ(out.frame[i].can_id, id);
        EXPECT_EQ(out.frame[i].len, layout == Layout::kFd ? 32U : 8U);
        if (layout == Layout::kClassic) {
          EXPECT_EQ(out.frame[i].data[0], 0xD0U | i) << "counter 13, fragment i";
        }
      }
      imu::hal::Receiver<8> rx;
      std::vector<imu::hal::RxEvent> ev;
      for (std::size_t i = 0; i < out.count; ++i) {
        (void)rx.push_drain(out.frame[i], imu::hal::wire_size(out.frame[i]), 0,
                            [&ev](const imu::hal::RxEvent& e) { ev.push_back(e); });
      }
      ASSERT_EQ(ev.size(), 1U);
      ASSERT_EQ(ev[0].type, echo ? imu::hal::RxEvent::Type::kModelSignalsEcho
                                 : imu::hal::RxEvent::Type::kModelSignals);
      const imu::hal::ModelSignalsRecord& m = ev[0].rec.signals;
      EXPECT_EQ(m.channel, 5U);
      EXPECT_EQ(m.flags, imu::hal::kModelPushed);
      EXPECT_EQ(bits(m.ramp_r), bits(r.ramp_r));
      EXPECT_EQ(bits(m.sin_a[0]), bits(r.sin_a[0]));
      EXPECT_EQ(bits(m.sin_a[1]), bits(r.sin_a[1]));
      EXPECT_EQ(bits(m.sin_f0_hz[0]), bits(r.sin_f0_hz[0]));
      EXPECT_EQ(bits(m.sin_f0_hz[1]), bits(r.sin_f0_hz[1]));
      EXPECT_EQ(bits(m.memory_s), bits(r.memory_s));
      std::uint8_t a[imu::hal::kModelSignalsLen];
      std::uint8_t b[imu::hal::kModelSignalsLen];
      imu::hal::serialize(m, a);
      imu::hal::serialize(r, b);
      EXPECT_EQ(std::memcmp(a, b, sizeof a), 0);
      EXPECT_EQ(rx.stats().records[static_cast<std::size_t>(kind)], 1U);
      EXPECT_EQ(rx.stats().records[static_cast<std::size_t>(other)], 0U);
      EXPECT_EQ(rx.stats().crc_errors, 0U);
      EXPECT_EQ(rx.stats().bad_record, 0U);
    }
  }
  // The wire bytes, offset by offset, against the layout written out by hand.
  Bytes want;
  want.u8(5);
  want.u8(imu::hal::kModelPushed);
  want.u8(0);
  want.u8(0);
  for (const float v : {r.ramp_r, r.sin_a[0], r.sin_a[1], r.sin_f0_hz[0], r.sin_f0_hz[1],
                        r.memory_s}) {
    want.f32(v);
  }
  want.crc();
  ASSERT_EQ(want.b.size(), imu::hal::kModelSignalsLen);
  std::uint8_t got[imu::hal::kModelSignalsLen + 1];
  std::memset(got, 0xA5, sizeof got);
  imu::hal::serialize(r, got);
  EXPECT_EQ(std::memcmp(got, want.b.data(), want.b.size()), 0);
  EXPECT_EQ(le32(got + 28), imu::hal::crc32c(got, 28));
  EXPECT_EQ(got[imu::hal::kModelSignalsLen], 0xA5) << "serialize wrote past the record";
  EXPECT_TRUE(imu::hal::crc_ok(got, imu::hal::kModelSignalsLen));
}

// Refusals of model signals records, each counted: a CRC error (a flipped bit, FD and classic);
// a channel >= 6 (bad_record, CRC valid, push and echo); a 48-byte FD frame on the 32-byte
// identifier (bad_dlc); a classic fragment index beyond the 5 fragments (bad_fragment). Nonzero
// reserved bytes are no reason to refuse. The identifiers classify back to the kinds.
TEST(Codec, ModelSignalsRecordErrorsAreRefusedAndCounted) {
  const imu::hal::ModelSignalsRecord r = model_signals();
  for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
    for (const std::size_t byte : {0U, 2U, 13U, 31U}) {  // channel, reserved, a float, CRC
      EncodedFrames out{};
      imu::hal::encode(r, true, layout, 4, out);
      if (layout == Layout::kFd) {
        out.frame[0].data[byte] ^= 0x10U;
      } else {
        out.frame[byte / 7].data[1 + byte % 7] ^= 0x10U;
      }
      imu::hal::Receiver<8> rx;
      std::size_t got = 0;
      for (std::size_t i = 0; i < out.count; ++i) {
        (void)rx.push_drain(out.frame[i], imu::hal::wire_size(out.frame[i]), 0,
                            [&got](const imu::hal::RxEvent&) { ++got; });
      }
      EXPECT_EQ(got, 0U) << byte;
      EXPECT_EQ(rx.stats().crc_errors, 1U) << byte;
      EXPECT_EQ(
          rx.stats().records[static_cast<std::size_t>(imu::hal::RecordKind::kModelSignalsEcho)],
          0U);
    }
  }
  for (const bool echo : {false, true}) {
    imu::hal::ModelSignalsRecord b = r;
    b.channel = 6;  // no such channel: CRC-valid but refused, never an index out of range
    EncodedFrames out{};
    imu::hal::encode(b, echo, Layout::kFd, 0, out);
    expect_refused(out);
  }
  // Reserved bytes set, CRC recomputed: accepted, the fields unchanged.
  std::uint8_t wire[imu::hal::kModelSignalsLen];
  imu::hal::serialize(r, wire);
  wire[2] = 0x5A;
  wire[3] = 0xFF;
  Bytes res{std::vector<std::uint8_t>(wire, wire + 28)};
  res.crc();
  const auto ev = decode(fd_frame(0x094, res.b));
  ASSERT_EQ(ev.size(), 1U);
  ASSERT_EQ(ev[0].type, imu::hal::RxEvent::Type::kModelSignals);
  EXPECT_EQ(ev[0].rec.signals.channel, 5U);
  EXPECT_EQ(bits(ev[0].rec.signals.ramp_r), bits(r.ramp_r));
  EXPECT_EQ(bits(ev[0].rec.signals.memory_s), bits(r.memory_s));
  // The identifier fixes the length: a 48-byte FD frame on 0x094 ...
  {
    imu::hal::Receiver<8> rx;
    EncodedFrames long_frame = fd_frame(0x094, std::vector<std::uint8_t>(48, 0));
    EXPECT_EQ(rx.push(long_frame.frame[0], imu::hal::kCanFdMtu, 0),
              imu::hal::FrameVerdict::kBadDlc);
    EXPECT_EQ(rx.stats().bad_dlc, 1U);
  }
  // ... and a classic fragment index 5 on 0x255 (a 32-byte record has fragments 0..4).
  {
    imu::hal::Receiver<8> rx;
    EncodedFrames out{};
    imu::hal::encode(r, true, Layout::kClassic, 1, out);
    ASSERT_EQ(out.count, 5U);
    CanFrame f = out.frame[4];
    f.data[0] = 0x15U;
    EXPECT_EQ(rx.push(f, imu::hal::kCanMtu, 0), imu::hal::FrameVerdict::kBadFragment);
    EXPECT_EQ(rx.stats().bad_fragment, 1U);
  }
  imu::hal::RecordKind k{};
  Layout l{};
  ASSERT_TRUE(imu::hal::kind_of_id(0x094, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kModelSignals);
  EXPECT_EQ(l, Layout::kFd);
  ASSERT_TRUE(imu::hal::kind_of_id(0x095, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kModelSignals);
  EXPECT_EQ(l, Layout::kClassic);
  ASSERT_TRUE(imu::hal::kind_of_id(0x254, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kModelSignalsEcho);
  EXPECT_EQ(l, Layout::kFd);
  ASSERT_TRUE(imu::hal::kind_of_id(0x255, k, l));
  EXPECT_EQ(k, imu::hal::RecordKind::kModelSignalsEcho);
  EXPECT_EQ(l, Layout::kClassic);
  EXPECT_FALSE(imu::hal::kind_of_id(0x096, k, l));
  EXPECT_FALSE(imu::hal::kind_of_id(0x256, k, l));
  EXPECT_EQ(imu::hal::record_len(imu::hal::RecordKind::kModelSignals), 32U);
  EXPECT_EQ(imu::hal::record_len(imu::hal::RecordKind::kModelSignalsEcho), 32U);
  EXPECT_EQ(imu::hal::model_version(imu::hal::RecordKind::kModelSignals), 0U);
  EXPECT_EQ(imu::hal::model_version(imu::hal::RecordKind::kModelSignalsEcho), 0U);
}

// Every kind has its own pair of identifiers (FD even, classic = FD + 1), and each of them
// classifies back to that kind and layout.
TEST(Codec, EveryKindHasItsOwnIdentifiers) {
  for (std::size_t i = 0; i < imu::hal::kRecordKinds; ++i) {
    const auto ki = static_cast<imu::hal::RecordKind>(i);
    const std::uint32_t id = imu::hal::fd_id(ki);
    EXPECT_EQ(id % 2U, 0U) << i;
    EXPECT_GT(imu::hal::record_len(ki), 0U) << i;
    EXPECT_LE(imu::hal::record_len(ki), imu::hal::kMaxRecordLen) << i;
    for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
      imu::hal::RecordKind k{};
      Layout l{};
      ASSERT_TRUE(imu::hal::kind_of_id(id + (layout == Layout::kFd ? 0U : 1U), k, l)) << i;
      EXPECT_EQ(k, ki) << i;
      EXPECT_EQ(l, layout) << i;
    }
    for (std::size_t j = 0; j < i; ++j) {
      const std::uint32_t other = imu::hal::fd_id(static_cast<imu::hal::RecordKind>(j));
      EXPECT_NE(id, other) << i << " " << j;
      EXPECT_NE(id + 1U, other) << i << " " << j;
      EXPECT_NE(id, other + 1U) << i << " " << j;
    }
  }
}

namespace {

// A float member of a model record, by its name in codec.hpp and its instance.
struct Member {
  const char* name;
  std::size_t instance;
  float* field;
};

}  // namespace

// The term registry's wire slots (terms.hpp TermWire) against the codec: every field a term
// names is, at the registry's byte offset of each instance, the record member of that name;
// and the terms' slots cover every float the two records carry for a model, each once (the
// signals' memory_s is the record's own, no term's).
TEST(Codec, EveryTermOfTheRegistryTravelsInItsSlot) {
  imu::hal::ModelRecord m{};
  m.version = imu::hal::kModelVersion2;
  m.channel = 2;
  imu::hal::ModelSignalsRecord sg{};
  sg.channel = 2;
  sg.memory_s = 1.5F;
  const std::vector<Member> model = {
      {"n", 0, &m.n},
      {"q", 0, &m.q},
      {"gm_sb", 0, &m.gm_sb[0]},
      {"gm_tb_s", 0, &m.gm_tb_s[0]},
      {"gm_sb", 1, &m.gm_sb[1]},
      {"gm_tb_s", 1, &m.gm_tb_s[1]},
      {"k", 0, &m.k},
      {"bi", 0, &m.bi},
      {"bi_tau_lo_s", 0, &m.bi_tau_lo_s},
      {"bi_tau_hi_s", 0, &m.bi_tau_hi_s},
      {"n_filter_s", 0, &m.n_filter_s},
      {"osc_sigma", 0, &m.osc_sigma},
      {"osc_f0_hz", 0, &m.osc_f0_hz},
      {"osc_beta_per_s", 0, &m.osc_beta_per_s}};
  const std::vector<Member> signals = {{"ramp_r", 0, &sg.ramp_r},
                                       {"sin_a", 0, &sg.sin_a[0]},
                                       {"sin_a", 1, &sg.sin_a[1]},
                                       {"sin_f0_hz", 0, &sg.sin_f0_hz[0]},
                                       {"sin_f0_hz", 1, &sg.sin_f0_hz[1]}};
  float next = 2.5F;  // distinct values, exact in float
  for (const std::vector<Member>* members : {&model, &signals}) {
    for (const Member& mm : *members) {
      *mm.field = next;
      next += 1.0F;
    }
  }
  std::uint8_t mb[imu::hal::kModel2Len];
  std::uint8_t sb[imu::hal::kModelSignalsLen];
  imu::hal::serialize(m, mb);
  imu::hal::serialize(sg, sb);
  constexpr std::size_t kCrcLen = 4;  // crc32c, the record's last bytes
  std::size_t model_slots = 0;
  std::size_t signal_slots = 0;
  std::vector<float> seen;
  for (const imu::TermInfo& t : imu::kTermTable) {
    const imu::TermWire& w = t.wire;
    ASSERT_NE(w.record, imu::WireRecord::kNone) << t.name;  // every term reaches the node
    ASSERT_GE(w.n_fields, 1U) << t.name;
    ASSERT_LE(w.n_fields, imu::kMaxWireFields) << t.name;
    const bool in_model = w.record == imu::WireRecord::kModel;
    const std::vector<Member>& members = in_model ? model : signals;
    const std::uint8_t* bytes = in_model ? mb : sb;
    const std::size_t len = in_model ? imu::hal::kModel2Len : imu::hal::kModelSignalsLen;
    for (std::size_t i = 0; i < t.max_instances; ++i) {
      ASSERT_LT(i, imu::kMaxWireInstances) << t.name;
      for (std::size_t j = 0; j < w.n_fields; ++j) {
        ASSERT_NE(w.fields[j], nullptr) << t.name;
        const std::size_t at = w.offset[i][j];
        ASSERT_GE(at, 4U) << t.name << " " << w.fields[j];  // after the record's header
        ASSERT_LE(at + 4U, len - kCrcLen) << t.name << " " << w.fields[j];  // before its CRC
        const Member* want = nullptr;
        for (const Member& mm : members) {
          want = std::strcmp(mm.name, w.fields[j]) == 0 && mm.instance == i ? &mm : want;
        }
        ASSERT_NE(want, nullptr) << t.name << " names no member " << w.fields[j];
        const std::uint32_t u = le32(bytes + at);
        float got = 0.0F;
        std::memcpy(&got, &u, sizeof got);
        EXPECT_EQ(got, *want->field) << t.name << " " << w.fields[j] << "[" << i
                                     << "] at byte " << at;
        seen.push_back(*want->field);
        (in_model ? model_slots : signal_slots) += 1;
      }
    }
  }
  EXPECT_EQ(model_slots, model.size());
  EXPECT_EQ(signal_slots, signals.size());
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end());  // each slot once
}

// imu/hal/receiver.hpp: every robustness case at the codec level (the transport tests repeat
// them through the loopback socket). Expected counts are worked out by hand per test.
#include "imu/hal/receiver.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace {

using imu::hal::CanFrame;
using imu::hal::EncodedFrames;
using imu::hal::FrameVerdict;
using imu::hal::Layout;
using imu::hal::RxEvent;
using Rx = imu::hal::Receiver<8>;

imu::hal::SampleRecord sample(std::uint32_t seq) {
  imu::hal::SampleRecord s{};
  s.seq = seq;
  s.t_sensor_ns = 10'000'000ULL * seq;
  for (int c = 0; c < 6; ++c) {
    s.counts[c] = static_cast<std::int32_t>(seq) * (c + 1) - 3;
  }
  return s;
}

/// What the consumer sees: sample seqs in order, with -n for a run of n missing samples.
struct Sink {
  std::vector<std::int64_t> seq;
  std::vector<RxEvent> other;
  std::uint32_t missing_end = 0;
  std::uint32_t resync_marks = 0;
  void drain(Rx& rx) {
    RxEvent e{};
    while (rx.pop(e)) {
      if (e.type == RxEvent::Type::kSample) {
        seq.push_back(e.rec.sample.seq);
      } else if (e.type == RxEvent::Type::kMissing) {
        resync_marks += e.resync ? 1U : 0U;
        // A run may arrive in pieces; the consumer adds them up (mark_missing(a + b)).
        if (!seq.empty() && seq.back() < 0 && e.missing_first_seq == missing_end) {
          seq.back() -= e.missing_count;
        } else {
          seq.push_back(-static_cast<std::int64_t>(e.missing_count));
        }
        missing_end = e.missing_first_seq + e.missing_count;
      } else {
        other.push_back(e);
      }
    }
  }
};

FrameVerdict push_frame(Rx& rx, Sink& sink, const CanFrame& f) {
  const FrameVerdict v = rx.push(f, imu::hal::wire_size(f), 1);
  sink.drain(rx);
  return v;
}

void send(Rx& rx, Sink& sink, std::uint32_t seq, Layout layout = Layout::kFd) {
  EncodedFrames out{};
  imu::hal::encode(sample(seq), layout, out);
  for (std::size_t i = 0; i < out.count; ++i) {
    (void)push_frame(rx, sink, out.frame[i]);
  }
}

void flush(Rx& rx, Sink& sink) {
  ASSERT_TRUE(rx.flush());
  sink.drain(rx);
}

std::vector<std::int64_t> range(std::int64_t a, std::int64_t b) {  // [a, b)
  std::vector<std::int64_t> v;
  for (std::int64_t i = a; i < b; ++i) {
    v.push_back(i);
  }
  return v;
}

TEST(Receiver, InOrderFdSamplesComeOutUnchanged) {
  Rx rx;
  Sink sink;
  EncodedFrames out{};
  imu::hal::encode(sample(42), Layout::kFd, out);
  ASSERT_EQ(rx.push(out.frame[0], 72, 555), FrameVerdict::kRecord);
  RxEvent e{};
  ASSERT_TRUE(rx.pop(e));
  EXPECT_EQ(e.type, RxEvent::Type::kSample);
  EXPECT_EQ(e.rx_time_ns, 555U);
  EXPECT_EQ(e.rec.sample.seq, 42U);
  EXPECT_EQ(e.rec.sample.t_sensor_ns, 420'000'000ULL);
  EXPECT_EQ(e.rec.sample.counts[0], 42 * 1 - 3);
  EXPECT_EQ(e.rec.sample.counts[5], 42 * 6 - 3);
  EXPECT_FALSE(rx.pop(e));
  for (std::uint32_t s = 43; s < 100; ++s) {
    send(rx, sink, s);
  }
  EXPECT_EQ(sink.seq, range(43, 100));
  EXPECT_EQ(rx.stats().samples, 58U);
  EXPECT_EQ(rx.stats().missing, 0U);
}

TEST(Receiver, ClassicSamplesAreReassembled) {
  Rx rx;
  Sink sink;
  for (std::uint32_t s = 0; s < 40; ++s) {
    send(rx, sink, s, Layout::kClassic);
  }
  EXPECT_EQ(sink.seq, range(0, 40));
  EXPECT_EQ(rx.stats().frames, 240U);
  EXPECT_EQ(rx.stats().truncated, 0U);
}

TEST(Receiver, WrongMtuAndDlcAreCountedAndDropped) {
  Rx rx;
  Sink sink;
  EncodedFrames out{};
  imu::hal::encode(sample(1), Layout::kFd, out);
  CanFrame f = out.frame[0];
  EXPECT_EQ(rx.push(f, 20, 0), FrameVerdict::kBadMtu);
  EXPECT_EQ(rx.push(f, 16, 0), FrameVerdict::kBadDlc);  // len 48 in a classic-sized frame
  f.len = 32;
  EXPECT_EQ(rx.push(f, 72, 0), FrameVerdict::kBadDlc);  // valid FD length, wrong for a sample
  f.len = 13;
  EXPECT_EQ(rx.push(f, 72, 0), FrameVerdict::kBadDlc);  // not a CAN FD length
  imu::hal::encode(sample(1), Layout::kClassic, out);
  CanFrame c = out.frame[0];
  c.len = 7;
  EXPECT_EQ(rx.push(c, 16, 0), FrameVerdict::kBadDlc);
  std::uint8_t big[100] = {};
  EXPECT_EQ(rx.push_bytes(big, sizeof big, 0), FrameVerdict::kBadMtu);
  EXPECT_EQ(rx.stats().bad_mtu, 2U);
  EXPECT_EQ(rx.stats().bad_dlc, 4U);
  EXPECT_EQ(rx.stats().frames, 6U);
  sink.drain(rx);
  EXPECT_TRUE(sink.seq.empty());
}

TEST(Receiver, UnknownRemoteAndErrorFramesAreCountedByClass) {
  Rx rx;
  CanFrame f{};
  f.can_id = 0x123;
  f.len = 8;
  EXPECT_EQ(rx.push(f, 16, 0), FrameVerdict::kUnknownId);
  f.can_id = 0x100U | imu::hal::kCanEffFlag;  // extended 0x100 is not the sample identifier
  EXPECT_EQ(rx.push(f, 16, 0), FrameVerdict::kUnknownId);
  f.can_id = 0x100U | imu::hal::kCanRtrFlag;
  EXPECT_EQ(rx.push(f, 16, 0), FrameVerdict::kRemoteFrame);
  // CAN_ERR_FLAG | CAN_ERR_CRTL (0x4) | CAN_ERR_BUSOFF (0x40), then CAN_ERR_BUSERROR (0x80).
  f.can_id = imu::hal::kCanErrFlag | 0x04U | 0x40U;
  EXPECT_EQ(rx.push(f, 16, 0), FrameVerdict::kErrorFrame);
  f.can_id = imu::hal::kCanErrFlag | 0x80U;
  EXPECT_EQ(rx.push(f, 16, 0), FrameVerdict::kErrorFrame);
  const auto& st = rx.stats();
  EXPECT_EQ(st.unknown_id, 2U);
  EXPECT_EQ(st.remote_frames, 1U);
  EXPECT_EQ(st.error_frames, 2U);
  EXPECT_EQ(st.err_class[2], 1U);
  EXPECT_EQ(st.err_class[6], 1U);
  EXPECT_EQ(st.err_class[7], 1U);
  EXPECT_EQ(st.err_class[0], 0U);
}

TEST(Receiver, BadCrcIsCountedAndBecomesAMissingSample) {
  Rx rx;
  Sink sink;
  for (std::uint32_t s = 0; s < 5; ++s) {
    send(rx, sink, s);
  }
  EncodedFrames out{};
  imu::hal::encode(sample(5), Layout::kFd, out);
  out.frame[0].data[20] ^= 0x10;  // one bit flipped in a count
  EXPECT_EQ(push_frame(rx, sink, out.frame[0]), FrameVerdict::kCrcError);
  for (std::uint32_t s = 6; s < 20; ++s) {
    send(rx, sink, s);
  }
  std::vector<std::int64_t> want = range(0, 5);
  want.push_back(-1);
  for (std::int64_t s = 6; s < 20; ++s) {
    want.push_back(s);
  }
  EXPECT_EQ(sink.seq, want);
  EXPECT_EQ(rx.stats().crc_errors, 1U);
  EXPECT_EQ(rx.stats().missing, 1U);
  EXPECT_EQ(rx.stats().gaps, 1U);
}

TEST(Receiver, GapBecomesOneMissingRunInItsPlace) {
  Rx rx;
  Sink sink;
  for (std::uint32_t s = 0; s < 10; ++s) {
    send(rx, sink, s);
  }
  for (std::uint32_t s = 13; s < 30; ++s) {
    send(rx, sink, s);
  }
  std::vector<std::int64_t> want = range(0, 10);
  want.push_back(-3);
  for (std::int64_t s = 13; s < 30; ++s) {
    want.push_back(s);
  }
  EXPECT_EQ(sink.seq, want);
  EXPECT_EQ(rx.stats().missing, 3U);
  EXPECT_EQ(rx.stats().gaps, 1U);
}

TEST(Receiver, LongGapIsCountedWithoutIteratingOverIt) {
  Rx rx;
  Sink sink;
  send(rx, sink, 0);
  send(rx, sink, 1'000'001);  // 1e6 missing: far beyond the window
  flush(rx, sink);            // the last W-1 holes could still be filled until the flush
  EXPECT_EQ(sink.seq, (std::vector<std::int64_t>{0, -1'000'000, 1'000'001}));
  EXPECT_EQ(rx.stats().missing, 1'000'000U);
  EXPECT_EQ(rx.stats().gaps, 1U);
}

TEST(Receiver, DuplicatesAreDroppedAndCounted) {
  Rx rx;
  Sink sink;
  for (std::uint32_t s = 0; s < 6; ++s) {
    send(rx, sink, s);
  }
  send(rx, sink, 3);  // already delivered
  send(rx, sink, 8);  // held (7 and 6 missing so far)
  send(rx, sink, 8);  // duplicate of a held sample
  send(rx, sink, 6);
  send(rx, sink, 7);
  EXPECT_EQ(sink.seq, range(0, 9));
  EXPECT_EQ(rx.stats().duplicates, 2U);
  EXPECT_EQ(rx.stats().missing, 0U);
}

TEST(Receiver, ReorderingWithinTheWindowIsRepaired) {
  Rx rx;
  Sink sink;
  const std::uint32_t order[] = {0, 1, 3, 2, 4, 9, 5, 6, 8, 7, 10, 11};
  for (const std::uint32_t s : order) {
    send(rx, sink, s);
  }
  EXPECT_EQ(sink.seq, range(0, 12));
  EXPECT_EQ(rx.stats().reordered, 5U);  // 2 (after 3); 5, 6, 8, 7 (after 9)
  EXPECT_EQ(rx.stats().missing, 0U);
  EXPECT_EQ(rx.held(), 0U);
}

TEST(Receiver, SampleLaterThanTheWindowIsLateNotInserted) {
  Rx rx;
  Sink sink;
  send(rx, sink, 0);
  for (std::uint32_t s = 2; s < 10; ++s) {  // 9 - 1 >= W: sample 1 is declared missing
    send(rx, sink, s);
  }
  send(rx, sink, 1);
  std::vector<std::int64_t> want{0, -1};
  for (std::int64_t s = 2; s < 10; ++s) {
    want.push_back(s);
  }
  EXPECT_EQ(sink.seq, want);
  EXPECT_EQ(rx.stats().late, 1U);
  EXPECT_EQ(rx.stats().duplicates, 0U);
}

TEST(Receiver, TruncatedClassicSampleIsCountedWhenTheNextCounterStarts) {
  Rx rx;
  Sink sink;
  send(rx, sink, 0, Layout::kClassic);
  EncodedFrames out{};
  imu::hal::encode(sample(1), Layout::kClassic, out);
  for (std::size_t i = 0; i < 3; ++i) {  // 3 of 6 fragments, then the sender resets
    EXPECT_EQ(push_frame(rx, sink, out.frame[i]), FrameVerdict::kFragment);
  }
  for (std::uint32_t s = 2; s < 12; ++s) {
    send(rx, sink, s, Layout::kClassic);
  }
  EXPECT_EQ(rx.stats().truncated, 1U);
  std::vector<std::int64_t> want{0, -1};
  for (std::int64_t s = 2; s < 12; ++s) {
    want.push_back(s);
  }
  EXPECT_EQ(sink.seq, want);
}

TEST(Receiver, OrphanAndOutOfRangeFragmentsAreCounted) {
  Rx rx;
  Sink sink;
  EncodedFrames out{};
  imu::hal::encode(sample(4), Layout::kClassic, out);
  EXPECT_EQ(push_frame(rx, sink, out.frame[2]), FrameVerdict::kOrphanFragment);
  EXPECT_EQ(push_frame(rx, sink, out.frame[0]), FrameVerdict::kFragment);
  EXPECT_EQ(push_frame(rx, sink, out.frame[2]), FrameVerdict::kOrphanFragment);  // 1 skipped
  CanFrame bad = out.frame[0];
  bad.data[0] = 0x4F;  // fragment 15 of a 6-fragment record
  EXPECT_EQ(push_frame(rx, sink, bad), FrameVerdict::kBadFragment);
  EXPECT_EQ(rx.stats().orphan_fragments, 2U);
  EXPECT_EQ(rx.stats().truncated, 1U);
  EXPECT_EQ(rx.stats().bad_fragment, 1U);
  // A fragment of another transfer (counter 5) in the middle of transfer 4 breaks it.
  EncodedFrames other{};
  imu::hal::encode(sample(5), Layout::kClassic, other);
  EXPECT_EQ(push_frame(rx, sink, out.frame[0]), FrameVerdict::kFragment);
  EXPECT_EQ(push_frame(rx, sink, other.frame[1]), FrameVerdict::kOrphanFragment);
  EXPECT_EQ(rx.stats().truncated, 2U);
  EXPECT_TRUE(sink.seq.empty());
}

TEST(Receiver, SenderRestartResynchronisesWithOneBreakMark) {
  Rx rx;
  Sink sink;
  for (std::uint32_t s = 1000; s < 1100; ++s) {
    send(rx, sink, s);
  }
  for (std::uint32_t s = 0; s < 5; ++s) {
    send(rx, sink, s);
  }
  std::vector<std::int64_t> want = range(1000, 1100);
  want.push_back(-1);
  for (std::int64_t s = 0; s < 5; ++s) {
    want.push_back(s);
  }
  EXPECT_EQ(sink.seq, want);
  EXPECT_EQ(rx.stats().resyncs, 1U);
  EXPECT_EQ(sink.resync_marks, 1U);
}

TEST(Receiver, SequenceWrapsAroundTwoToThe32) {
  Rx rx;
  Sink sink;
  std::vector<std::int64_t> want;
  for (std::uint32_t i = 0; i < 20; ++i) {
    const std::uint32_t s = 0xFFFFFFF6U + i;  // wraps after 10 samples
    if (i != 12) {
      send(rx, sink, s);
    }
  }
  flush(rx, sink);
  EXPECT_EQ(sink.seq.size(), 20U);
  EXPECT_EQ(sink.seq[12], -1);
  EXPECT_EQ(sink.seq[13], 3);
  EXPECT_EQ(rx.stats().missing, 1U);
  EXPECT_EQ(rx.stats().resyncs, 0U);
}

TEST(Receiver, FlushReleasesHeldSamplesAndCountsPartialTransfers) {
  Rx rx;
  Sink sink;
  send(rx, sink, 0);
  send(rx, sink, 3);
  send(rx, sink, 4);
  EXPECT_EQ(rx.held(), 2U);
  EncodedFrames out{};
  imu::hal::encode(sample(5), Layout::kClassic, out);
  (void)push_frame(rx, sink, out.frame[0]);
  flush(rx, sink);
  EXPECT_EQ(sink.seq, (std::vector<std::int64_t>{0, -2, 3, 4}));
  EXPECT_EQ(rx.stats().truncated, 1U);
  EXPECT_EQ(rx.held(), 0U);
}

TEST(Receiver, FullEventQueueRefusesFramesWithoutLosingThem) {
  Rx rx;
  EncodedFrames out{};
  std::uint32_t seq = 0;
  std::size_t accepted = 0;
  FrameVerdict v = FrameVerdict::kRecord;
  while (v != FrameVerdict::kBusy) {
    imu::hal::encode(sample(seq), Layout::kFd, out);
    v = rx.push(out.frame[0], 72, 0);
    if (v != FrameVerdict::kBusy) {
      ++seq;
      ++accepted;
    }
  }
  EXPECT_EQ(rx.stats().busy, 1U);
  EXPECT_EQ(accepted, Rx::kQueue - Rx::kMaxEventsPerPush + 1);
  Sink sink;
  sink.drain(rx);
  EXPECT_EQ(push_frame(rx, sink, out.frame[0]), FrameVerdict::kRecord);  // the refused one
  EXPECT_EQ(sink.seq, range(0, static_cast<std::int64_t>(seq) + 1));
}

// A CRC-valid Config record whose channel count byte is not 6 (a forged or foreign record):
// its LSB list would not mean what it says. Refused and counted, no Config event
// (every parameter of a config checked); the count 6 still passes.
TEST(Receiver, ConfigWithAnotherChannelCountIsRefused) {
  imu::hal::ConfigRecord c{};
  c.cfg_id = 3;
  c.rate_hz = 100.0;
  for (double& l : c.lsb) {
    l = 1e-3;
  }
  for (const std::uint8_t n_ch : {std::uint8_t{5}, std::uint8_t{6}}) {
    CanFrame f{};
    f.can_id = imu::hal::kIdConfigFd;
    f.len = 64;
    f.flags = imu::hal::kCanFdFdf | imu::hal::kCanFdBrs;
    imu::hal::serialize(c, f.data);
    f.data[1] = n_ch;  // the channel count, then a valid CRC over the forged bytes
    const std::uint32_t crc = imu::hal::crc32c(f.data, imu::hal::kConfigLen - 4);
    for (std::size_t i = 0; i < 4; ++i) {
      f.data[imu::hal::kConfigLen - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
    }
    Rx rx;
    std::size_t configs = 0;
    const FrameVerdict v = rx.push_drain(f, imu::hal::kCanFdMtu, 0, [&](const RxEvent& e) {
      configs += e.type == RxEvent::Type::kConfig ? 1U : 0U;
    });
    if (n_ch == 6) {
      EXPECT_EQ(v, FrameVerdict::kRecord);
      EXPECT_EQ(configs, 1U);
      EXPECT_EQ(rx.stats().bad_record, 0U);
    } else {
      EXPECT_EQ(v, FrameVerdict::kBadRecord);
      EXPECT_EQ(configs, 0U);
      EXPECT_EQ(rx.stats().bad_record, 1U);
      EXPECT_EQ(rx.stats().crc_errors, 0U);
      EXPECT_EQ(rx.stats().frames, 1U);
    }
  }
}

TEST(Receiver, TelemetryAndConfigAreDeliveredInBothLayouts) {
  for (const Layout layout : {Layout::kFd, Layout::kClassic}) {
    Rx rx;
    Sink sink;
    EncodedFrames out{};
    imu::hal::ConfigRecord c{};
    c.cfg_id = 2;
    c.rate_hz = 100.0;
    imu::hal::encode(c, layout, 1, out);
    for (std::size_t i = 0; i < out.count; ++i) {
      (void)push_frame(rx, sink, out.frame[i]);
    }
    imu::hal::BiasRecord b{};
    b.seq = 77;
    b.bias[4] = -0.5F;
    b.var[4] = 0.25F;
    b.flags = 1;
    imu::hal::encode(b, layout, 2, out);
    for (std::size_t i = 0; i < out.count; ++i) {
      (void)push_frame(rx, sink, out.frame[i]);
    }
    imu::hal::MonitorRecord m{};
    m.flags = 5;
    m.cusum_mask = 0x21;
    imu::hal::encode(m, layout, 3, out);
    for (std::size_t i = 0; i < out.count; ++i) {
      (void)push_frame(rx, sink, out.frame[i]);
    }
    imu::hal::AdevRecord a{};
    a.channel = 4;
    imu::hal::encode(a, layout, 4, out);
    for (std::size_t i = 0; i < out.count; ++i) {
      (void)push_frame(rx, sink, out.frame[i]);
    }
    imu::hal::encode(imu::hal::StatsRecord{}, layout, 5, out);
    for (std::size_t i = 0; i < out.count; ++i) {
      (void)push_frame(rx, sink, out.frame[i]);
    }
    ASSERT_EQ(sink.other.size(), 5U);
    EXPECT_EQ(sink.other[0].type, RxEvent::Type::kConfig);
    EXPECT_EQ(sink.other[0].rec.config.cfg_id, 2);
    EXPECT_EQ(sink.other[1].type, RxEvent::Type::kBias);
    EXPECT_EQ(sink.other[1].rec.bias.seq, 77U);
    EXPECT_EQ(sink.other[1].rec.bias.flags, 1);
    // Tolerance 4 ulp (EXPECT_FLOAT_EQ): the value is copied bit for bit, so it is exact.
    EXPECT_FLOAT_EQ(sink.other[1].rec.bias.bias[4], -0.5F);
    EXPECT_FLOAT_EQ(sink.other[1].rec.bias.var[4], 0.25F);
    EXPECT_EQ(sink.other[2].type, RxEvent::Type::kMonitor);
    EXPECT_EQ(sink.other[2].rec.monitor.flags, 5);
    EXPECT_EQ(sink.other[2].rec.monitor.cusum_mask, 0x21);
    EXPECT_EQ(sink.other[3].type, RxEvent::Type::kAdev);
    EXPECT_EQ(sink.other[3].rec.adev.channel, 4);
    EXPECT_EQ(sink.other[4].type, RxEvent::Type::kStats);
    imu::hal::ConfigRecord got{};
    ASSERT_TRUE(rx.config(got));
    EXPECT_EQ(got.cfg_id, 2);
    send(rx, sink, 0, layout);  // cfg_id 0 != 2
    EXPECT_EQ(rx.stats().cfg_mismatch, 1U);
  }
}

}  // namespace

// libFuzzer target for the frame decoder and the receiver (reassembly, reorder window, gaps).
// Two modes, chosen by the first input byte:
//  * raw: the input is a sequence of [nbytes][nbytes bytes] frames pushed with push_bytes();
//  * structured: 3-byte operations build CRC-valid records (samples at relative sequence
//    numbers, both layouts, truncated transfers, bit flips, telemetry, error frames, flushes),
//    which random bytes would almost never produce, so the deep paths get exercised.
// Invariants checked (trap on violation): released samples have strictly increasing sequence
// numbers between resyncs; Missing runs are not empty; every frame is counted exactly once.
#include <cstddef>
#include <cstdint>

#include "imu/hal/receiver.hpp"

namespace {

using imu::hal::EncodedFrames;
using imu::hal::FrameVerdict;
using imu::hal::Layout;
using imu::hal::RxEvent;
using Rx = imu::hal::Receiver<8>;

struct Checker {
  bool have_last = false;
  std::uint32_t last_seq = 0;
  std::uint64_t resyncs = 0;
  std::uint64_t pushed = 0;

  void drain(Rx& rx) {
    RxEvent e{};
    while (rx.pop(e)) {
      if (e.type == RxEvent::Type::kMissing && e.resync) {
        ++resyncs;
        have_last = false;  // the sender restarted: a new sequence begins
        continue;
      }
      if (e.type == RxEvent::Type::kSample) {
        if (have_last && static_cast<std::int32_t>(e.rec.sample.seq - last_seq) <= 0) {
          __builtin_trap();
        }
        have_last = true;
        last_seq = e.rec.sample.seq;
      } else if (e.type == RxEvent::Type::kMissing) {
        if (e.missing_count == 0) {
          __builtin_trap();
        }
        have_last = true;
        last_seq = e.missing_first_seq + e.missing_count - 1;
      }
    }
  }

  void push(Rx& rx, const imu::hal::CanFrame& f) {
    if (rx.push(f, imu::hal::wire_size(f), 0) != FrameVerdict::kBusy) {
      ++pushed;
    }
    drain(rx);
  }
};

void run_raw(const std::uint8_t* data, std::size_t size) {
  Rx rx;
  Checker chk;
  std::size_t i = 0;
  while (i < size) {
    const std::size_t n = data[i++] % 80U;
    const std::size_t take = n <= size - i ? n : size - i;
    if (rx.push_bytes(data + i, take, 0) != FrameVerdict::kBusy) {
      ++chk.pushed;
    }
    chk.drain(rx);
    i += take;
  }
  if (rx.flush()) {
    chk.drain(rx);
  }
  if (rx.stats().frames != chk.pushed || rx.stats().resyncs != chk.resyncs) {
    __builtin_trap();
  }
}

void run_structured(const std::uint8_t* data, std::size_t size) {
  Rx rx;
  Checker chk;
  EncodedFrames out{};
  std::uint32_t cursor = 1000;
  for (std::size_t i = 0; i + 3 <= size; i += 3) {
    const std::uint8_t op = data[i];
    const std::uint8_t a = data[i + 1];
    const std::uint8_t b = data[i + 2];
    const Layout layout = (b & 1U) != 0 ? Layout::kClassic : Layout::kFd;
    imu::hal::SampleRecord s{};
    s.seq = cursor + static_cast<std::uint32_t>(static_cast<std::int8_t>(a));
    s.counts[0] = static_cast<std::int32_t>(a) * 1000 - static_cast<std::int32_t>(b);
    switch (op % 8U) {
      case 0:  // a whole sample near the cursor; the cursor moves on
        imu::hal::encode(s, layout, out);
        for (std::size_t k = 0; k < out.count; ++k) {
          chk.push(rx, out.frame[k]);
        }
        ++cursor;
        break;
      case 1:  // a truncated transfer
        imu::hal::encode(s, layout, out);
        for (std::size_t k = 0; k < out.count && k < static_cast<std::size_t>(b >> 1); ++k) {
          chk.push(rx, out.frame[k]);
        }
        break;
      case 2: {  // a bit flip somewhere in one frame
        imu::hal::encode(s, layout, out);
        const std::size_t k = static_cast<std::size_t>(b) % out.count;
        out.frame[k].data[static_cast<std::size_t>(a) % 64U] ^=
            static_cast<std::uint8_t>(1U << (b % 8U));
        for (std::size_t j = 0; j < out.count; ++j) {
          chk.push(rx, out.frame[j]);
        }
        ++cursor;
        break;
      }
      case 3: {  // telemetry and configuration
        imu::hal::ChannelMonitorRecord cm{};
        cm.channel = static_cast<std::uint8_t>(b % 8U);  // 6 and 7: refused (bad_record)
        imu::hal::ModelRecord mr{};
        mr.version = static_cast<std::uint8_t>(a % 4U);  // 1, 2: layouts; 0, 3: refused
        mr.channel = static_cast<std::uint8_t>(b % 8U);
        mr.osc_sigma = static_cast<float>(a);
        imu::hal::ModelSignalsRecord ms{};
        ms.channel = static_cast<std::uint8_t>(b % 8U);  // 6 and 7: refused (bad_record)
        ms.ramp_r = -static_cast<float>(a);
        switch (a % 10U) {
          case 0: imu::hal::encode(imu::hal::ConfigRecord{}, layout, b, out); break;
          case 1: imu::hal::encode(imu::hal::AdevRecord{}, layout, b, out); break;
          case 2: imu::hal::encode(imu::hal::BiasRecord{}, layout, b, out); break;
          case 3: imu::hal::encode(imu::hal::MonitorRecord{}, layout, b, out); break;
          case 4: imu::hal::encode(cm, layout, b, out); break;
          case 5: imu::hal::encode(mr, false, layout, b, out); break;  // push
          case 6: imu::hal::encode(mr, true, layout, b, out); break;   // echo
          case 7: imu::hal::encode(ms, false, layout, b, out); break;  // signals push
          case 8: imu::hal::encode(ms, true, layout, b, out); break;   // signals echo
          default: imu::hal::encode(imu::hal::StatsRecord{}, layout, b, out); break;
        }
        for (std::size_t k = 0; k < out.count; ++k) {
          chk.push(rx, out.frame[k]);
        }
        break;
      }
      case 4:  // a jump of the sender's counter (gap, or restart when large and backwards)
        cursor += static_cast<std::uint32_t>(a) * static_cast<std::uint32_t>(b) *
                  ((op & 0x80U) != 0 ? 0xFFFFFFFFU : 1U);
        break;
      case 5: {  // an arbitrary frame header with the sample's bytes
        imu::hal::encode(s, Layout::kFd, out);
        out.frame[0].can_id = (static_cast<std::uint32_t>(a) << 3) | (b & 7U) |
                              (static_cast<std::uint32_t>(op & 0xE0U) << 24);
        out.frame[0].len = static_cast<std::uint8_t>(b % 72U);
        const std::size_t nbytes = (op & 0x10U) != 0 ? 16U : 72U;
        if (rx.push(out.frame[0], nbytes, 0) != FrameVerdict::kBusy) {
          ++chk.pushed;
        }
        chk.drain(rx);
        break;
      }
      case 6:
        if (rx.flush()) {
          chk.drain(rx);
        }
        break;
      default: {  // an error frame with arbitrary class bits
        imu::hal::CanFrame f{};
        f.can_id = imu::hal::kCanErrFlag | a | (static_cast<std::uint32_t>(b) << 8);
        f.len = 8;
        chk.push(rx, f);
        break;
      }
    }
  }
  if (rx.flush()) {
    chk.drain(rx);
  }
  if (rx.stats().frames != chk.pushed || rx.stats().resyncs != chk.resyncs) {
    __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) {
    return 0;
  }
  if ((data[0] & 1U) != 0) {
    run_structured(data + 1, size - 1);
  } else {
    run_raw(data + 1, size - 1);
  }
  return 0;
}

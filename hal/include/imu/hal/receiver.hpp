// Receiver: turns raw frames into an ordered stream of samples, "missing" marks and telemetry.
//
// Frames are pushed in (push); events are read out (pop). Per frame it checks the MTU and DLC,
// classifies the identifier (protocol record, error frame, remote frame, unknown), reassembles
// classic-CAN fragments, checks the CRC-32C, and sends samples through a reorder window of W
// samples: samples are released in sequence order; a duplicate is dropped; a hole that is still
// open when a sample W or more ahead arrives becomes a Missing event (count of samples), which
// the consumer hands to OnlineAdev::mark_missing(). A hole expires one sample at a time as
// later samples arrive, so one run of n missing samples may come as several consecutive
// Missing events whose counts add up to n (stats.gaps counts it once). Every outcome is
// counted in RxStats.
//
// Platform-free, no heap, no exceptions; sizeof(Receiver<W>) is the whole state. Not
// re-entrant on one instance. Cost: push() is O(frame bytes + W); pop() is O(1).
#ifndef IMU_HAL_RECEIVER_HPP
#define IMU_HAL_RECEIVER_HPP

#include <cstddef>
#include <cstdint>

#include "imu/hal/codec.hpp"

namespace imu::hal {

/// Every frame outcome and every sequence event, counted. Counters never wrap in practice
/// (uint64). `records` counts CRC-valid records per RecordKind.
struct RxStats {
  std::uint64_t frames = 0;            ///< push() calls that consumed a frame
  std::uint64_t bad_mtu = 0;           ///< nbytes neither CAN_MTU (16) nor CANFD_MTU (72)
  std::uint64_t bad_dlc = 0;           ///< len invalid for the MTU, or wrong for the identifier
  std::uint64_t unknown_id = 0;        ///< identifier (standard or extended) not in the protocol
  std::uint64_t remote_frames = 0;     ///< RTR frames (never used by the protocol)
  std::uint64_t error_frames = 0;      ///< CAN_ERR_FLAG frames
  std::uint64_t err_class[kErrClasses] = {};  ///< error frames per class bit (see codec.hpp)
  std::uint64_t crc_errors = 0;
  std::uint64_t bad_fragment = 0;      ///< classic fragment index beyond the record length
  std::uint64_t truncated = 0;         ///< classic transfer abandoned before its last fragment
  std::uint64_t orphan_fragments = 0;  ///< classic fragment whose transfer start was not seen
  std::uint64_t bad_record = 0;        ///< CRC-valid record this version refuses: a Config
                                       ///< record whose channel count is not kChannels, a
                                       ///< Model record whose version byte is not its kind's
                                       ///< or whose channel is not below kChannels, a
                                       ///< ChannelMonitor or ModelSignals record's channel
                                       ///< likewise
  std::uint64_t records[kRecordKinds] = {};
  std::uint64_t samples = 0;           ///< samples released (Sample events)
  std::uint64_t duplicates = 0;        ///< sample with a sequence number already received
  std::uint64_t late = 0;              ///< sample arriving after its slot was reported missing
  std::uint64_t reordered = 0;         ///< sample arriving after a later one, put back in order
  std::uint64_t missing = 0;           ///< samples reported missing (sum of Missing counts)
  std::uint64_t gaps = 0;              ///< runs of consecutive missing samples
  std::uint64_t resyncs = 0;           ///< sequence jumped back more than 64: sender restarted
  std::uint64_t cfg_mismatch = 0;      ///< sample whose cfg_id differs from the last config
  std::uint64_t busy = 0;              ///< push() refused because events were not popped
};

/// What push() did with a frame.
enum class FrameVerdict : std::uint8_t {
  kRecord,          ///< completed a CRC-valid record (events may follow)
  kFragment,        ///< stored a classic fragment of a record in progress
  kBusy,            ///< not consumed: pop() the pending events, then push the frame again
  kBadMtu,
  kBadDlc,
  kUnknownId,
  kRemoteFrame,
  kErrorFrame,
  kCrcError,
  kBadRecord,       ///< CRC-valid but refused (RxStats::bad_record)
  kBadFragment,
  kOrphanFragment,
};

/// One output event. `rec` holds the member named by `type` (kMissing uses no member).
struct RxEvent {
  enum class Type : std::uint8_t {
    kSample, kMissing, kConfig, kAdev, kBias, kMonitor, kStats, kRejects, kModel, kModelEcho,
    kChannelMonitor, kModelSignals, kModelSignalsEcho
  };
  Type type;
  std::uint64_t rx_time_ns;           ///< receive time of the frame that completed the record
  std::uint32_t missing_first_seq;    ///< kMissing: first missing sequence number
  std::uint32_t missing_count;        ///< kMissing: number of consecutive missing samples
  bool resync;                        ///< kMissing: break mark of a sender restart (count 1);
                                      ///< the next sample starts a new sequence
  union Rec {
    SampleRecord sample;
    ConfigRecord config;
    AdevRecord adev;
    BiasRecord bias;
    MonitorRecord monitor;
    StatsRecord stats;
    RejectsRecord rejects;
    ModelRecord model;                ///< kModel and kModelEcho, record version 1 or 2
    ChannelMonitorRecord channel_monitor;
    ModelSignalsRecord signals;       ///< kModelSignals and kModelSignalsEcho
  } rec;
};

/// W: reorder window in samples (1..32). A gap is reported once W later samples have arrived
/// (or at flush()); a sample up to W-1 positions early is put back in order.
template <std::size_t W = 8>
class Receiver {
  static_assert(W >= 1 && W <= 32, "reorder window must be 1..32 samples");

 public:
  static constexpr std::size_t kWindow = W;
  /// Worst case events from one push() or flush(): W held samples, W+1 missing runs, 1 more.
  static constexpr std::size_t kMaxEventsPerPush = 2 * W + 2;
  static constexpr std::size_t kQueue = 2 * kMaxEventsPerPush;
  /// A sample more than this many behind the next expected one means the sender restarted.
  static constexpr std::uint32_t kResyncBehind = 64;

  Receiver() { reset(); }

  /// Forget everything, including statistics. O(W).
  void reset();

  /// Push one frame: `nbytes` is what the transport delivered (CAN_MTU or CANFD_MTU when well
  /// formed); rx_time_ns is the receive timestamp passed through to events. Returns kBusy
  /// (frame not consumed, counted in stats.busy) when fewer than kMaxEventsPerPush event
  /// slots are free. O(len + W).
  [[nodiscard]] FrameVerdict push(const CanFrame& f, std::size_t nbytes, std::uint64_t rx_time_ns);

  /// Same as push() for raw bytes (at most 72 are read; a longer nbytes is counted bad_mtu).
  [[nodiscard]] FrameVerdict push_bytes(const std::uint8_t* bytes, std::size_t nbytes,
                                        std::uint64_t rx_time_ns);

  /// Take the oldest event; false if there is none. O(1).
  [[nodiscard]] bool pop(RxEvent& out);

  /// End of stream or idle timeout: release every held sample; holes before the last held
  /// sample become Missing; incomplete classic transfers are counted truncated. Returns false
  /// (nothing done) if the event queue lacks room: pop() first. O(W).
  [[nodiscard]] bool flush();

  /// push() one frame and hand every event it releases to on_event(const RxEvent&). On kBusy
  /// (events were left in the queue) they are handed out first and the frame goes in then.
  /// Returns the frame's verdict. The one pump every consumer uses (node, imu-sim, RxPump).
  template <class OnEvent>
  FrameVerdict push_drain(const CanFrame& f, std::size_t nbytes, std::uint64_t rx_time_ns,
                          OnEvent&& on_event) {
    FrameVerdict v = push(f, nbytes, rx_time_ns);
    while (v == FrameVerdict::kBusy) {
      drain(on_event);
      v = push(f, nbytes, rx_time_ns);
    }
    drain(on_event);
    return v;
  }

  /// flush() and hand out what it releases (events left in the queue go first). Returns
  /// flush()'s result.
  template <class OnEvent>
  bool flush_drain(OnEvent&& on_event) {
    drain(on_event);
    const bool flushed = flush();
    drain(on_event);
    return flushed;
  }

  /// Hand every queued event to on_event, oldest first.
  template <class OnEvent>
  void drain(OnEvent&& on_event) {
    RxEvent e{};
    while (pop(e)) {
      on_event(e);
    }
  }

  /// Samples held in the reorder window waiting for an earlier one.
  [[nodiscard]] std::size_t held() const;
  [[nodiscard]] std::size_t events_pending() const { return q_count_; }
  [[nodiscard]] const RxStats& stats() const { return stats_; }
  /// The config its consumer runs, after the consumer refused a newer one (out of range): the
  /// samples that follow are checked against it, not against the refused record (whose id
  /// would count every valid sample as cfg_mismatch). have = false: no config yet.
  void use_config(const ConfigRecord& c, bool have) {
    cfg_ = c;
    have_cfg_ = have;
  }
  /// The last configuration received; false if none yet.
  [[nodiscard]] bool config(ConfigRecord& out) const {
    out = cfg_;
    return have_cfg_;
  }

 private:
  struct Slot {
    bool valid;
    std::uint64_t rx_time_ns;
    SampleRecord s;
  };
  struct Partial {
    bool active;
    std::uint8_t transfer_id;
    std::uint8_t next_frag;
    std::uint8_t buf[kMaxFragments * kClassicPayload];
  };

  [[nodiscard]] std::size_t queue_free() const { return kQueue - q_count_; }
  RxEvent& enqueue(RxEvent::Type t, std::uint64_t rx_time_ns);
  FrameVerdict on_record(RecordKind k, const std::uint8_t* buf, std::uint64_t rx_time_ns);
  FrameVerdict on_classic(RecordKind k, const CanFrame& f, std::uint64_t rx_time_ns);
  void on_sample(const SampleRecord& s, std::uint64_t rx_time_ns);
  void deliver(const Slot& slot);
  void emit_missing(std::uint32_t first_seq, std::uint32_t n);
  void advance_to(std::uint32_t new_next);
  void release_held();

  RxStats stats_;
  RxEvent q_[kQueue];
  std::size_t q_head_;
  std::size_t q_count_;
  Slot slots_[W];
  bool started_;
  std::uint32_t next_;       // next sequence number to release
  std::uint32_t max_seen_;   // highest sequence number received (modulo 2^32)
  std::uint64_t history_;    // bit i: sample next_-1-i was delivered (not reported missing)
  bool have_missing_;
  std::uint32_t missing_end_;  // sequence number after the last one reported missing
  Partial partial_[kRecordKinds];
  bool have_cfg_;
  ConfigRecord cfg_;
};

extern template class Receiver<8>;

// ---- implementation ------------------------------------------------------------------------

template <std::size_t W>
void Receiver<W>::reset() {
  stats_ = RxStats{};
  q_head_ = 0;
  q_count_ = 0;
  for (auto& s : slots_) {
    s.valid = false;
  }
  started_ = false;
  next_ = 0;
  max_seen_ = 0;
  history_ = 0;
  have_missing_ = false;
  missing_end_ = 0;
  for (auto& p : partial_) {
    p.active = false;
  }
  have_cfg_ = false;
  cfg_ = ConfigRecord{};
}

template <std::size_t W>
FrameVerdict Receiver<W>::push_bytes(const std::uint8_t* bytes, std::size_t nbytes,
                                     std::uint64_t rx_time_ns) {
  // At most one frame image is read; push() counts any size but 16 or 72 as bad_mtu.
  CanFrame f{};
  auto* dst = reinterpret_cast<std::uint8_t*>(&f);  // NOLINT: CanFrame is the raw frame image
  for (std::size_t i = 0; i < nbytes && i < kCanFdMtu; ++i) {
    dst[i] = bytes[i];
  }
  return push(f, nbytes, rx_time_ns);
}

template <std::size_t W>
FrameVerdict Receiver<W>::push(const CanFrame& f, std::size_t nbytes, std::uint64_t rx_time_ns) {
  if (queue_free() < kMaxEventsPerPush) {
    ++stats_.busy;
    return FrameVerdict::kBusy;
  }
  ++stats_.frames;
  if (nbytes != kCanMtu && nbytes != kCanFdMtu) {
    ++stats_.bad_mtu;
    return FrameVerdict::kBadMtu;
  }
  const bool fd = nbytes == kCanFdMtu;
  if ((!fd && f.len > 8) || (fd && (f.len > 64 || fd_len_for(f.len) != f.len))) {
    ++stats_.bad_dlc;
    return FrameVerdict::kBadDlc;
  }
  if ((f.can_id & kCanErrFlag) != 0) {
    ++stats_.error_frames;
    for (std::size_t i = 0; i < kErrClasses; ++i) {
      if ((f.can_id & (1U << i)) != 0) {
        ++stats_.err_class[i];
      }
    }
    return FrameVerdict::kErrorFrame;
  }
  if ((f.can_id & kCanRtrFlag) != 0) {
    ++stats_.remote_frames;
    return FrameVerdict::kRemoteFrame;
  }
  RecordKind kind{};
  Layout layout{};
  if (!kind_of_id(f.can_id, kind, layout)) {
    ++stats_.unknown_id;
    return FrameVerdict::kUnknownId;
  }
  if (layout == Layout::kClassic) {
    if (f.len != 8) {
      ++stats_.bad_dlc;
      return FrameVerdict::kBadDlc;
    }
    return on_classic(kind, f, rx_time_ns);
  }
  if (!fd || f.len != fd_len_for(record_len(kind))) {
    ++stats_.bad_dlc;
    return FrameVerdict::kBadDlc;
  }
  return on_record(kind, f.data, rx_time_ns);
}

template <std::size_t W>
FrameVerdict Receiver<W>::on_classic(RecordKind k, const CanFrame& f, std::uint64_t rx_time_ns) {
  const std::size_t len = record_len(k);
  const std::size_t n_frags = (len + kClassicPayload - 1) / kClassicPayload;
  const auto tid = static_cast<std::uint8_t>(f.data[0] >> 4);
  const auto frag = static_cast<std::uint8_t>(f.data[0] & 0x0FU);
  Partial& p = partial_[static_cast<std::size_t>(k)];
  if (frag >= n_frags) {
    ++stats_.bad_fragment;
    return FrameVerdict::kBadFragment;
  }
  if (frag == 0) {
    if (p.active) {
      ++stats_.truncated;  // the previous transfer never completed
    }
    p.active = true;
    p.transfer_id = tid;
    p.next_frag = 0;
  } else if (!p.active) {
    ++stats_.orphan_fragments;
    return FrameVerdict::kOrphanFragment;
  } else if (tid != p.transfer_id || frag != p.next_frag) {
    ++stats_.truncated;
    ++stats_.orphan_fragments;
    p.active = false;
    return FrameVerdict::kOrphanFragment;
  }
  for (std::size_t i = 0; i < kClassicPayload; ++i) {
    p.buf[static_cast<std::size_t>(frag) * kClassicPayload + i] = f.data[1 + i];
  }
  p.next_frag = static_cast<std::uint8_t>(frag + 1);
  if (p.next_frag < n_frags) {
    return FrameVerdict::kFragment;
  }
  p.active = false;
  return on_record(k, p.buf, rx_time_ns);
}

template <std::size_t W>
RxEvent& Receiver<W>::enqueue(RxEvent::Type t, std::uint64_t rx_time_ns) {
  // Callers checked queue_free() >= kMaxEventsPerPush before producing events.
  RxEvent& e = q_[(q_head_ + q_count_) % kQueue];
  ++q_count_;
  e.type = t;
  e.rx_time_ns = rx_time_ns;
  e.missing_first_seq = 0;
  e.missing_count = 0;
  e.resync = false;
  return e;
}

template <std::size_t W>
FrameVerdict Receiver<W>::on_record(RecordKind k, const std::uint8_t* buf,
                                    std::uint64_t rx_time_ns) {
  if (!crc_ok(buf, record_len(k))) {
    ++stats_.crc_errors;
    return FrameVerdict::kCrcError;
  }
  if (k == RecordKind::kConfig && buf[1] != kChannels) {  // byte 1: the channel count
    ++stats_.bad_record;  // counts[] and lsb[] would not mean what they say
    return FrameVerdict::kBadRecord;
  }
  if (model_version(k) != 0 &&
      (buf[0] != model_version(k) || buf[1] >= kChannels)) {  // bytes 0, 1: version, channel
    ++stats_.bad_record;
    return FrameVerdict::kBadRecord;
  }
  if ((k == RecordKind::kChannelMonitor || k == RecordKind::kModelSignals ||
       k == RecordKind::kModelSignalsEcho) &&
      buf[0] >= kChannels) {  // byte 0: the channel
    ++stats_.bad_record;
    return FrameVerdict::kBadRecord;
  }
  ++stats_.records[static_cast<std::size_t>(k)];
  switch (k) {
    case RecordKind::kSample: {
      SampleRecord s{};
      parse(buf, s);
      on_sample(s, rx_time_ns);
      break;
    }
    case RecordKind::kConfig:
      parse(buf, cfg_);
      have_cfg_ = true;
      enqueue(RxEvent::Type::kConfig, rx_time_ns).rec.config = cfg_;
      break;
    case RecordKind::kAdev:
      parse(buf, enqueue(RxEvent::Type::kAdev, rx_time_ns).rec.adev);
      break;
    case RecordKind::kBias:
      parse(buf, enqueue(RxEvent::Type::kBias, rx_time_ns).rec.bias);
      break;
    case RecordKind::kMonitor:
      parse(buf, enqueue(RxEvent::Type::kMonitor, rx_time_ns).rec.monitor);
      break;
    case RecordKind::kStats:
      parse(buf, enqueue(RxEvent::Type::kStats, rx_time_ns).rec.stats);
      break;
    case RecordKind::kRejects:
      parse(buf, enqueue(RxEvent::Type::kRejects, rx_time_ns).rec.rejects);
      break;
    case RecordKind::kModel:
    case RecordKind::kModel2:  // both versions: one event, ModelRecord::version tells which
      parse(buf, enqueue(RxEvent::Type::kModel, rx_time_ns).rec.model);
      break;
    case RecordKind::kModelEcho:
    case RecordKind::kModelEcho2:
      parse(buf, enqueue(RxEvent::Type::kModelEcho, rx_time_ns).rec.model);
      break;
    case RecordKind::kChannelMonitor:
      parse(buf, enqueue(RxEvent::Type::kChannelMonitor, rx_time_ns).rec.channel_monitor);
      break;
    case RecordKind::kModelSignals:
      parse(buf, enqueue(RxEvent::Type::kModelSignals, rx_time_ns).rec.signals);
      break;
    case RecordKind::kModelSignalsEcho:
      parse(buf, enqueue(RxEvent::Type::kModelSignalsEcho, rx_time_ns).rec.signals);
      break;
  }
  return FrameVerdict::kRecord;
}

template <std::size_t W>
void Receiver<W>::deliver(const Slot& slot) {
  enqueue(RxEvent::Type::kSample, slot.rx_time_ns).rec.sample = slot.s;
  ++stats_.samples;
  history_ = (history_ << 1) | 1U;
}

template <std::size_t W>
void Receiver<W>::emit_missing(std::uint32_t first_seq, std::uint32_t n) {
  if (n == 0) {
    return;
  }
  stats_.missing += n;
  history_ = n >= 64 ? 0 : history_ << n;
  const bool continues = have_missing_ && first_seq == missing_end_;
  if (!continues) {
    ++stats_.gaps;
  }
  have_missing_ = true;
  missing_end_ = first_seq + n;
  if (continues && q_count_ > 0) {
    RxEvent& last = q_[(q_head_ + q_count_ - 1) % kQueue];
    if (last.type == RxEvent::Type::kMissing) {
      last.missing_count += n;  // extend the queued run
      return;
    }
  }
  RxEvent& e = enqueue(RxEvent::Type::kMissing, 0);
  e.missing_first_seq = first_seq;
  e.missing_count = n;
}

template <std::size_t W>
void Receiver<W>::advance_to(std::uint32_t new_next) {
  // Release or declare missing everything before new_next (new_next - next_ > 0).
  const std::uint32_t span = new_next - next_;
  const std::uint32_t in_window = span < W ? span : static_cast<std::uint32_t>(W);
  for (std::uint32_t i = 0; i < in_window; ++i) {
    const std::uint32_t seq = next_ + i;
    Slot& slot = slots_[seq % W];
    if (slot.valid) {
      deliver(slot);
      slot.valid = false;
    } else {
      emit_missing(seq, 1);
    }
  }
  if (span > in_window) {
    emit_missing(next_ + in_window, span - in_window);
  }
  next_ = new_next;
}

template <std::size_t W>
void Receiver<W>::release_held() {
  std::size_t last = W;  // offset of the last held sample, W if none
  for (std::size_t i = 0; i < W; ++i) {
    if (slots_[(next_ + i) % W].valid) {
      last = i;
    }
  }
  if (last < W) {
    advance_to(next_ + static_cast<std::uint32_t>(last) + 1U);
  }
}

template <std::size_t W>
void Receiver<W>::on_sample(const SampleRecord& s, std::uint64_t rx_time_ns) {
  if (have_cfg_ && s.cfg_id != cfg_.cfg_id) {
    ++stats_.cfg_mismatch;
  }
  if (!started_) {
    started_ = true;
    next_ = s.seq;
    max_seen_ = s.seq;
  }
  auto d = static_cast<std::int32_t>(s.seq - next_);
  if (d < 0) {
    const auto back = static_cast<std::uint32_t>(-static_cast<std::int64_t>(d));
    if (back <= kResyncBehind) {
      if (((history_ >> (back - 1)) & 1U) != 0) {
        ++stats_.duplicates;
      } else {
        ++stats_.late;
      }
      return;
    }
    // The sender restarted (or the stream was cut for a long time): release what is held and
    // mark one missing sample so the consumer breaks its phase, then start over at s.seq.
    ++stats_.resyncs;
    release_held();
    ++stats_.missing;
    ++stats_.gaps;
    RxEvent& e = enqueue(RxEvent::Type::kMissing, rx_time_ns);
    e.missing_first_seq = next_;
    e.missing_count = 1;
    e.resync = true;
    have_missing_ = false;
    next_ = s.seq;
    max_seen_ = s.seq;
    history_ = 0;
    d = 0;
  }
  if (static_cast<std::uint32_t>(d) >= W) {
    advance_to(s.seq - static_cast<std::uint32_t>(W - 1));
  }
  Slot& slot = slots_[s.seq % W];
  if (slot.valid) {
    ++stats_.duplicates;
    return;
  }
  if (static_cast<std::int32_t>(s.seq - max_seen_) < 0) {
    ++stats_.reordered;
  } else {
    max_seen_ = s.seq;
  }
  slot.valid = true;
  slot.rx_time_ns = rx_time_ns;
  slot.s = s;
  while (slots_[next_ % W].valid) {
    Slot& head = slots_[next_ % W];
    deliver(head);
    head.valid = false;
    ++next_;
  }
}

template <std::size_t W>
bool Receiver<W>::pop(RxEvent& out) {
  if (q_count_ == 0) {
    return false;
  }
  out = q_[q_head_];
  q_head_ = (q_head_ + 1) % kQueue;
  --q_count_;
  return true;
}

template <std::size_t W>
bool Receiver<W>::flush() {
  if (queue_free() < kMaxEventsPerPush) {
    return false;
  }
  for (auto& p : partial_) {
    if (p.active) {
      ++stats_.truncated;
      p.active = false;
    }
  }
  release_held();
  return true;
}

template <std::size_t W>
std::size_t Receiver<W>::held() const {
  std::size_t n = 0;
  for (const auto& s : slots_) {
    n += s.valid ? 1U : 0U;
  }
  return n;
}

}  // namespace imu::hal

#endif  // IMU_HAL_RECEIVER_HPP

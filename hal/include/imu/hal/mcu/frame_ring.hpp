// Bare-metal MCU backend of the frame ports (imu/hal/frame_io.hpp): interrupt-fed rings.
//
//   SpscRing<T, N>      lock-free single-producer / single-consumer ring of N slots.
//   IsrFrameSource<N>   FrameSource over a SpscRing<RxFrame, N>: the CAN RX interrupt pushes
//                       (push_from_isr), the main loop takes frames with receive().
//   RingFrameSink<N>    FrameSink over a SpscRing<CanFrame, N>: the node's send() pushes
//                       telemetry, one consumer (the CAN TX-complete interrupt or the main
//                       loop) pops and hands it to the controller.
// The ports hold a reference to their ring, which the image defines as a separate object: the
// ports have a vtable pointer, so a port object is initialised data (.data: flash and RAM),
// while a ring on its own is all zeros (.bss: RAM only).
//
// Platform-free (no OS, no heap, no exceptions; built under the fw rules), compile-time
// capacities, header-only, unit-tested on the desktop (tests/hal/test_frame_ring.cpp).
//
// Concurrency: exactly one producer context and one consumer context per ring (e.g. an ISR and
// the main loop). The producer owns head_, the consumer owns tail_; each publishes its index
// with a release store and reads the other's with an acquire load, so a slot's contents are
// visible before the index that hands it over. On a single-core Cortex-M4 this compiles to
// plain loads and stores plus DMB; it is also correct on a multi-core host. Indices and
// counters are 32-bit: std::atomic<uint64_t> is not lock-free on the M4 (it would need
// libatomic), so counters wrap at 2^32 (compare them modulo 2^32).
//
// Full ring: the NEWEST item is dropped (push returns false) and counted in overflows().
// Dropping the oldest instead would need the producer to advance tail_, which the consumer owns:
// that needs a lock or a CAS loop against a consumer that may be mid-copy of that very slot.
// For the IMU stream, dropping the newest also keeps the delivered frames a prefix of the
// stream with one gap, which the receiver's sequence check reports as missing samples.
#ifndef IMU_HAL_MCU_FRAME_RING_HPP
#define IMU_HAL_MCU_FRAME_RING_HPP

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "imu/hal/frame_io.hpp"

namespace imu::hal::mcu {

/// Lock-free SPSC ring of N slots (N a power of two, 2 .. 2^31). Each operation is O(1) plus a
/// copy of T; none waits. T must be trivially copyable (it is copied into and out of slots).
template <typename T, std::size_t N>
class SpscRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "capacity must be a power of two >= 2");
  static_assert(N <= (std::size_t{1} << 31), "capacity must fit the 32-bit free-running index");
  static_assert(std::is_trivially_copyable_v<T>, "slots are copied");
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free, "needs lock-free 32-bit atomics");

 public:
  static constexpr std::size_t capacity() { return N; }

  /// Producer only. Copies v into the ring; false (nothing stored) when the ring is full.
  bool push(const T& v) {
    const std::uint32_t head = head_.load(std::memory_order_relaxed);  // own index
    const std::uint32_t tail = tail_.load(std::memory_order_acquire);  // slot freed by consumer
    if (head - tail >= N) {
      return false;
    }
    slots_[head & kMask] = v;
    head_.store(head + 1U, std::memory_order_release);  // publish the slot
    return true;
  }

  /// Consumer only. The oldest item, or nullptr when empty. Valid until drop_front().
  [[nodiscard]] const T* front() const {
    const std::uint32_t tail = tail_.load(std::memory_order_relaxed);  // own index
    const std::uint32_t head = head_.load(std::memory_order_acquire);  // slot published
    return head == tail ? nullptr : &slots_[tail & kMask];
  }

  /// Consumer only. Releases the oldest item (no-op when empty).
  void drop_front() {
    const std::uint32_t tail = tail_.load(std::memory_order_relaxed);
    if (head_.load(std::memory_order_acquire) != tail) {
      tail_.store(tail + 1U, std::memory_order_release);  // slot may be reused
    }
  }

  /// Consumer only. Moves the oldest item to out; false when empty.
  bool pop(T& out) {
    const T* p = front();
    if (p == nullptr) {
      return false;
    }
    out = *p;
    drop_front();
    return true;
  }

  /// Items in the ring: exact from the producer or the consumer side, a snapshot elsewhere.
  [[nodiscard]] std::size_t size() const {
    const std::uint32_t tail = tail_.load(std::memory_order_acquire);
    const std::uint32_t head = head_.load(std::memory_order_acquire);
    return static_cast<std::size_t>(head - tail);
  }
  [[nodiscard]] bool empty() const { return size() == 0; }

 private:
  static constexpr std::uint32_t kMask = static_cast<std::uint32_t>(N - 1);
  T slots_[N] = {};
  std::atomic<std::uint32_t> head_{0};  ///< next slot to write; written by the producer only
  std::atomic<std::uint32_t> tail_{0};  ///< next slot to read; written by the consumer only
};

/// Frame source fed by the CAN receive interrupt. Producer: push_from_isr (one ISR, or any one
/// context). Consumer: receive (the main loop).
template <std::size_t N>
class IsrFrameSource final : public FrameSource {
 public:
  using Ring = SpscRing<RxFrame, N>;
  /// The ring must outlive the source; the source is its only producer and consumer.
  explicit IsrFrameSource(Ring& ring) : ring_(ring) {}

  /// Producer. Queues one received frame as the transport delivered it (nbytes: kCanMtu or
  /// kCanFdMtu; the receiver counts anything else) with its receive time. False when the
  /// ring is full: the frame is dropped and counted in overflows(). O(1).
  bool push_from_isr(const CanFrame& f, std::uint32_t nbytes, std::uint64_t rx_time_ns) {
    RxFrame r{};
    r.frame = f;
    r.nbytes = nbytes;
    r.rx_time_ns = rx_time_ns;
    if (ring_.push(r)) {
      return true;
    }
    overflows_.store(overflows_.load(std::memory_order_relaxed) + 1U,
                     std::memory_order_relaxed);  // producer is the only writer
    return false;
  }

  /// Consumer. Takes up to cap queued frames, oldest first. Never waits (timeout_ms is
  /// ignored: on an MCU the caller sleeps in WFI until the next interrupt): kTimeout when
  /// nothing is queued, kBadArgument on a null or empty buffer. O(frames taken).
  [[nodiscard]] IoStatus receive(RxFrame* out, std::size_t cap, std::size_t& n,
                                 int /*timeout_ms*/) override {
    n = 0;
    if (out == nullptr || cap == 0) {
      return IoStatus::kBadArgument;
    }
    while (n < cap && ring_.pop(out[n])) {
      ++n;
    }
    return n > 0 ? IoStatus::kOk : IoStatus::kTimeout;
  }

  /// Frames dropped because the ring was full (wraps at 2^32). Any context.
  [[nodiscard]] std::uint32_t overflows() const {
    return overflows_.load(std::memory_order_relaxed);
  }
  /// Frames queued now (a snapshot outside the two contexts).
  [[nodiscard]] std::size_t pending() const { return ring_.size(); }
  static constexpr std::size_t capacity() { return N; }

 private:
  Ring& ring_;
  std::atomic<std::uint32_t> overflows_{0};
};

/// Frame sink drained by the CAN transmit side. Producer: send() (the node, in the main loop).
/// Consumer: front()/drop_front() or pop() (the TX-complete interrupt OR the main loop, one of
/// them). When the ring is full, send() may call a wait function (set_wait) that makes room,
/// e.g. by handing queued frames to the controller; if there is still no room the frame is
/// dropped, counted in overflows(), and send() returns kWouldBlock (the node counts it too).
template <std::size_t N>
class RingFrameSink final : public FrameSink {
 public:
  /// Called by send() on a full ring when timeout_ms != 0; returns true if there may be room
  /// now. It runs in the producer's context: if it pops, the producer context must be the
  /// ring's only consumer (e.g. the main loop both sends and drains).
  using WaitFn = bool (*)(void* ctx, int timeout_ms);
  using Ring = SpscRing<CanFrame, N>;
  /// The ring must outlive the sink; the sink is its only producer and consumer.
  explicit RingFrameSink(Ring& ring) : ring_(ring) {}

  void set_wait(WaitFn fn, void* ctx) {
    wait_ = fn;
    wait_ctx_ = ctx;
  }

  /// Producer. Queues f (O(1) plus the wait function on a full ring).
  [[nodiscard]] IoStatus send(const CanFrame& f, int timeout_ms) override {
    if (ring_.push(f)) {
      return IoStatus::kOk;
    }
    if (wait_ != nullptr && timeout_ms != 0 && wait_(wait_ctx_, timeout_ms) && ring_.push(f)) {
      return IoStatus::kOk;
    }
    overflows_.store(overflows_.load(std::memory_order_relaxed) + 1U, std::memory_order_relaxed);
    return IoStatus::kWouldBlock;
  }

  /// Consumer. The oldest queued frame or nullptr; keep it queued until the controller has
  /// accepted it, then drop_front().
  [[nodiscard]] const CanFrame* front() const { return ring_.front(); }
  void drop_front() { ring_.drop_front(); }
  bool pop(CanFrame& out) { return ring_.pop(out); }

  /// Frames refused because the ring stayed full (wraps at 2^32). Any context.
  [[nodiscard]] std::uint32_t overflows() const {
    return overflows_.load(std::memory_order_relaxed);
  }
  [[nodiscard]] std::size_t pending() const { return ring_.size(); }
  static constexpr std::size_t capacity() { return N; }

 private:
  Ring& ring_;
  std::atomic<std::uint32_t> overflows_{0};
  WaitFn wait_ = nullptr;
  void* wait_ctx_ = nullptr;
};

}  // namespace imu::hal::mcu

#endif  // IMU_HAL_MCU_FRAME_RING_HPP

// The node's main loop on a bare-metal MCU (see imu/node/mcu_main.hpp and
// imu/hal/mcu/board_hooks.hpp). Compiled under fw/'s rules. Static state only: the Node, two
// rings; no heap, no semihosting, no instruction named here (the core's are in the HAL).
//
// Main loop (imu_m4_main, called by the board's reset handler; never returns):
//   1. take received frames from the receive ring in small batches, hand each to
//      Node::on_frame, publish the ring's drop count to the node (telemetry), pass queued
//      telemetry to the controller (imu_board_can_send) until it is busy;
//   2. after kIdleMs without a frame (board clock): Node::on_idle() once (the full set);
//   3. nothing to do: WFI with interrupts masked around the emptiness check, so a frame that
//      arrives between the check and the WFI still wakes the core.
// The telemetry ring's consumer is the main loop (step 1 and the sink's wait function), never
// an interrupt, so the ring has one consumer.
#include "imu/node/mcu_main.hpp"

#include "imu/hal/mcu/board_hooks.hpp"
#include "imu/hal/mcu/cortex_m.hpp"
#include "imu/hal/mcu/frame_ring.hpp"
#include "imu/hal/mcu/startup.hpp"

namespace imu::node::mcu {
namespace {

constexpr std::size_t kBatch = 4;              // frames taken from the ring per receive()
constexpr std::uint32_t kMaxTxPolls = 1U << 16;  // bound of a wait without a board clock

Node g_node;
hal::mcu::IsrFrameSource<kRxFrames>::Ring g_rx_ring;  // .bss
hal::mcu::RingFrameSink<kTxFrames>::Ring g_tx_ring;    // .bss
hal::mcu::IsrFrameSource<kRxFrames> g_rx(g_rx_ring);
hal::mcu::RingFrameSink<kTxFrames> g_tx(g_tx_ring);
std::uint32_t g_idle_flushes = 0;

/// Hands queued telemetry to the controller until it is busy or the ring is empty. Returns the
/// frames it took.
std::size_t drain_tx() {
  std::size_t n = 0;
  for (const hal::CanFrame* f = g_tx.front(); f != nullptr; f = g_tx.front()) {
    if (!imu_board_can_send(*f)) {
      break;
    }
    g_tx.drop_front();
    ++n;
  }
  return n;
}

/// The telemetry sink's wait (ring full): poll the controller until it takes a frame, for at
/// most timeout_ms by the board clock (negative: no time bound) and kMaxTxPolls polls.
bool wait_tx(void* /*ctx*/, int timeout_ms) {
  const std::uint32_t start = imu_board_millis();
  const std::uint32_t limit =
      timeout_ms < 0 ? ~std::uint32_t{0} : static_cast<std::uint32_t>(timeout_ms);
  for (std::uint32_t polls = 0; polls < kMaxTxPolls; ++polls) {
    if (drain_tx() > 0) {
      return true;
    }
    if (imu_board_millis() - start >= limit) {
      return false;
    }
  }
  return false;
}

/// Sleeps until an interrupt if no frame is queued (see hal::mcu::sleep_until_interrupt_unless).
void sleep_until_interrupt() {
  hal::mcu::sleep_until_interrupt_unless([] { return g_rx.pending() != 0; });
}

/// Step 1 of the main loop: every queued frame through the node. True if there was any.
bool process_rx() {
  hal::RxFrame batch[kBatch];
  std::size_t n = 0;
  bool any = false;
  while (g_rx.receive(batch, kBatch, n, 0) == hal::IoStatus::kOk) {
    for (std::size_t i = 0; i < n; ++i) {
      g_node.on_frame(batch[i].frame, batch[i].nbytes, batch[i].rx_time_ns);
    }
    g_node.set_link_counters(g_rx.overflows(), 0);
    (void)drain_tx();
    any = true;
  }
  return any;
}

}  // namespace

const Node& image_node() { return g_node; }

LoopCounters loop_counters() {
  return LoopCounters{static_cast<std::uint32_t>(g_rx.pending()), g_rx.overflows(),
                      static_cast<std::uint32_t>(g_tx.pending()), g_tx.overflows(),
                      g_idle_flushes};
}

}  // namespace imu::node::mcu

bool imu_node_can_rx(const imu::hal::CanFrame& f, std::uint32_t nbytes,
                     std::uint64_t rx_time_ns) {
  return imu::node::mcu::g_rx.push_from_isr(f, nbytes, rx_time_ns);
}

// The main loop (see the file comment). Returns 1 only if the node refuses its configuration.
extern "C" int imu_m4_main() {
  namespace mcu = imu::node::mcu;
  imu_board_init();
  mcu::g_tx.set_wait(mcu::wait_tx, nullptr);
  const imu::node::NodeConfig cfg;  // defaults: status 1 s, full set 60 s at 100 Hz
  if (mcu::g_node.configure(cfg, mcu::g_tx, nullptr, nullptr) != imu::node::NodeStatus::kOk) {
    return 1;
  }
  imu_board_can_init();
  std::uint32_t last_rx_ms = imu_board_millis();
  bool flushed = true;  // nothing received since the last idle flush
  for (;;) {
    if (mcu::process_rx()) {
      last_rx_ms = imu_board_millis();
      flushed = false;
      continue;
    }
    (void)mcu::drain_tx();
    if (!flushed && imu_board_millis() - last_rx_ms >= mcu::kIdleMs) {
      mcu::g_node.on_idle();
      ++mcu::g_idle_flushes;
      flushed = true;
      (void)mcu::drain_tx();
      continue;
    }
    mcu::sleep_until_interrupt();
  }
}

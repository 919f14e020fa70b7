// The production node image's program (see node_prod.hpp and imu/hal/mcu/board_hooks.hpp).
// Compiled under fw/'s rules. Static state only: the Node, two rings; no heap, no semihosting.
//
// Main loop (imu_m4_main, called by startup.cpp; never returns):
//   1. take received frames from the receive ring in small batches, hand each to
//      Node::on_frame, publish the ring's drop count to the node (telemetry), pass queued
//      telemetry to the controller (imu_board_can_send) until it is busy;
//   2. after kProdIdleMs without a frame (board clock): Node::on_idle() once (the full set);
//   3. nothing to do: WFI with interrupts masked around the emptiness check, so a frame that
//      arrives between the check and the WFI still wakes the core.
// The telemetry ring's consumer is the main loop (step 1 and the sink's wait function), never
// an interrupt, so the ring has one consumer.
#include "imu/node/mcu_main.hpp"

#include "imu/hal/mcu/board_hooks.hpp"
#include "imu/hal/mcu/frame_ring.hpp"
#include "imu/hal/mcu/startup.hpp"

namespace imu::m4 {
namespace {

constexpr std::size_t kBatch = 4;              // frames taken from the ring per receive()
constexpr std::uint32_t kMaxTxPolls = 1U << 16;  // bound of a wait without a board clock
constexpr std::uintptr_t kScbAircr = 0xE000ED0CU;
constexpr std::uint32_t kAircrSysReset = 0x05FA0004U;  // VECTKEY | SYSRESETREQ

node::Node g_node;
hal::mcu::IsrFrameSource<kProdRxFrames>::Ring g_rx_ring;  // .bss
hal::mcu::RingFrameSink<kProdTxFrames>::Ring g_tx_ring;    // .bss
hal::mcu::IsrFrameSource<kProdRxFrames> g_rx(g_rx_ring);
hal::mcu::RingFrameSink<kProdTxFrames> g_tx(g_tx_ring);
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

/// Sleeps until an interrupt if no frame is queued. PRIMASK is set around the check: a pending
/// interrupt still ends WFI, and is taken once PRIMASK is cleared.
void sleep_until_interrupt() {
  asm volatile("cpsid i" ::: "memory");
  if (g_rx.pending() == 0) {
    asm volatile("dsb\n\twfi" ::: "memory");
  }
  asm volatile("cpsie i" ::: "memory");
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

const node::Node& prod_node() { return g_node; }

ProdCounters prod_counters() {
  return ProdCounters{static_cast<std::uint32_t>(g_rx.pending()), g_rx.overflows(),
                      static_cast<std::uint32_t>(g_tx.pending()), g_tx.overflows(),
                      g_idle_flushes};
}

}  // namespace imu::m4

bool imu_node_can_rx(const imu::hal::CanFrame& f, std::uint32_t nbytes,
                     std::uint64_t rx_time_ns) {
  return imu::m4::g_rx.push_from_isr(f, nbytes, rx_time_ns);
}

extern "C" int imu_m4_main() {
  using imu::m4::g_node;
  imu_board_init();
  imu::m4::g_tx.set_wait(imu::m4::wait_tx, nullptr);
  const imu::node::NodeConfig cfg;  // defaults: status 1 s, full set 60 s at 100 Hz
  if (g_node.configure(cfg, imu::m4::g_tx, nullptr, nullptr) != imu::node::NodeStatus::kOk) {
    return 1;
  }
  imu_board_can_init();
  std::uint32_t last_rx_ms = imu_board_millis();
  bool flushed = true;  // nothing received since the last idle flush
  for (;;) {
    if (imu::m4::process_rx()) {
      last_rx_ms = imu_board_millis();
      flushed = false;
      continue;
    }
    (void)imu::m4::drain_tx();
    if (!flushed && imu_board_millis() - last_rx_ms >= imu::m4::kProdIdleMs) {
      g_node.on_idle();
      ++imu::m4::g_idle_flushes;
      flushed = true;
      (void)imu::m4::drain_tx();
      continue;
    }
    imu::m4::sleep_until_interrupt();
  }
}

// ---- weak board defaults (board_hooks.hpp) and the startup's exit and fault hooks ----------

__attribute__((weak)) void imu_board_init() {}
__attribute__((weak)) void imu_board_can_init() {}
__attribute__((weak)) bool imu_board_can_send(const imu::hal::CanFrame& /*f*/) { return false; }
__attribute__((weak)) std::uint32_t imu_board_millis() { return 0; }

__attribute__((weak)) void imu_board_fault() {
  asm volatile("dsb" ::: "memory");
  *reinterpret_cast<volatile std::uint32_t*>(imu::m4::kScbAircr) =  // NOLINT: SCB register
      imu::m4::kAircrSysReset;
  asm volatile("dsb" ::: "memory");
  for (;;) {
    asm volatile("wfi");
  }
}

extern "C" void imu_m4_exit(int /*rc*/) { imu_board_fault(); }
extern "C" void imu_m4_fault() { imu_board_fault(); }

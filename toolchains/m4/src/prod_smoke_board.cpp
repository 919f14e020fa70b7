// Board shim of the production image's smoke variant (imu_m4_node_prod_smoke.elf, QEMU
// mps2-an386 only; never in the production image). It implements the board hooks
// (imu/hal/mcu/board_hooks.hpp) with SysTick as the "CAN receive interrupt": every 1 ms tick
// injects the next frame of a short record (a ConfigRecord, the largest model for each of the
// six channels, kSmokeSamples samples from samples.hpp) through imu_node_can_rx, paced so that
// at most half the receive ring is queued. imu_board_can_send accepts every telemetry frame and
// counts it by record kind. kCheckMs after the last frame (past the 200 ms idle flush), the tick
// checks what the node did and exits through semihosting:
//   PROD-SMOKE tx=<frames> stats=<n> adev=<n> echo=<n> samples=<n> models=<n> rejected=<n>
//              rx_overflows=<n> tx_overflows=<n> idle=<n> stack_used=<bytes> of=<bytes>
//   PROD-SMOKE PASS | PROD-SMOKE FAIL   (exit status 0 | 1; 3 on a fault)
#include <cstdint>

#include "imu/hal/codec.hpp"
#include "imu/hal/mcu/board_hooks.hpp"
#include "imu/hal/mcu/startup.hpp"
#include "imu/node/mcu_main.hpp"
#include "largest_model.hpp"
#include "line.hpp"
#include "samples.hpp"
#include "semihost.hpp"

namespace {

constexpr std::uint32_t kSmokeSamples = 300;  // 3 s at 100 Hz: three status sets
constexpr std::uint32_t kSetupFrames = 1 + imu::hal::kChannels;
constexpr std::uint32_t kFrames = kSetupFrames + kSmokeSamples;
constexpr std::uint32_t kCheckMs = 1000;
// The stack's high-water mark must stay this far below its size: a mark at the size would not
// tell a fit from an overflow into .bss, and interrupts nest on the same stack.
constexpr std::size_t kStackGuardBytes = 1024;
constexpr std::uint32_t kSysclkHz = 25000000;  // mps2-an386
constexpr std::uintptr_t kSystCsr = 0xE000E010U;
constexpr std::uintptr_t kSystRvr = 0xE000E014U;
constexpr std::uintptr_t kSystCvr = 0xE000E018U;

volatile std::uint32_t& reg(std::uintptr_t a) {
  return *reinterpret_cast<volatile std::uint32_t*>(a);  // NOLINT: memory-mapped register
}

// Written by the tick only.
volatile std::uint32_t g_ms = 0;
std::uint32_t g_next = 0;
std::uint32_t g_last_ms = 0;
imu::m4::SampleSource g_src[imu::hal::kChannels] = {
    imu::m4::SampleSource(0), imu::m4::SampleSource(1), imu::m4::SampleSource(2),
    imu::m4::SampleSource(3), imu::m4::SampleSource(4), imu::m4::SampleSource(5)};

// Written by the main loop only (imu_board_can_send), read by the tick at the end.
struct TxCounts {
  std::uint32_t total;
  std::uint32_t stats;
  std::uint32_t adev;
  std::uint32_t echo;
};
volatile TxCounts g_txc = {};

void encode_frame(std::uint32_t k, imu::hal::EncodedFrames& fr) {
  using imu::hal::Layout;
  if (k == 0) {
    imu::hal::ConfigRecord cfg{};
    cfg.cfg_id = 1;
    cfg.rate_hz = 100.0;
    for (double& l : cfg.lsb) {
      l = 1.0 / 1024.0;
    }
    imu::hal::encode(cfg, Layout::kFd, 0, fr);
  } else if (k < kSetupFrames) {
    imu::hal::encode(imu::m4::largest_model(static_cast<std::uint8_t>(k - 1)), false, Layout::kFd, 0, fr);
  } else {
    imu::hal::SampleRecord s{};
    s.seq = k - kSetupFrames;
    s.t_sensor_ns = static_cast<std::uint64_t>(s.seq) * 10000000U;
    s.cfg_id = 1;
    for (std::size_t c = 0; c < imu::hal::kChannels; ++c) {
      s.counts[c] = g_src[c].next();
    }
    imu::hal::encode(s, Layout::kFd, fr);
  }
}

void inject_next() {
  imu::hal::EncodedFrames fr{};
  encode_frame(g_next, fr);
  const std::uint64_t t_ns = static_cast<std::uint64_t>(g_ms) * 1000000U;
  for (std::size_t i = 0; i < fr.count; ++i) {
    (void)imu_node_can_rx(fr.frame[i], static_cast<std::uint32_t>(imu::hal::wire_size(fr.frame[i])),
                          t_ns);
  }
  ++g_next;
}

[[noreturn]] void check_and_exit() {
  const imu::node::NodeStats& st = imu::node::mcu::image_node().stats();
  const imu::node::mcu::LoopCounters pc = imu::node::mcu::loop_counters();
  const std::uint32_t total = g_txc.total;
  const std::uint32_t stats = g_txc.stats;
  const std::uint32_t adev = g_txc.adev;
  const std::uint32_t echo = g_txc.echo;
  imu::m4::Line<> line;
  line.str("PROD-SMOKE tx=").u64(total).str(" stats=").u64(stats).str(" adev=").u64(adev);
  line.str(" echo=").u64(echo).str(" samples=").u64(st.samples);
  line.str(" models=").u64(st.models_accepted).str(" rejected=").u64(st.model_rejected);
  line.str(" rx_overflows=").u64(pc.rx_overflows).str(" tx_overflows=").u64(pc.tx_overflows);
  line.str(" idle=").u64(pc.idle_flushes);
  line.str(" stack_used=").u64(imu::hal::mcu::stack_high_water_bytes());
  line.str(" of=").u64(imu::hal::mcu::stack_size_bytes()).str("\n");
  imu::m4::semihost_write0(line.c_str());
  const bool ok = st.samples == kSmokeSamples && st.models_accepted == imu::hal::kChannels &&
                  st.model_rejected == 0 && pc.rx_overflows == 0 && pc.tx_overflows == 0 &&
                  pc.idle_flushes >= 1 && stats >= kSmokeSamples / 100 && adev > 0 &&
                  echo >= imu::hal::kChannels && !line.truncated() &&
                  imu::hal::mcu::stack_high_water_bytes() + kStackGuardBytes <=
                      imu::hal::mcu::stack_size_bytes();
  imu::m4::semihost_write0(ok ? "PROD-SMOKE PASS\n" : "PROD-SMOKE FAIL\n");
  imu::m4::semihost_exit(ok ? 0 : 1);
}

}  // namespace

extern "C" void SysTick_Handler() {
  g_ms = g_ms + 1;
  if (g_next < kFrames) {
    if (imu::node::mcu::loop_counters().rx_pending < imu::node::mcu::kRxFrames / 2) {
      inject_next();
      g_last_ms = g_ms;
    }
  } else if (g_ms - g_last_ms >= kCheckMs) {
    check_and_exit();
  }
}

void imu_board_init() {}

void imu_board_can_init() {
  reg(kSystRvr) = kSysclkHz / 1000U - 1U;  // 1 ms
  reg(kSystCvr) = 0;
  reg(kSystCsr) = 0x7U;  // ENABLE | TICKINT | CLKSOURCE = processor clock
}

bool imu_board_can_send(const imu::hal::CanFrame& f) {
  imu::hal::RecordKind kind{};
  imu::hal::Layout layout{};
  TxCounts c = {g_txc.total, g_txc.stats, g_txc.adev, g_txc.echo};
  ++c.total;
  if (imu::hal::kind_of_id(f.can_id, kind, layout)) {
    c.stats += kind == imu::hal::RecordKind::kStats ? 1U : 0U;
    c.adev += kind == imu::hal::RecordKind::kAdev ? 1U : 0U;
    c.echo += (kind == imu::hal::RecordKind::kModelEcho ||
               kind == imu::hal::RecordKind::kModelEcho2) ? 1U : 0U;
  }
  g_txc.total = c.total;
  g_txc.stats = c.stats;
  g_txc.adev = c.adev;
  g_txc.echo = c.echo;
  return true;
}

std::uint32_t imu_board_millis() { return g_ms; }

void imu_board_fault() {
  imu::m4::semihost_write0("PROD-SMOKE FAULT\n");
  imu::m4::semihost_exit(3);
}

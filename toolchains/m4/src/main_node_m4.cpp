// Bare-metal program of the node image (imu_m4_main, called by the board's reset handler): runs
// the node workload (node_workload.hpp), prints through semihosting, and measures the node's
// cost with the SysTick counter. Under `qemu-system-arm -icount shift=0` the virtual clock
// advances one step per guest instruction, so SysTick ticks are proportional to instructions
// executed; the ratio is calibrated on a loop of known length (2 instructions per iteration:
// subs, bne).
// Extra lines (target only):
//   IMU-NODE COST ticks=<samples phase> cal_ticks=<calibration loop> cal_insns=<its instructions>
//   IMU-NODE STEADY-COST ticks=<ticks> samples=<S>: the same over S samples of a second node
//     whose pushed filters have frozen their gains (run_node_steady)
//   IMU-ADEV COST frame_ticks=<ticks> frames=<F> block_ticks=<ticks> samples=<S>
//     the ADEV kernel alone: F frames of six channels through the node's
//     MultiAdev<6, 8, 22>::push_frame, and S samples of one channel through
//     OnlineAdev<8, 22>::push_block, each on pseudo-random counts (an LCG)
//   IMU-M4 STACK used=<bytes> of=<bytes>
#include <cstdint>

#include "imu/hal/mcu/startup.hpp"
#include "imu/node/node.hpp"
#include "imu/online_adev.hpp"

#include "line.hpp"
#include "largest_model.hpp"
#include "node_workload.hpp"
#include "semihost.hpp"

namespace {

constexpr std::uintptr_t kSystCsr = 0xE000E010u;
constexpr std::uintptr_t kSystRvr = 0xE000E014u;
constexpr std::uintptr_t kSystCvr = 0xE000E018u;
constexpr std::uint32_t kSystMask = 0x00FFFFFFu;  // 24-bit down-counter

volatile std::uint32_t& reg(std::uintptr_t a) {
  return *reinterpret_cast<volatile std::uint32_t*>(a);  // NOLINT: memory-mapped register
}

void systick_start() {
  reg(kSystRvr) = kSystMask;
  reg(kSystCvr) = 0;
  reg(kSystCsr) = 0x5u;  // ENABLE | CLKSOURCE = processor clock, no interrupt
}

/// Elapsed ticks, accumulated across wraps: must be called at least once per 2^24 ticks.
struct TickCounter {
  std::uint32_t last = 0;
  std::uint64_t total = 0;
  void start() {
    last = reg(kSystCvr) & kSystMask;
    total = 0;
  }
  void poll() {
    const std::uint32_t now = reg(kSystCvr) & kSystMask;
    total += (last - now) & kSystMask;  // down-counter: elapsed = last - now (mod 2^24)
    last = now;
  }
};

TickCounter g_ticks;

void write_semihost(const char* text, void* /*ctx*/) { imu::m4::semihost_write0(text); }

void mark(int phase, void* /*ctx*/) {
  if (phase == 0) {
    g_ticks.start();
  } else {
    g_ticks.poll();
  }
}

// The ADEV kernel alone, outside the node: frames through MultiAdev::push_frame (the node's
// path) and a block through OnlineAdev::push_block. Static: no stack, no heap.
constexpr std::uint32_t kAdevFrames = 4096;
constexpr std::uint32_t kAdevBlock = 4096;
imu::node::NodeAdev g_multi;
imu::OnlineAdev<8, 22> g_single(0.01, 1.0);
std::int32_t g_block[kAdevBlock];

std::int32_t next_counts(std::uint32_t& s) {
  s = s * 1664525U + 1013904223U;  // LCG: cheap, deterministic
  return static_cast<std::int32_t>(s >> 20U) - 2048;
}

void adev_kernel_cost(std::uint64_t& frame_ticks, std::uint64_t& block_ticks) {
  std::uint32_t s = 12345U;
  std::int32_t frame[imu::node::kChannels];
  TickCounter t;
  t.start();
  for (std::uint32_t f = 0; f < kAdevFrames; ++f) {
    for (auto& c : frame) {
      c = next_counts(s);  // ~4 instructions per channel: counted in, negligible beside the push
    }
    g_multi.push_frame(frame);
    t.poll();
  }
  g_multi.flush();
  t.poll();
  frame_ticks = t.total;
  for (auto& c : g_block) {
    c = next_counts(s);
  }
  t.start();
  for (std::uint32_t k = 0; k < kAdevBlock; k += 256) {
    g_single.push_block(g_block + k, 256);
    t.poll();
  }
  block_ticks = t.total;
}

// The node's filter alone (NodeFilter on the largest model, discretised on target at 100 Hz):
// time-varying steps from its prior, then, once its gain has frozen, frozen steps. Static.
constexpr std::uint32_t kKfSteps = 2000;
imu::DiscreteModel<imu::node::kNodeStates> g_kf_model;
imu::node::NodeFilter g_kf;

bool filter_cost(std::uint64_t& tv_ticks, std::uint64_t& steady_ticks) {
  imu::ModelParams p{};
  std::size_t states = 0;
  if (!imu::node::model_record_valid(imu::m4::largest_model(0), p) ||
      !imu::node::discretize_pushed(p, 100.0, g_kf_model, states) ||
      g_kf.configure(g_kf_model, 0.0) != imu::KfStatus::kOk) {
    return false;
  }
  g_kf.set_steady_state(true);
  std::uint32_t s = 777U;
  volatile float sink = 0.0F;
  TickCounter t;
  t.start();
  for (std::uint32_t k = 0; k < kKfSteps; ++k) {
    sink = g_kf.step(static_cast<float>(next_counts(s)) * 0.01F, true).innovation;
    t.poll();
  }
  tv_ticks = t.total;
  for (std::uint32_t k = 0; k < 400000 && !g_kf.steady(); ++k) {
    sink = g_kf.step(static_cast<float>(next_counts(s)) * 0.01F, true).innovation;
  }
  if (!g_kf.steady()) {
    return false;
  }
  t.start();
  for (std::uint32_t k = 0; k < kKfSteps; ++k) {
    sink = g_kf.step(static_cast<float>(next_counts(s)) * 0.01F, true).innovation;
    t.poll();
  }
  steady_ticks = t.total;
  (void)sink;
  return true;
}

constexpr std::uint32_t kCalIterations = 1000000;

std::uint64_t calibrate() {
  TickCounter t;
  t.start();
  std::uint32_t n = kCalIterations;
  asm volatile(
      "1:\n\t"
      "subs %0, %0, #1\n\t"
      "bne 1b\n\t"
      : "+r"(n)
      :
      : "cc");
  t.poll();
  return t.total;
}

}  // namespace

extern "C" int imu_m4_main() {
  systick_start();
  const std::uint64_t cal = calibrate();
  const imu::m4::NodeRunStatus st = imu::m4::run_node_workload(write_semihost, mark, nullptr);
  imu::m4::Line<> line;
  line.str("IMU-NODE COST ticks=").u64(g_ticks.total).str(" cal_ticks=").u64(cal);
  line.str(" cal_insns=").u64(2ULL * kCalIterations).str("\n");
  imu::m4::semihost_write0(line.c_str());
  const imu::m4::NodeRunStatus st_steady =
      imu::m4::run_node_steady(write_semihost, mark, nullptr);
  line.clear();
  line.str("IMU-NODE STEADY-COST ticks=").u64(g_ticks.total).str(" samples=");
  line.u64(imu::m4::kSteadySamples).str("\n");
  imu::m4::semihost_write0(line.c_str());
  std::uint64_t frame_ticks = 0;
  std::uint64_t block_ticks = 0;
  adev_kernel_cost(frame_ticks, block_ticks);
  line.clear();
  line.str("IMU-ADEV COST frame_ticks=").u64(frame_ticks).str(" frames=").u64(kAdevFrames);
  line.str(" block_ticks=").u64(block_ticks).str(" samples=").u64(kAdevBlock).str("\n");
  imu::m4::semihost_write0(line.c_str());
  std::uint64_t tv_ticks = 0;
  std::uint64_t kf_steady_ticks = 0;
  if (filter_cost(tv_ticks, kf_steady_ticks)) {
    line.clear();
    line.str("IMU-KF COST tv_ticks=").u64(tv_ticks).str(" steady_ticks=").u64(kf_steady_ticks);
    line.str(" steps=").u64(kKfSteps).str("\n");
    imu::m4::semihost_write0(line.c_str());
  }
  line.clear();
  line.str("IMU-M4 STACK used=").u64(imu::hal::mcu::stack_high_water_bytes());
  line.str(" of=").u64(imu::hal::mcu::stack_size_bytes()).str("\n");
  imu::m4::semihost_write0(line.c_str());
  return st == imu::m4::NodeRunStatus::kOk && st_steady == imu::m4::NodeRunStatus::kOk ? 0 : 1;
}

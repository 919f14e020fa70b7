// Online ADEV cost: ns per sample per channel (L = 24 and the default L = 22, M = 8), and the
// bytes of state per channel with where they go. Run: build/tests/bench/bench_adev
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include "imu/online_adev.hpp"

namespace {

std::vector<std::int32_t> make_input(std::size_t n) {
  std::vector<std::int32_t> v(n);
  std::uint32_t s = 12345U;
  for (auto& x : v) {
    s = s * 1664525U + 1013904223U;  // LCG: cheap, deterministic
    x = static_cast<std::int32_t>(s >> 20U) - 2048;
  }
  return v;
}

template <std::size_t M, std::size_t L>
void BM_PushPerSample(benchmark::State& state) {
  const auto input = make_input(1U << 20U);
  imu::OnlineAdev<M, L> adev(0.01, 1.0);
  for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    adev.push_block(input.data(), input.size());
    benchmark::DoNotOptimize(adev);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(input.size()));
  state.counters["ns_per_sample"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(input.size()),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["state_bytes"] = static_cast<double>(sizeof(adev));
}
BENCHMARK(BM_PushPerSample<8, 24>)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PushPerSample<8, 22>)->Unit(benchmark::kMillisecond);

// The baseline-ISA kernel (what a CPU without AVX2 + FMA runs), for comparison.
void BM_PushPerSamplePortable(benchmark::State& state) {
  const auto input = make_input(1U << 20U);
  imu::OnlineAdev<8, 22> adev(0.01, 1.0);
  for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    adev.push_block_portable(input.data(), input.size());
    benchmark::DoNotOptimize(adev);
  }
  state.counters["ns_per_sample"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(input.size()),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_PushPerSamplePortable)->Unit(benchmark::kMillisecond);

void BM_SixChannels(benchmark::State& state) {
  const auto input = make_input(6U << 18U);
  imu::MultiAdev<6, 8, 24> adev;
  for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    for (std::size_t i = 0; i + 6 <= input.size(); i += 6) {
      const std::int32_t(&s)[6] = *reinterpret_cast<const std::int32_t(*)[6]>(&input[i]);
      adev.push(s);
    }
    benchmark::DoNotOptimize(adev);
  }
  const auto samples = static_cast<double>(state.iterations()) * static_cast<double>(input.size());
  state.counters["ns_per_sample_per_channel"] =
      benchmark::Counter(samples, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_SixChannels)->Unit(benchmark::kMillisecond);

// The node's path: one frame of six samples per call, buffered and summed across channels by
// MultiAdev::push_frame (bit-identical to BM_SixChannels' push()).
void BM_SixChannelsFrame(benchmark::State& state) {
  const auto input = make_input(6U << 18U);
  imu::MultiAdev<6, 8, 24> adev;
  for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    for (std::size_t i = 0; i + 6 <= input.size(); i += 6) {
      const std::int32_t(&s)[6] = *reinterpret_cast<const std::int32_t(*)[6]>(&input[i]);
      adev.push_frame(s);
    }
    adev.flush();
    benchmark::DoNotOptimize(adev);
  }
  const auto samples = static_cast<double>(state.iterations()) * static_cast<double>(input.size());
  state.counters["ns_per_sample_per_channel"] =
      benchmark::Counter(samples, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_SixChannelsFrame)->Unit(benchmark::kMillisecond);

// The same six-channel batches through the baseline-ISA kernel (OnlineAdev::push_frames_portable
// on batches of kAdevFrameBufferDefault frames, as MultiAdev::flush() would pass them).
void BM_SixChannelsFramePortable(benchmark::State& state) {
  constexpr std::size_t kF = imu::kAdevFrameBufferDefault;
  using Channel = imu::OnlineAdev<8, 24>;
  const auto input = make_input(6U << 18U);
  Channel ch[6];
  std::int32_t frames[kF][6];
  for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    std::size_t n = 0;
    for (std::size_t i = 0; i + 6 <= input.size(); i += 6) {
      std::memcpy(frames[n], &input[i], sizeof frames[n]);
      if (++n == kF) {
        Channel::push_frames_portable(ch, frames, n);
        n = 0;
      }
    }
    Channel::push_frames_portable(ch, frames, n);
    benchmark::DoNotOptimize(ch);
  }
  const auto samples = static_cast<double>(state.iterations()) * static_cast<double>(input.size());
  state.counters["ns_per_sample_per_channel"] =
      benchmark::Counter(samples, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_SixChannelsFramePortable)->Unit(benchmark::kMillisecond);

void BM_Snapshot(benchmark::State& state) {
  const auto input = make_input(1U << 20U);
  imu::OnlineAdev<8, 24> adev(0.01, 1.0);
  adev.push_block(input.data(), input.size());
  imu::AdevPoint pts[imu::OnlineAdev<8, 24>::kMaxPoints];
  for (auto _ : state) {  // NOLINT(clang-analyzer-deadcode.DeadStores): benchmark idiom
    benchmark::DoNotOptimize(adev.snapshot(pts, std::size(pts)));
  }
}
BENCHMARK(BM_Snapshot)->Unit(benchmark::kMicrosecond);

void print_state_breakdown() {
  constexpr std::size_t kM = 8;
  constexpr std::size_t kL = 24;
  constexpr std::size_t ring = 2 * kM * 8;
  constexpr std::size_t level0 = ring + kM * (8 + 8 + 8) + 8;
  constexpr std::size_t upper = ring + (kM / 2) * (8 + 8 + 8) + 8;
  std::printf("state per channel, M=%zu L=%zu: sizeof = %zu bytes (%.2f KiB)\n", kM, kL,
              sizeof(imu::OnlineAdev<kM, kL>), sizeof(imu::OnlineAdev<kM, kL>) / 1024.0);
  std::printf("  level 0: ring 2M x int64 = %zu, M x (total, partial, terms) = %zu, seg = 8 -> %zu\n",
              ring, kM * 24, level0);
  std::printf("  level k>=1 (x%zu): ring %zu + M/2 x 24 = %zu + seg 8 -> %zu each, %zu total\n", kL,
              ring, (kM / 2) * 24, upper, upper * kL);
  std::printf("  channel header (Ts, LSB, n, phase, missing, gaps) = %zu\n",
              sizeof(imu::OnlineAdev<kM, kL>) - level0 - upper * kL);
  std::printf("default M=8 L=22: %zu bytes per channel; 6 channels: %zu bytes\n",
              sizeof(imu::OnlineAdev<8, 22>), sizeof(imu::MultiAdev<6, 8, 22>));
}

}  // namespace

int main(int argc, char** argv) {
  print_state_breakdown();
  std::printf("kernel path on this CPU (push_block, push_frames): %s\n",
              imu::OnlineAdev<8, 22>::kernel_isa());
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

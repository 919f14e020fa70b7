// See demo.hpp. Compiled under fw/'s rules (prelude force-included: no heap, stdio, exceptions).
#include "demo.hpp"

#include "imu/bias_kf.hpp"
#include "imu/online_adev.hpp"
#include "line.hpp"
#include "samples.hpp"

namespace imu::m4 {
namespace {

// A one-frame push_frame buffer: the demo feeds push(), and the batched path is for hosts with
// double-precision vectors (its stack would not fit the 4 KiB here).
using Adev = MultiAdev<kChannels, kAdevM, kAdevL, 1>;

// Static, not on the stack: the estimator is the bulk of the image's RAM and must show in .bss.
Adev g_adev;
AdevPoint g_points[Adev::Channel::kMaxPoints];
ScalarBiasKf<float> g_kf[kChannels];

}  // namespace

DemoStatus run_demo(WriteFn write, void* ctx) {
  Line<> line;
  std::uint64_t lines = 0;
  bool truncated = false;
  const auto emit = [&]() {
    line.str("\n");
    truncated = truncated || line.truncated();
    write(line.c_str(), ctx);
    ++lines;
    line.clear();
  };

  line.str("IMU-M4 BEGIN channels=").u64(kChannels).str(" samples=").u64(kSamples);
  line.str(" M=").u64(kAdevM).str(" L=").u64(kAdevL);
  line.str(" ts_bits=").f64(kSamplePeriodS).str(" lsb_bits=").f64(kLsb);
  emit();

  g_adev.reset();
  for (std::size_t c = 0; c < kChannels; ++c) {
    g_adev.channel(c).configure(kSamplePeriodS, kLsb);
  }
  SampleSource sources[kChannels] = {};
  for (std::size_t c = 0; c < kChannels; ++c) {
    sources[c] = SampleSource(static_cast<std::uint32_t>(c));
    if (g_kf[c].configure(kKfPhi, kKfQw, kKfR, kKfP0, 0.0, 0.0) != KfStatus::kOk) {
      line.str("IMU-M4 END status=bad_filter_model");
      emit();
      return DemoStatus::kBadFilterModel;
    }
  }
  constexpr auto kLsbF = static_cast<float>(kLsb);  // 2^-10: exact in float
  std::int32_t row[kChannels] = {};
  for (std::uint32_t i = 0; i < kSamples; ++i) {
    const bool is_static = is_static_sample(i);
    for (std::size_t c = 0; c < kChannels; ++c) {
      row[c] = sources[c].next();
      // |counts| < 2^24 here, so the conversion to float is exact.
      static_cast<void>(g_kf[c].step(static_cast<float>(row[c]) * kLsbF, is_static));
    }
    g_adev.push(row);
  }

  for (std::size_t c = 0; c < kChannels; ++c) {
    const auto& ch = g_adev.channel(c);
    const std::size_t k = ch.snapshot(g_points, Adev::Channel::kMaxPoints);
    for (std::size_t i = 0; i < k; ++i) {
      const AdevPoint& p = g_points[i];
      line.str("P c=").u64(c).str(" af=").u64(p.af).str(" st=").u64(p.stride);
      line.str(" n=").u64(p.n_terms).str(" avar=").f64(p.avar).str(" adev=").f64(p.adev);
      line.str(" edf=").f64(p.edf).str(" lo=").f64(p.ci_lo).str(" hi=").f64(p.ci_hi);
      emit();
    }
    line.str("C c=").u64(c).str(" samples=").u64(ch.samples()).str(" points=").u64(k);
    emit();
  }
  for (std::size_t c = 0; c < kChannels; ++c) {
    const auto& kf = g_kf[c];
    const double truth = static_cast<double>(sources[c].bias_counts()) * kLsb;
    line.str("K c=").u64(c).str(" bias=").f32(kf.bias()).str(" var=").f32(kf.variance());
    line.str(" truth=").f64(truth).str(" predictions=").u64(kf.stats().predictions);
    line.str(" updates=").u64(kf.stats().updates);
    emit();
  }

  line.str("IMU-M4 END status=").str(truncated ? "truncated" : "ok").str(" lines=").u64(lines + 1);
  emit();
  return truncated ? DemoStatus::kLineTruncated : DemoStatus::kOk;
}

}  // namespace imu::m4

// See demo.hpp. Compiled under fw/'s rules (prelude force-included: no heap, stdio, exceptions).
#include "demo.hpp"

#include "imu/online_adev.hpp"
#include "line.hpp"
#include "samples.hpp"

namespace imu::m4 {
namespace {

using Adev = MultiAdev<kChannels, kAdevM, kAdevL>;

// Static, not on the stack: the estimator is the bulk of the image's RAM and must show in .bss.
Adev g_adev;
AdevPoint g_points[Adev::Channel::kMaxPoints];

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
  }
  std::int32_t row[kChannels] = {};
  for (std::uint32_t i = 0; i < kSamples; ++i) {
    for (std::size_t c = 0; c < kChannels; ++c) {
      row[c] = sources[c].next();
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
  // TODO(issue 3): run the bias Kalman filter over the same samples and print its state here
  // ("K c=<ch> ..." lines) once fw/ has it.

  line.str("IMU-M4 END status=").str(truncated ? "truncated" : "ok").str(" lines=").u64(lines + 1);
  emit();
  return truncated ? DemoStatus::kLineTruncated : DemoStatus::kOk;
}

}  // namespace imu::m4

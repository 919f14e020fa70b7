// What a rate random walk must not stand in for. A walk raises the ADEV at the long taus and
// the block means' likelihood of a walk; so do flicker (bias instability) seen over a few of
// its decades, a deterministic ramp, and a level shift part way through the record. The walk is
// named only where the record needs it beside them (the line, the step) and where it holds on
// both halves of the record. The first-order model of synth_cases.hpp, 10^6 samples at 100 Hz,
// plus one effect; seeds 911..928 (no other test uses them).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/analyze/synth.hpp"
#include "analyse_checked.hpp"
#include "synth_cases.hpp"

namespace {

namespace ia = imu::analyze;
namespace tc = imu::analyze::test;

constexpr int kSeeds = 8;

ia::Report analyse(const ia::SynthSpec& spec, const std::string& name) {
  return tc::analyse_checked(ia::synthesize(spec), name, spec.seed);
}

using tc::named;

void show(const ia::Report& r, const char* what, std::uint64_t seed) {
  std::printf("%s seed %llu:\n%s", what, static_cast<unsigned long long>(seed),
              ia::to_text(r).c_str());
}

// A ramp of 2e-6 /s (ADEV R tau / sqrt(2) = 1.4e-3 at T/10, above the rest) in flicker of B =
// 3e-4: the ramp, or an unexplained rise, never a walk.
TEST(AnalyzeWalk, ARampInFlickerIsNotAWalk) {
  int walks = 0;
  int ramps = 0;
  for (int i = 0; i < kSeeds; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 911 + static_cast<std::uint64_t>(i));
    spec.flicker_b = 3e-4;
    spec.ramp_r = 2e-6;
    const ia::Report r = analyse(spec, "ramp_flicker");
    ramps += named(r, "ramp") ? 1 : 0;
    if (named(r, "rate_random_walk")) {
      ++walks;
      show(r, "ramp named a walk", spec.seed);
    }
  }
  std::printf("ramp + flicker records (seeds 911..918): walk named %d, ramp named %d of %d\n",
              walks, ramps, kSeeds);
  EXPECT_EQ(walks, 0);
}

// A level shift of 2 GM sigmas at 60 % of the record: a step, or a time range, never a walk.
TEST(AnalyzeWalk, AStepIsNotAWalk) {
  int walks = 0;
  int steps = 0;
  for (int i = 0; i < kSeeds; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 921 + static_cast<std::uint64_t>(i));
    spec.step_time_s = 0.6 * static_cast<double>(spec.samples) / spec.fs_hz;
    spec.step_size = 3.0 * spec.b;
    const ia::Report r = analyse(spec, "step");
    steps += named(r, "bias_step") ? 1 : 0;
    if (named(r, "rate_random_walk")) {
      ++walks;
      show(r, "step named a walk", spec.seed);
    }
  }
  std::printf("step records (seeds 921..928): walk named %d, step named %d of %d\n", walks, steps,
              kSeeds);
  EXPECT_EQ(walks, 0);
  EXPECT_GE(steps, kSeeds - 1);
}

}  // namespace

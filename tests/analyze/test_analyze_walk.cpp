// What a rate random walk must not stand in for. A walk raises the ADEV at the long taus and
// the block means' likelihood of a walk; so do flicker (bias instability) seen over a few of
// its decades, a deterministic ramp, and a level shift part way through the record. The walk is
// named only where the record needs it beside them (the line, the step) and where it holds on
// both halves of the record. The first-order model of synth_cases.hpp, 10^6 samples at 100 Hz,
// plus one effect; seeds 911..928, 941..952 and 5101..5112 (no other test uses them); a
// quantized record with a fast GM and a step (seeds 961..976). And K's interval where a GM
// beside the walk is slow for the record (seeds 4401..4415). A GM slower than the record
// resolves is no walk; a walk beyond a GM the ADEV shows stays one (seeds 8601..8630). A step
// on a ramp (seeds 1201..1208); flicker's wander, no step (seeds 1211..1222).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/analyze/synth.hpp"
#include "imu/error_model.hpp"
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

// A bias step named within half_window_s of t_s, or an unexplained time range reaching there.
bool step_or_range_at(const ia::Report& r, double t_s, double half_window_s) {
  for (const ia::Effect& e : r.effects) {
    if (e.type == "bias_step" && std::fabs(e.time_s - t_s) <= half_window_s) {
      return true;
    }
  }
  for (const ia::UnexplainedRun& u : r.unexplained) {
    if (u.t_max_s > u.t_min_s && u.t_max_s >= t_s - half_window_s &&
        u.t_min_s <= t_s + half_window_s) {
      return true;
    }
  }
  return false;
}

void show(const ia::Report& r, const char* what, std::uint64_t seed) {
  std::printf("%s seed %llu:\n%s", what, static_cast<unsigned long long>(seed),
              ia::to_text(r).c_str());
}

// Step records tallied: a step named within half_window_s of the true time, a step or a time
// range there, a walk named (its report printed).
struct StepTally {
  int steps = 0;
  int at_it = 0;
  int walks = 0;
  void add(const ia::Report& r, const ia::SynthSpec& spec, double half_window_s) {
    for (const ia::Effect& e : r.effects) {
      steps += e.type == "bias_step" && std::fabs(e.time_s - spec.step_time_s) <= half_window_s
                   ? 1
                   : 0;
    }
    at_it += step_or_range_at(r, spec.step_time_s, half_window_s) ? 1 : 0;
    if (named(r, "rate_random_walk")) {
      ++walks;
      show(r, "step named a walk", spec.seed);
    }
  }
};

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
// (A walk the record's likelihood needs on its own, 2 ln LR 9 to 15 here, explains it as well
// on most seeds: a step or a walk's wander, an unexplained time range.)
TEST(AnalyzeWalk, AStepIsNotAWalk) {
  StepTally t;
  for (int i = 0; i < kSeeds; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 921 + static_cast<std::uint64_t>(i));
    const double t_rec_s = static_cast<double>(spec.samples) / spec.fs_hz;
    spec.step_time_s = 0.6 * t_rec_s;
    spec.step_size = 3.0 * spec.b;
    t.add(analyse(spec, "step"), spec, 0.05 * t_rec_s);
  }
  std::printf("step records (seeds 921..928): walk named %d, step named at it %d, a step or a "
              "time range at it %d of %d\n", t.walks, t.steps, t.at_it, kSeeds);
  EXPECT_EQ(t.walks, 0);
  EXPECT_GE(t.at_it, kSeeds - 1);
}

// A level shift of 2.5 B (1.5 GM sigmas) at 35 % of the record, near the least the record's
// likelihood detects: where a step is named at it (within 5 % of the record), the 95 % set of
// its time holds the true time. Printed: how many are named there, given an unexplained time
// range, or called a walk.
TEST(AnalyzeWalk, ASmallStepsTimeIntervalHoldsItsTime) {
  constexpr int kRecords = 12;
  int steps = 0;
  int ranges = 0;
  int walks = 0;
  int times_in = 0;
  for (int i = 0; i < kRecords; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 941 + static_cast<std::uint64_t>(i));
    const double t_rec_s = static_cast<double>(spec.samples) / spec.fs_hz;
    spec.step_time_s = 0.35 * t_rec_s;
    spec.step_size = 2.5 * spec.b;
    const ia::Report r = analyse(spec, "small_step");
    const double w0 = spec.step_time_s - 0.05 * t_rec_s;
    const double w1 = spec.step_time_s + 0.05 * t_rec_s;
    bool step = false;
    for (const ia::Effect& e : r.effects) {
      if (e.type != "bias_step" || e.time_s < w0 || e.time_s > w1) {
        continue;
      }
      step = true;
      for (const ia::ParamInterval& iv : e.ci95) {
        if (iv.name != "time_s") {
          continue;
        }
        times_in += iv.lo <= spec.step_time_s && spec.step_time_s <= iv.hi ? 1 : 0;
        std::printf("seed %llu: step at %.1f s named at %.1f s, 95 %% [%.1f, %.1f] s\n",
                    static_cast<unsigned long long>(spec.seed), spec.step_time_s, e.time_s,
                    iv.lo, iv.hi);
      }
    }
    bool range = false;
    for (const ia::UnexplainedRun& u : r.unexplained) {
      range = range || (u.t_max_s > u.t_min_s && u.t_max_s >= w0 && u.t_min_s <= w1);
    }
    steps += step ? 1 : 0;
    ranges += !step && range ? 1 : 0;
    walks += named(r, "rate_random_walk") ? 1 : 0;
  }
  std::printf("small step records (seeds 941..952): step named at it %d (its time inside its 95 %% "
              "set %d), an unexplained time range over it %d, walk named %d of %d\n",
              steps, times_in, ranges, walks, kRecords);
  EXPECT_GE(steps, kRecords / 2);
  EXPECT_GE(10 * times_in, 9 * steps);
}

// A quantized record at 975 Hz with a fast GM (Tp 2.4 s) and a level shift of 1.7e-4 (2 GM
// peak ADEVs) at 57 % of its 4300 s: beside such a short GM the shift raises the long taus as a
// walk would, and a walk explains the record about as well as the step (2 ln LR 11 to 20
// against 17 to 22 for the step; beside the walk the step 10 to 14, below its threshold 15.9).
// The GM + walk records below give the same figures with no step in them: a step or a walk's
// wander, which the record does not tell apart, an unexplained time range (a step named on 13
// of 16 before, which named a step on 10 of those 30 walk records).
TEST(AnalyzeWalk, AStepAWalkExplainsOnlyWithoutItIsAStep) {
  constexpr int kRecords = 16;
  StepTally t;
  for (int i = 0; i < kRecords; ++i) {
    ia::SynthSpec spec;
    spec.seed = 961 + static_cast<std::uint64_t>(i);
    spec.fs_hz = 975.0;
    spec.samples = std::size_t{1} << 22;
    spec.n = 6.6e-4;
    spec.b = 8e-5;
    spec.tp_s = 2.4;
    spec.q = 7.3e-5;
    const double t_rec_s = static_cast<double>(spec.samples) / spec.fs_hz;
    spec.step_time_s = 0.57 * t_rec_s;
    spec.step_size = 1.7e-4;
    ia::Options o;
    o.fs_hz = spec.fs_hz;
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(ia::synthesize(spec), "quantized_step", o, r, err)) << err;
    t.add(r, spec, 0.05 * t_rec_s);
  }
  std::printf("quantized step records (seeds 961..976): step named at it %d, a step or a time "
              "range at it %d, walk named %d of %d\n", t.steps, t.at_it, t.walks, kRecords);
  EXPECT_GE(t.at_it, 12);
  EXPECT_LE(t.walks, 1);  // seed 964: no step significant over the positions, a walk's 10.3
}

// The example's first-order model with synth's walk K = 1.4e-4 (imu-sim synth's defaults) over
// 1 and 2 h: the GM (Tb ~ 160 s) lies near T/40, the slowest the fit takes, and the walk
// dominates from ~40 s on. Where the fit places the GM elsewhere (at Tb < 3 s, or not at all),
// the walk takes its power: K came out 1.3 to 1.7 x the truth, and its interval, which knew only
// the chosen model's scatter, held the truth on 8 of the 13 records that name the walk. The
// cost's profile over K with a GM free beside it holds it on at least 90 %. A walk's wander
// gathered at one place was also named a step on 10 of the 30 records (the step beat the walk by
// AIC's 2 for its time, or showed no walk beside it); a step must now stand beside a walk the
// record needs on its own, and where it does not the shift is an unexplained time range: a
// step on 2 of 30 (1 h seed 4405 at 351 s and 2 h seed 4410, where the walk's 2 ln LR is 3.2
// and 5.4, below its level). Where the GM is not one the ADEV shows beside the walk, the record
// does not tell the walk from the first-order model's own GM slower than it resolves, and that
// GM stands in for it (slow_gm_for_walk: no walk named, the GM's Tb interval open above). The
// walk or that GM on at least 10 of 30, as the walk was before, when a rise without a peak was
// named a walk: on 12, the walk on 2 of them (2 h seeds 4404 and 4412, beside a GM the ADEV
// shows) and the GM on 10; the other 18 hold no walk, as before.
TEST(AnalyzeWalk, KsIntervalHoldsTheWalkBesideASlowGm) {
  int steps = 0;
  int walks = 0;
  int stand_in = 0;
  int k_in = 0;
  int records = 0;
  for (const double hours : {1.0, 2.0}) {
    for (std::uint64_t seed = 4401; seed <= 4415; ++seed) {
      ia::SynthSpec spec = tc::make_case("control", seed);
      spec.k = 1.4e-4;
      spec.samples = static_cast<std::size_t>(hours * 3600.0 * spec.fs_hz);
      const ia::Report r = analyse(spec, "walk_gm");
      ++records;
      steps += named(r, "bias_step") ? 1 : 0;
      stand_in += ia::gm_stands_in_for_walk(r) ? 1 : 0;
      std::printf("%.0f h seed %llu: walk %s, GMs %zu (Tb %.4g s), GM in its place %s\n", hours,
                  static_cast<unsigned long long>(seed),
                  named(r, "rate_random_walk") ? "yes" : "no", r.model_after.n_gm,
                  r.model_after.n_gm > 0 ? r.model_after.gm[0].tb_s : 0.0,
                  ia::gm_stands_in_for_walk(r) ? "yes" : "no");
      for (const ia::Effect& e : r.effects) {
        if (e.type != "rate_random_walk" || e.ci95.empty()) {
          continue;
        }
        ++walks;
        const ia::ParamInterval& iv = e.ci95.front();
        k_in += spec.k >= iv.lo && spec.k <= iv.hi ? 1 : 0;
        std::printf("%.0f h seed %llu: K %.4g, 95 %% [%.4g, %.4g]\n", hours,
                    static_cast<unsigned long long>(seed), e.k, iv.lo, iv.hi);
      }
    }
  }
  std::printf("GM + walk records (1 and 2 h, seeds 4401..4415): walk named on %d of %d, K inside "
              "its 95 %% interval on %d; one GM with Tb open above in its place on %d; a step "
              "named on %d\n",
              walks, records, k_in, stand_in, steps);
  EXPECT_GE(walks + stand_in, 10);
  EXPECT_GE(10 * k_in, 9 * walks);
  EXPECT_LE(steps, 3);
}

// A step of 3.8 GM sigmas at 30 % of a 1.5 h record beside a sinusoid of 75 s period and 4 GM
// sigmas (seeds 5101..5112): the step search runs before the sinusoid is in the model, and
// against white + GM alone the sinusoid raises the walk's 2 ln LR and the noise the step is
// measured against, so the shift may not stand beside that walk. With the model complete the
// shift is tried again (settle_unnamed_shifts): named on 6 of 12 (3 without that second try,
// the rest time ranges then). Seed 5110 names a walk beside the range (2 ln LR 7.7 with the
// shift out): a wrong name this rule does not remove.
TEST(AnalyzeWalk, AStepBesideASlowSinusoidIsTriedAgainWithTheWholeModel) {
  constexpr int kRecords = 12;
  StepTally t;
  for (int i = 0; i < kRecords; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 5101 + static_cast<std::uint64_t>(i));
    const double t_rec_s = 1.5 * 3600.0;
    spec.samples = static_cast<std::size_t>(t_rec_s * spec.fs_hz);
    spec.sin_a = 6e-3;
    spec.sin_f_hz = 0.0133;
    spec.step_time_s = 0.3 * t_rec_s;
    spec.step_size = 5.5e-3;
    t.add(analyse(spec, "step_beside_sinusoid"), spec, 0.05 * t_rec_s);
  }
  std::printf("step beside a slow sinusoid (seeds 5101..5112): step named at it %d, a step or a "
              "time range at it %d, walk named %d of %d\n", t.steps, t.at_it, t.walks,
              kRecords);
  EXPECT_GE(t.steps, 5);
  EXPECT_GE(t.at_it, 8);
  EXPECT_LE(t.walks, 1);
}

// White noise and one GM whose Tb is a sixth of the record (10^4 s at 100 Hz, Tb 1667 s: its
// ADEV peak lies at 3150 s, beyond T/10): over [Ts, T/10] a rise without a peak, from which a
// GM bounded to T/38 (the ADEV fit's bound, the walk test's H0) reverts many times too fast.
// The first-order model's own GM with a Tb the record does not bound above explains it as well
// as a walk; there is nothing beyond the base model to name (slow_gm_for_walk). Seeds
// 8601..8610: a walk named on none, no K in the model after (a walk named on 3 before: 8602,
// 8606 and 8610, beside a GM of Tb 0.1 to 0.7 s).
TEST(AnalyzeWalk, AGmSlowerThanTheRecordResolvesIsNoWalk) {
  constexpr int kRecords = 10;
  int walks = 0;
  int with_k = 0;
  for (int i = 0; i < kRecords; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 8601 + static_cast<std::uint64_t>(i));
    const double t_rec_s = static_cast<double>(spec.samples) / spec.fs_hz;
    spec.tp_s = imu::kGmPeakTauFactor * t_rec_s / 6.0;
    const ia::Report r = analyse(spec, "slow_gm");
    with_k += r.model_after.k > 0.0 ? 1 : 0;
    if (named(r, "rate_random_walk")) {
      ++walks;
      show(r, "slow GM named a walk", spec.seed);
    }
  }
  std::printf("white + one GM of Tb = T/6 (seeds 8601..8610): walk named %d, K in the model "
              "after %d of %d\n", walks, with_k, kRecords);
  EXPECT_EQ(walks, 0);
  EXPECT_EQ(with_k, 0);
}

// A GM the ADEV shows (Tp 100 s, peak ADEV 2e-3, dominating the model near its peak) and a walk
// rising beyond it (K = 2e-4: 3.7e-3 at T/10): the rise after the GM's peak is more than the
// first-order model holds and stays a walk. Seeds 8621..8630: named on 9 (as before).
TEST(AnalyzeWalk, AWalkBeyondAVisibleGmStaysAWalk) {
  constexpr int kRecords = 10;
  int walks = 0;
  for (int i = 0; i < kRecords; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 8621 + static_cast<std::uint64_t>(i));
    spec.tp_s = 100.0;
    spec.b = 2e-3;
    spec.k = 2e-4;
    const ia::Report r = analyse(spec, "visible_gm_walk");
    if (named(r, "rate_random_walk")) {
      ++walks;
    } else {
      show(r, "visible GM + walk named no walk", spec.seed);
    }
  }
  std::printf("GM of Tp 100 s + walk (seeds 8621..8630): walk named %d of %d\n", walks,
              kRecords);
  EXPECT_GE(walks, kRecords - 2);
}

// A short GM (peak ADEV 1.3e-5 at 4 s) at 200 Hz over 2^21 samples (10,486 s), a ramp rising
// 9 GM sigmas over the record and a level shift against it of 4.5 GM sigmas at 58 % of it:
// the ramp tilts the plain step profile (its best shift lands mid-ramp) and a walk explains a
// line plus a shift better than either alone. With the line fitted beside the step the pair is
// found: the step named at it and the ramp, no walk. Seeds 1201..1208.
TEST(AnalyzeWalk, AStepOnARampIsNamedWithTheRamp) {
  StepTally t;
  int ramps = 0;
  for (int i = 0; i < kSeeds; ++i) {
    ia::SynthSpec spec;
    spec.seed = 1201 + static_cast<std::uint64_t>(i);
    spec.fs_hz = 200.0;
    spec.samples = std::size_t{1} << 21;
    spec.n = 1e-4;
    spec.b = 1.3e-5;
    spec.tp_s = 4.0;
    const double t_rec_s = static_cast<double>(spec.samples) / spec.fs_hz;
    const double gm_sigma = spec.b / 0.6186;  // the GM's peak ADEV is 0.6186 sigma
    spec.ramp_r = 9.0 * gm_sigma / t_rec_s;
    spec.step_time_s = 0.58 * t_rec_s;
    spec.step_size = -4.5 * gm_sigma;
    const ia::Report r = tc::analyse_checked(ia::synthesize(spec), "ramp_step", spec.seed,
                                             spec.fs_hz);
    t.add(r, spec, 0.05 * t_rec_s);
    ramps += named(r, "ramp") ? 1 : 0;
  }
  std::printf("ramp + step records (seeds 1201..1208): step named at it %d, ramp named %d, walk "
              "named %d of %d\n", t.steps, ramps, t.walks, kSeeds);
  EXPECT_GE(t.steps, kSeeds - 1);
  EXPECT_GE(ramps, kSeeds - 1);
  EXPECT_EQ(t.walks, 0);
}

// Dominant bias instability (B = 5e-3, its flicker floor 3.7 x the GM's peak ADEV; 1.8 x 10^6
// samples at 100 Hz) and no step: flicker's wander gathers at places as a walk's does and raises the
// step profile there (to 19 to 23 against H0, over thresholds of 18); a shift is named a step
// only where it stands beside the bias instability the record needs (a step was named on seeds
// 1215 and 1217 before that check, and on 3 of 40 seeds 1211..1250). Seeds 1211..1222.
TEST(AnalyzeWalk, FlickersWanderIsNoStep) {
  constexpr int kRecords = 12;
  int steps = 0;
  for (int i = 0; i < kRecords; ++i) {
    ia::SynthSpec spec = tc::make_case("control", 1211 + static_cast<std::uint64_t>(i));
    spec.flicker_b = 5e-3;
    spec.samples = 1800000;
    const ia::Report r = analyse(spec, "flicker");
    if (named(r, "bias_step")) {
      ++steps;
      show(r, "flicker named a step", spec.seed);
    }
  }
  std::printf("flicker records (seeds 1211..1222): step named %d of %d\n", steps, kRecords);
  EXPECT_EQ(steps, 0);
}

}  // namespace

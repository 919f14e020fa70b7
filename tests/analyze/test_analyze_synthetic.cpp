// The analysis on synthetic channels: the first-order model plus one effect at a
// time, 10 seeds each (seeds 101..110; the "_alt" model 1..5; the thresholds were tuned on seeds
// >= 1000 with tune_analyze), 20 controls. True values come from synth_cases.hpp, not from the
// code under test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
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

constexpr std::uint64_t kSeeds[] = {1, 2, 3, 4, 5};  // the "_alt" model's generalisation check
// Seeds 101..110 and 201..220 for the acceptance counts (never used while tuning: tune_analyze
// ran seeds >= 1000).
constexpr std::uint64_t kFirst11 = 101;
constexpr int kSeeds11 = 10;

// The report on the record y of spec under the default options at its rate, its consistency
// checked.
ia::Report analyze_record(const std::vector<double>& y, const ia::SynthSpec& spec,
                          const std::string& name) {
  ia::Report r;
  std::string err;
  ia::Options o;
  o.fs_hz = spec.fs_hz;
  EXPECT_TRUE(ia::analyze(y, name, o, r, err)) << err;
  std::string why;
  EXPECT_TRUE(ia::report_consistent(r, why)) << name << " seed " << spec.seed << ": " << why
                                             << "\n" << ia::to_text(r);
  return r;
}

// The same on spec's own record.
ia::Report analyze_spec(const ia::SynthSpec& spec, const std::string& name) {
  const std::vector<double> y = ia::synthesize(spec);
  EXPECT_EQ(y.size(), spec.samples);
  return analyze_record(y, spec, name);
}

ia::Report run(const std::string& name, std::uint64_t seed) {
  return analyze_spec(tc::make_case(name, seed), name);
}

std::string describe(const ia::Report& r) { return ia::to_text(r); }

// The peak ADEV of m's first GM, and in tp_s the tau of that peak (0 without a GM).
double gm_peak(const imu::ModelParams& m, double& tp_s) {
  tp_s = m.n_gm > 0 ? imu::kGmPeakTauFactor * m.gm[0].tb_s : 0.0;
  return m.n_gm > 0 ? imu::kGmPeakAdevFactor * std::sqrt(m.gm[0].sb * m.gm[0].tb_s) : 0.0;
}

// Prints r's text under "<what> seed <seed>:" (a record a test's count missed).
void print_report(const std::string& what, std::uint64_t seed, const ia::Report& r) {
  std::printf("%s seed %llu:\n%s", what.c_str(), static_cast<unsigned long long>(seed),
              describe(r).c_str());
}

// Exactly one effect of the expected type (a false extra effect is as bad as a missed one).
const ia::Effect* single_effect(const ia::Report& r, const std::string& type) {
  EXPECT_EQ(r.effects.size(), 1U) << describe(r);
  if (r.effects.size() != 1U || r.effects[0].type != type) {
    ADD_FAILURE() << "expected one " << type << "\n" << describe(r);
    return nullptr;
  }
  return &r.effects[0];
}

// ADEV-visible effects: the augmented model must fit better on the same taus.
void expect_error_lower(const ia::Report& r) {
  EXPECT_LT(r.error_after.adev_rms_rel, r.error_before.adev_rms_rel) << describe(r);
  EXPECT_EQ(r.error_after.n_taus, r.error_before.n_taus);
}

// ---- One effect at a time, 10 seeds each (found with its parameter in tolerance on
// >= 9 of 10). A seed counts when the effect is named with its parameter in tolerance; a seed
// where anything else is named beside it is counted apart (printed), as a false extra effect.
// `extra` counts the reports that name an effect other than the expected one and a second GM;
// `second_gm` the reports whose model holds a second GM (named gauss_markov, as every model
// term is). A second GM is printed, not counted as a false effect: on the oscillation records
// the model used to take a fast GM (Tb ~ Ts) for what a too narrow band misses below 1 / f0
// (see OscillationWidthIsFittedToTheSpectrum).
struct Tally {
  int found = 0;
  int extra = 0;
  int second_gm = 0;
  int rms_lower = 0;
};

template <typename Pred>
Tally tally(const std::string& name, const std::string& type, Pred in_tolerance) {
  Tally t;
  for (int i = 0; i < kSeeds11; ++i) {
    const std::uint64_t seed = kFirst11 + static_cast<std::uint64_t>(i);
    const ia::Report r = run(name, seed);
    bool ok = false;
    std::size_t others = 0;
    bool gm2 = false;
    for (const auto& e : r.effects) {
      ok = ok || (e.type == type && in_tolerance(e));
      gm2 = gm2 || e.type == "gauss_markov";
      others += e.type != type && e.type != "gauss_markov" ? 1U : 0U;
    }
    t.found += ok ? 1 : 0;
    t.extra += others > 0 ? 1 : 0;
    t.second_gm += gm2 ? 1 : 0;
    t.rms_lower += r.error_after.adev_rms_rel < r.error_before.adev_rms_rel ? 1 : 0;
    if (!ok || r.effects.size() > 1) {
      print_report(name, seed, r);
    }
  }
  std::printf("%s: found in tolerance on %d of %d seeds, other effects beside it on %d, a second "
              "GM on %d, RMS error lower after on %d\n",
              name.c_str(), t.found, kSeeds11, t.extra, t.second_gm, t.rms_lower);
  return t;
}

TEST(AnalyzeSynthetic, Quantization) {
  const Tally t = tally("quantization", "quantization", [](const ia::Effect& e) {
    return std::fabs(e.q - tc::kQ) <= 0.25 * tc::kQ;  // target: within 25 %
  });
  EXPECT_GE(t.found, 9);
  EXPECT_LE(t.extra, 1);
}

// The named walk's K (0 if none).
double named_k(const ia::Report& r) {
  for (const auto& e : r.effects) {
    if (e.type == "rate_random_walk") {
      return e.k;
    }
  }
  return 0.0;
}

TEST(AnalyzeSynthetic, RateRandomWalk) {
  // The walk (K = 1e-3) crosses the white noise near 3 s and holds the ADEV up to T/10 beside
  // no GM the ADEV shows (the example's GM peaks at 300 s a tenth below it): a rise without a
  // peak, which the first-order model's own GM with a Tb the record does not bound above
  // explains as well as the walk. The record does not tell a GM slower than it resolves from a
  // walk where the record allows a GM that peaks inside T/4, and the base model's GM is no name
  // then (slow_gm_for_walk); where every GM it allows peaks beyond T/4 the walk is named.
  // Target: the walk's power in the model after on >= 9 of 10: a walk named with K within
  // 25 %, or none and one GM with Tb's interval open above (the walk, Tb = infinity, inside
  // it) whose drive sqrt(Sb), the walk's K at tau << Tb, is within 25 % of K. Now: 9 of 10,
  // the walk named on 7 (the GM on 101, 107, 110; seed 108 names the walk beside the
  // example's GM, which the ADEV shows there, with K 38 % low). When the GM always stood in
  // where the record did not tell them apart: the walk named on 1; before that rule, when a
  // rise without a peak was always a walk: named on 10 of 10.
  int held = 0;
  int walks = 0;
  int extra = 0;
  for (int i = 0; i < kSeeds11; ++i) {
    const std::uint64_t seed = kFirst11 + static_cast<std::uint64_t>(i);
    const ia::Report r = run("rate_random_walk", seed);
    const imu::ModelParams& m = r.model_after;
    bool ok = false;
    for (const auto& e : r.effects) {
      ok = ok || (e.type == "rate_random_walk" && std::fabs(e.k - tc::kK) <= 0.25 * tc::kK);
      walks += e.type == "rate_random_walk" ? 1 : 0;
      extra += e.type != "rate_random_walk" ? 1 : 0;
    }
    const double k_gm = m.n_gm > 0 ? std::sqrt(m.gm[0].sb) : 0.0;
    ok = ok || (ia::gm_stands_in_for_walk(r) && std::fabs(k_gm - tc::kK) <= 0.25 * tc::kK);
    held += ok ? 1 : 0;
    std::printf("rate_random_walk seed %llu: walk named %d, K %.4g, one GM's sqrt(Sb) %.4g, "
                "Tb %.4g s\n", static_cast<unsigned long long>(seed),
                named_k(r) > 0.0 ? 1 : 0, named_k(r), k_gm, m.n_gm > 0 ? m.gm[0].tb_s : 0.0);
    if (!ok) {
      print_report("rate_random_walk", seed, r);
    }
  }
  std::printf("rate_random_walk: the walk's power held on %d of %d (walk named on %d), other "
              "effects %d\n", held, kSeeds11, walks, extra);
  EXPECT_GE(held, 9);
  EXPECT_LE(extra, 1);
}

TEST(AnalyzeSynthetic, Ramp) {
  const Tally t = tally("ramp", "ramp", [](const ia::Effect& e) {
    return std::fabs(e.r - tc::kR) <= 0.25 * tc::kR;  // target: within 25 %
  });
  EXPECT_GE(t.found, 9);
  EXPECT_LE(t.extra, 1);
  EXPECT_GE(t.rms_lower, 9);
}

TEST(AnalyzeSynthetic, Sinusoid) {
  const Tally t = tally("sinusoid", "sinusoid", [](const ia::Effect& e) {
    return std::fabs(e.freq_hz - tc::kSinF) <= 0.05 * tc::kSinF &&    // target: 5 %
           std::fabs(e.amplitude - tc::kSinA) <= 0.25 * tc::kSinA;  // 25 %
  });
  EXPECT_GE(t.found, 9);
  EXPECT_LE(t.extra, 1);
  EXPECT_GE(t.rms_lower, 9);
}

TEST(AnalyzeSynthetic, NarrowbandOscillationIsNotASinusoid) {
  // A randomly driven, damped oscillation (a vibration mode; the ADIS16405 gyro_z carry one at
  // 20 Hz): named `oscillation`, not `sinusoid`, with its sigma and centre frequency.
  const Tally t = tally("oscillation", "oscillation", [](const ia::Effect& e) {
    return std::fabs(e.amplitude - tc::kOscSigma) <= 0.25 * tc::kOscSigma &&  // 25 %
           std::fabs(e.freq_hz - tc::kOscF0) <= 0.05 * tc::kOscF0;            // 5 %
  });
  EXPECT_GE(t.found, 9);
  EXPECT_LE(t.extra, 1);
  EXPECT_GE(t.rms_lower, 9);
}

// A record of white noise N = 3e-3 and a faint GM at 100 Hz (the terms under test are added).
ia::SynthSpec faint_gm_record(std::size_t samples, std::uint64_t seed) {
  ia::SynthSpec spec;
  spec.fs_hz = 100.0;
  spec.samples = samples;
  spec.n = 3e-3;
  spec.b = 1e-6;
  spec.tp_s = 10.0;
  spec.seed = seed;
  return spec;
}

// White noise N and a GM of peak ADEV b at tp_s, `samples` at 100 Hz.
ia::SynthSpec gm_record(std::size_t samples, std::uint64_t seed, double n, double b,
                        double tp_s) {
  ia::SynthSpec spec = faint_gm_record(samples, seed);
  spec.n = n;
  spec.b = b;
  spec.tp_s = tp_s;
  return spec;
}

// 1 if r has an effect of `type` whose 95 % interval `name` holds `truth`, else 0.
int interval_holds(const ia::Report& r, const std::string& type, const std::string& name,
                   double truth) {
  for (const auto& e : r.effects) {
    for (const auto& iv : e.ci95) {
      if (e.type == type && iv.name == name && iv.lo <= truth && truth <= iv.hi) {
        return 1;
      }
    }
  }
  return 0;
}

// An oscillation at fs / 5 (as the ADIS16405 gyros' 20 Hz band at 100 Hz), point-sampled: the
// ADEV of a record is that of sample means, which exceeds the continuous average's by
// ((pi f0 Ts) / sin(pi f0 Ts))^2 = 14 % in AVAR here. Fitted with the continuous shape, sigma
// came out 7 % high, far outside its interval; the sampled shape gives it within a few per cent.
TEST(AnalyzeSynthetic, OscillationAtAFifthOfTheRateKeepsItsSigma) {
  int inside = 0;
  int close = 0;
  for (std::uint64_t seed = 930001; seed <= 930004; ++seed) {
    ia::SynthSpec spec = faint_gm_record(1000000, seed);
    spec.osc_sigma = 0.02;
    spec.osc_f0_hz = 20.0;
    spec.osc_beta_per_s = 3.14159265358979323846 * 1.0;  // 1 Hz half-power width
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(ia::synthesize(spec), "osc", ia::Options{}, r, err)) << err;
    for (const auto& e : r.effects) {
      close += e.type == "oscillation" && std::fabs(e.amplitude / spec.osc_sigma - 1.0) <= 0.03
                   ? 1
                   : 0;
    }
    inside += interval_holds(r, "oscillation", "sigma", spec.osc_sigma);
  }
  std::printf("oscillation at fs / 5: sigma within 3 %% on %d of 4, inside its interval on %d\n",
              close, inside);
  EXPECT_GE(close, 3);
  EXPECT_GE(inside, 3);
}

// A point-sampled oscillation at fs / 7 (14.3 Hz at 100 Hz, half-power width 5 %, sigma three
// times the white std per sample), 2^20 samples, seeds 930101..930110: the analysis reads it as
// point samples or as a sensor's averages over each sample period, whichever fits the ADEV
// better, and the two readings of the same band differ by 3.5 % in sigma. Its interval holds
// the truth on at least 9 of 10 whichever reading it took.
TEST(AnalyzeSynthetic, AnOscillationsSigmaIntervalHoldsEitherSampling) {
  int inside = 0;
  int averaged = 0;
  for (std::uint64_t seed = 930101; seed <= 930110; ++seed) {
    ia::SynthSpec spec = faint_gm_record(1048576, seed);
    spec.osc_f0_hz = spec.fs_hz / 7.0;
    spec.osc_beta_per_s = 3.14159265358979323846 * 0.05 * spec.osc_f0_hz;
    spec.osc_sigma = 1.0 * spec.n * std::sqrt(spec.fs_hz);
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(ia::synthesize(spec), "osc", ia::Options{}, r, err)) << err;
    averaged += r.model_after.osc_sigma > 0.0 && !(r.model_after.osc_ts_s > 0.0) ? 1 : 0;
    const int in = interval_holds(r, "oscillation", "sigma", spec.osc_sigma);
    inside += in;
    if (in == 0) {
      print_report("oscillation at fs / 7", seed, r);
    }
  }
  std::printf("oscillation at fs / 7: read as averages on %d of 10, sigma inside its interval on "
              "%d\n", averaged, inside);
  EXPECT_GE(inside, 9);
}

// Oscillations of other centres and widths (3 to 12 Hz, half-power width 6 % to 20 % of f0):
// the width read off the half-power points of the Welch PSD came out 15-50 % narrow (the highest
// bin overstates the peak; the flanks that set the floor hold the band's tails), outside its
// interval, and the ADEV fit took a fast GM beside the band for what that narrower shape misses
// below 1 / f0 (named "a second GM"; the record's own GM then became the model's second). With
// the band's shape fitted to the PSD: width within 10 %, no second GM.
TEST(AnalyzeSynthetic, OscillationWidthIsFittedToTheSpectrum) {
  constexpr int kSeedsHere = 6;
  constexpr double kF0Hz[kSeedsHere] = {3.0, 4.5, 6.0, 8.0, 10.0, 12.0};
  constexpr double kWidthRel[kSeedsHere] = {0.2, 0.06, 0.12, 0.08, 0.15, 0.1};
  int close = 0;
  int inside = 0;
  int one_gm = 0;
  for (int i = 0; i < kSeedsHere; ++i) {
    ia::SynthSpec spec = faint_gm_record(1000000, 960101 + static_cast<std::uint64_t>(i));
    spec.b = 4e-4;  // a GM the ADEV shows (peak 0.13 of the white ADEV at Tp)
    spec.osc_sigma = 0.01;
    spec.osc_f0_hz = kF0Hz[i];
    const double width_hz = kWidthRel[i] * kF0Hz[i];
    spec.osc_beta_per_s = 3.14159265358979323846 * width_hz;
    const ia::Report r = analyze_spec(spec, "osc");
    std::string named;
    for (const auto& e : r.effects) {
      const bool osc = e.type == "oscillation";
      close += osc && std::fabs(e.bandwidth_hz / width_hz - 1.0) <= 0.1 ? 1 : 0;
      named += " " + e.type + (osc ? " " + std::to_string(e.bandwidth_hz) : "");
    }
    inside += interval_holds(r, "oscillation", "bandwidth_hz", width_hz);
    one_gm += r.model_after.n_gm == 1 ? 1 : 0;
    std::printf("f0 %.1f Hz, width %.3g Hz: GMs %zu, effects%s\n", kF0Hz[i], width_hz,
                r.model_after.n_gm, named.c_str());
  }
  std::printf("oscillation widths: within 10 %% on %d of %d, inside the interval on %d, one GM on "
              "%d\n", close, kSeedsHere, inside, one_gm);
  EXPECT_GE(close, kSeedsHere - 1);
  EXPECT_GE(inside, kSeedsHere - 2);
  EXPECT_GE(one_gm, kSeedsHere - 1);
}

// White noise and one GM whose ADEV peak (at 140 s, 0.6 of the white noise's ADEV there) lies
// beyond the first-order model's [Ts, 100 s]: the before-model's GM then sits at the shortest
// taus, where it can follow the slow wander of the overlapping estimates (EDF ~1e6), and the
// record's own GM came in beside it as "a second GM" (2 of these 24 seeds before the rule that
// a GM changing the model's ADEV by under unexplained_min_rel is not named; 0 with it). The
// truth has one GM: no effect, and the model after's one GM within 3x of the record's Tb (19
// of 24 before, 21 with it; the rest are records whose ADEV hardly shows the GM's peak).
TEST(AnalyzeSynthetic, ASlowGmOnlyBeyondTheFirstOrderRangeIsNotASecondGm) {
  int clean = 0;
  int near_tb = 0;
  constexpr int kSeedsHere = 24;
  for (std::uint64_t seed = 940001; seed < 940001 + kSeedsHere; ++seed) {
    ia::SynthSpec spec = faint_gm_record(4194304, seed);
    spec.fs_hz = 333.0;
    spec.n = 7e-4;
    spec.b = 3.4e-5;
    spec.tp_s = 140.0;
    ia::Options o;
    o.fs_hz = spec.fs_hz;
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(ia::synthesize(spec), "gm", o, r, err)) << err;
    clean += r.effects.empty() ? 1 : 0;
    const double tb_true_s = spec.tp_s / imu::kGmPeakTauFactor;
    near_tb += r.model_after.n_gm == 1 &&
                       std::fabs(std::log(r.model_after.gm[0].tb_s / tb_true_s)) < std::log(3.0)
                   ? 1
                   : 0;
    if (!r.effects.empty()) {
      print_report("slow GM", seed, r);
    }
  }
  std::printf("slow GM only: no effect on %d of %d, one GM within 3x of Tb on %d\n", clean,
              kSeedsHere, near_tb);
  EXPECT_GE(clean, kSeedsHere - 1);
  EXPECT_GE(near_tb, 20);
}

// A slow thermal cycle: a sinusoid of 8 or 10 periods in the record, twice the GM's peak ADEV,
// beside white noise and a GM peaking at 60 s (2^18 samples at 100 Hz, 2621 s). Its ADEV bump
// lies at 0.37 of its period, at or beyond T/10, where the first-order fit's GM takes it up:
// no residual run shows it, the periodogram's low band and the record's likelihood find it.
// Controls: the same records without the line, their GM peaking from T/40 to T/4 (a slow GM
// makes low-frequency peaks in the periodogram): no sinusoid.
TEST(AnalyzeSynthetic, ASlowThermalCycleIsASinusoidAndASlowGmIsNot) {
  constexpr std::size_t kSamples = 262144;
  const double t_rec = static_cast<double>(kSamples) / 100.0;
  int found = 0;
  constexpr int kSeedsHere = 6;
  for (std::uint64_t seed = 951201; seed < 951201 + kSeedsHere; ++seed) {
    ia::SynthSpec spec = gm_record(kSamples, seed, 3e-3, 3e-4, 60.0);
    spec.sin_f_hz = (seed % 2 == 0 ? 10.0 : 8.0) / t_rec;
    spec.sin_a = 6e-4;
    ia::Options o;
    o.fs_hz = spec.fs_hz;
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(ia::synthesize(spec), "thermal", o, r, err)) << err;
    bool ok = false;
    for (const auto& e : r.effects) {
      ok = ok || (e.type == "sinusoid" && std::fabs(e.freq_hz / spec.sin_f_hz - 1.0) <= 0.05 &&
                  std::fabs(e.amplitude / spec.sin_a - 1.0) <= 0.25);
    }
    found += ok ? 1 : 0;
    if (!ok) {
      print_report("thermal cycle", seed, r);
    }
  }
  int false_lines = 0;
  constexpr int kControls = 12;
  for (std::uint64_t seed = 951301; seed < 951301 + kControls; ++seed) {
    const double tp_s = t_rec / 40.0 * std::pow(10.0, static_cast<double>(seed % 4) / 3.0);
    const ia::SynthSpec spec = gm_record(kSamples, seed, 3e-3, 3e-4, tp_s);
    ia::Options o;
    o.fs_hz = spec.fs_hz;
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(ia::synthesize(spec), "slow gm", o, r, err)) << err;
    for (const auto& e : r.effects) {
      if (e.type == "sinusoid") {
        ++false_lines;
        print_report("slow GM, a sinusoid named", seed, r);
      }
    }
  }
  std::printf("thermal cycle: found on %d of %d; a sinusoid on %d of %d slow-GM records\n",
              found, kSeedsHere, false_lines, kControls);
  EXPECT_GE(found, kSeedsHere - 1);
  EXPECT_EQ(false_lines, 0);
}

// White noise N = 3.3e-4 and a GM peaking at 60 s, 2^20 samples at 100 Hz; with_q: quantization
// at 30 % of the white noise's AVAR at Ts (3 Q^2 / Ts^2 = 0.3 N^2 / Ts).
ia::SynthSpec q_record(std::uint64_t seed, bool with_q) {
  ia::SynthSpec spec = gm_record(1048576, seed, 3.3e-4, 4e-5, 60.0);
  spec.q = with_q ? spec.n * std::sqrt(0.3 / spec.fs_hz / 3.0) : 0.0;
  return spec;
}

// Counts r's quantization effects into named, and into close those whose model Q is within
// 10 % of q_true.
void count_q(const ia::Report& r, double q_true, int& named, int& close) {
  for (const auto& e : r.effects) {
    if (e.type == "quantization") {
      ++named;
      close += std::fabs(r.model_after.q / q_true - 1.0) <= 0.1 ? 1 : 0;
    }
  }
}

// Quantization at 30 % of the white noise's AVAR at Ts (dominant nowhere: that takes 2x) beside
// white noise and a GM: the model without Q misses the first taus, so Q is named, near its
// truth, and N keeps its interval (a Q dropped here leaves its AVAR to N, which then runs
// high). At 10 % Q is kept on 2 of these 6 seeds: the rule also asks the RMS and max errors
// over [Ts, T/10] to rise without it, and those are set by the long taus' scatter.
TEST(AnalyzeSynthetic, QuantizationBesideLargerWhiteNoiseIsKept) {
  int named = 0;
  int q_close = 0;
  int n_inside = 0;
  constexpr int kSeedsHere = 6;
  for (std::uint64_t seed = 950101; seed < 950101 + kSeedsHere; ++seed) {
    const ia::SynthSpec spec = q_record(seed, true);
    const ia::Report r = analyze_spec(spec, "q");
    count_q(r, spec.q, named, q_close);
    ASSERT_FALSE(r.model_after_ci95.empty());
    const ia::ParamInterval& n = r.model_after_ci95.front();
    n_inside += n.name == "n" && n.lo <= spec.n && spec.n <= n.hi ? 1 : 0;
  }
  std::printf("Q beside larger white noise: named on %d of %d, within 10 %% on %d, N inside its "
              "interval on %d\n",
              named, kSeedsHere, q_close, n_inside);
  EXPECT_GE(named, kSeedsHere - 1);
  EXPECT_GE(q_close, kSeedsHere - 1);
  EXPECT_GE(n_inside, kSeedsHere - 2);
}

// The same beside a narrowband oscillation (8 Hz, 10 % of f0 wide), with controls without Q.
// Quantization used to be exempt from the rule there: with the band's width read off the PSD's
// half-power points, what the band's shape missed at the shortest taus lowered the cost as Q
// would, and Q was named on records without it. With the band fitted to the spectrum the
// exemption is gone: Q kept where present, not named where absent.
TEST(AnalyzeSynthetic, QuantizationBesideAnOscillation) {
  int named = 0;
  int q_close = 0;
  int false_q = 0;
  constexpr int kSeedsHere = 6;
  for (std::uint64_t seed = 970101; seed < 970101 + kSeedsHere; ++seed) {
    for (const bool with_q : {true, false}) {
      ia::SynthSpec spec = q_record(seed, with_q);
      spec.osc_sigma = 0.002;  // 0.6 x the white std per sample
      spec.osc_f0_hz = 8.0;
      spec.osc_beta_per_s = 3.14159265358979323846 * 0.8;
      const ia::Report r = analyze_spec(spec, "q");
      if (with_q) {
        count_q(r, spec.q, named, q_close);
      } else {
        false_q += static_cast<int>(std::count_if(r.effects.begin(), r.effects.end(),
                                                  [](const ia::Effect& e) {
                                                    return e.type == "quantization";
                                                  }));
      }
    }
  }
  std::printf("Q beside an oscillation: named on %d of %d, within 10 %% on %d; named without it "
              "on %d of %d\n",
              named, kSeedsHere, q_close, false_q, kSeedsHere);
  EXPECT_GE(named, kSeedsHere - 2);
  EXPECT_GE(q_close, kSeedsHere - 2);
  EXPECT_EQ(false_q, 0);
}

TEST(AnalyzeSynthetic, BiasStep) {
  const double record_s = 1e6 / 100.0;
  const Tally t = tally("bias_step", "bias_step", [record_s](const ia::Effect& e) {
    return std::fabs(e.time_s - tc::kStepTime) <= 0.02 * record_s &&  // 2 % of T
           std::fabs(e.size - tc::kStepSize) <= 0.25 * tc::kStepSize;  // 25 %
  });
  EXPECT_GE(t.found, 9);
  EXPECT_LE(t.extra, 1);
}

TEST(AnalyzeSynthetic, Outliers) {
  const Tally t = tally("outliers", "outliers", [](const ia::Effect& e) {
    return std::fabs(static_cast<double>(e.count) - static_cast<double>(tc::kOutliers)) <=
           0.2 * static_cast<double>(tc::kOutliers);  // target: within 20 %
  });
  EXPECT_GE(t.found, 9);
  EXPECT_LE(t.extra, 1);
}

// A delta-velocity style record: every value on a coarse lattice (white noise a third of a
// step) offset by gravity, with the floating-point residue of offset + k q. Finite data always
// gets a report; the lattice is found; samples one step from the usual level are not outliers
// (before: the innovations' robust scale saw only the fraction of a step most of them are, and
// tens of thousands of samples were "outliers", or the term search found no usable ADEV point
// and the analysis stopped with no report).
TEST(AnalyzeSynthetic, CoarseLatticeWithAnOffsetGetsAReportWithoutFalseOutliers) {
  struct Case {
    double q;
    double offset;
    std::uint64_t seed;
  };
  for (const Case c : {Case{0.0024525, -9.80665, 7301}, Case{0.001, 9.80665, 7302}}) {
    constexpr double kFs = 100.0;
    constexpr std::size_t kN = 360000;  // 1 h
    std::mt19937_64 rng(c.seed);
    std::normal_distribution<double> g(0.0, 1.0);
    const double white_sd = 0.3 * c.q;
    const double a = std::exp(-1.0 / (kFs * 100.0));  // GM, Tb = 100 s, sigma 0.15 q
    const double gm_sd = 0.15 * c.q * std::sqrt(1.0 - a * a);
    double b = 0.0;
    std::vector<double> y(kN);
    for (double& v : y) {
      b = a * b + gm_sd * g(rng);
      v = c.offset + std::round((b + white_sd * g(rng)) / c.q) * c.q;
    }
    ia::Options o;
    o.fs_hz = kFs;
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(y, "acc_z", o, r, err)) << "q " << c.q << ": " << err;
    std::string why;
    EXPECT_TRUE(ia::report_consistent(r, why)) << "q " << c.q << ": " << why;
    EXPECT_NEAR(r.lsb, c.q, 0.01 * c.q) << r.lsb_note;
    for (const ia::Effect& e : r.effects) {
      if (e.type == "outliers") {
        EXPECT_LE(e.count, 10U) << "q " << c.q << "\n" << describe(r);
      }
    }
  }
}

// Generalisation: the same thresholds on another first-order model and a shorter record.
TEST(AnalyzeSynthetic, OtherModelControlAndEffects) {
  const double record_s = 3e5 / 100.0;
  for (const auto seed : kSeeds) {
    const ia::Report c = run("control_alt", seed);
    EXPECT_TRUE(c.effects.empty()) << "seed " << seed << "\n" << describe(c);

    const ia::Report s = run("sinusoid_alt", seed);
    if (const ia::Effect* e = single_effect(s, "sinusoid")) {
      EXPECT_NEAR(e->freq_hz, tc::kAltSinF, 0.05 * tc::kAltSinF);    // target: 5 %
      EXPECT_NEAR(e->amplitude, tc::kAltSinA, 0.25 * tc::kAltSinA);  // target: 25 %
    }
    expect_error_lower(s);

    const ia::Report st = run("bias_step_alt", seed);
    if (const ia::Effect* e = single_effect(st, "bias_step")) {
      EXPECT_NEAR(e->time_s, tc::kAltStepTime, 0.02 * record_s);          // 2 % of T
      EXPECT_NEAR(e->size, tc::kAltStepSize, 0.25 * tc::kAltStepSize);    // 25 %
    }

    const ia::Report o = run("outliers_alt", seed);
    if (const ia::Effect* e = single_effect(o, "outliers")) {
      EXPECT_NEAR(static_cast<double>(e->count), static_cast<double>(tc::kAltOutliers),
                  0.2 * static_cast<double>(tc::kAltOutliers));  // 20 %
    }

    const ia::Report r = run("ramp_alt", seed);
    if (const ia::Effect* e = single_effect(r, "ramp")) {
      EXPECT_NEAR(e->r, tc::kAltR, 0.25 * tc::kAltR);  // 25 %
    }
    expect_error_lower(r);
  }
}

// ---- The long-tau family, dropouts and an effect the analysis has no term for.

bool is_named(const ia::Report& r, const std::string& type) {
  for (const auto& e : r.effects) {
    if (e.type == type) {
      return true;
    }
  }
  return false;
}

TEST(AnalyzeSynthetic, BiasInstabilityIsFoundWithBWithin30Percent) {
  int found = 0;
  int wrong_name = 0;  // a walk, ramp or step named for flicker
  for (int i = 0; i < kSeeds11; ++i) {
    const ia::Report r = run("bias_instability", kFirst11 + static_cast<std::uint64_t>(i));
    bool ok = false;
    for (const auto& e : r.effects) {
      ok = ok || (e.type == "bias_instability" && std::fabs(e.b - tc::kBi) <= 0.3 * tc::kBi);
    }
    found += ok ? 1 : 0;
    wrong_name += is_named(r, "rate_random_walk") || is_named(r, "ramp") ||
                          is_named(r, "bias_step")
                      ? 1
                      : 0;
    if (!ok || r.effects.size() > 1) {
      const std::uint64_t seed = kFirst11 + static_cast<std::uint64_t>(i);
      print_report("bias instability", seed, r);
    }
  }
  std::printf("bias instability: B within 30 %% on %d of %d seeds; a walk, ramp or step named "
              "on %d\n", found, kSeeds11, wrong_name);
  EXPECT_GE(found, 9);       // target: >= 9 of 10, B within 30 %
  EXPECT_LE(wrong_name, 1);
}

TEST(AnalyzeSynthetic, StepOfThreeGmSigmasLateInALongRecordIsAStep) {
  const double record_s = static_cast<double>(tc::kStep3Samples) / 100.0;
  int found = 0;
  int extra = 0;  // further effects beside the step
  for (int i = 0; i < kSeeds11; ++i) {
    const ia::Report r = run("bias_step_3sigma", kFirst11 + static_cast<std::uint64_t>(i));
    bool ok = false;
    for (const auto& e : r.effects) {
      ok = ok || (e.type == "bias_step" &&
                  std::fabs(e.time_s - tc::kStep3Time) <= 0.02 * record_s);  // target: 2 %
    }
    found += ok ? 1 : 0;
    extra += r.effects.size() > 1 ? 1 : 0;
    EXPECT_FALSE(is_named(r, "rate_random_walk") || is_named(r, "bias_instability"))
        << describe(r);
  }
  std::printf("3-sigma step at 80 %% of a 20,000 s record: found (time within 2 %%) on %d of %d; "
              "other effects beside it on %d\n", found, kSeeds11, extra);
  EXPECT_GE(found, 9);
}

// A step's size interval is its GLS standard error times 1.96 (|size| / |z|, z the statistic
// in either detector's units; seeds 421..430): the true size lies inside it on all but at most
// 2 of those named (a 95 % interval misses more than 2 of 8 to 10 with probability under 1 %).
// A step that does not stand beside a walk the record needs is a time range, not named.
TEST(AnalyzeSynthetic, StepSizeIntervalHoldsTheTrueSize) {
  int named = 0;
  int inside = 0;
  for (std::uint64_t seed = 421; seed <= 430; ++seed) {
    const ia::Report r = run("bias_step_3sigma", seed);
    for (const auto& e : r.effects) {
      if (e.type != "bias_step" || e.ci95.empty()) {
        continue;
      }
      ++named;
      const ia::ParamInterval& iv = e.ci95.front();
      inside += tc::kStep3Size >= iv.lo && tc::kStep3Size <= iv.hi ? 1 : 0;
      std::printf("step seed %llu: size %.4g in [%.4g, %.4g] (|z| %.1f)\n",
                  static_cast<unsigned long long>(seed), tc::kStep3Size, iv.lo, iv.hi,
                  e.statistic);
    }
  }
  std::printf("3-sigma step: the true size inside the 95 %% interval on %d of %d named\n", inside,
              named);
  EXPECT_GE(named, 8);
  EXPECT_GE(inside, named - 2);
}

// A step of 20 white-noise sds between block boundaries (at 6000.37 s: sample 600037) beside a
// GM of 2 s, 2^20 samples at 100 Hz (seeds 990301..990304). The window detector finds it at a
// boundary of its blocks (16 samples and more); the step is placed at its sample, and the
// before-model's innovations at the step's first samples (the filter still predicted the old
// level) are not reported as outliers. Before, those samples were outliers replaced by the
// filter's old level: the step was found 0.2-0.4 s late, 17 % small, and 27-43 outliers named.
TEST(AnalyzeSynthetic, ALargeStepIsPlacedToItsSampleAndLeavesNoOutliers) {
  int placed = 0;
  int outliers = 0;
  for (std::uint64_t seed = 990301; seed <= 990304; ++seed) {
    ia::SynthSpec spec = gm_record(1048576, seed, 1e-3, 2e-4, 2.0);
    spec.step_time_s = 6000.37;
    spec.step_size = 20.0 * spec.n * std::sqrt(spec.fs_hz);
    const double first_after_s = std::ceil(spec.step_time_s * spec.fs_hz) / spec.fs_hz;
    const ia::Report r = analyze_spec(spec, "large_step");
    bool ok = false;
    for (const auto& e : r.effects) {
      ok = ok || (e.type == "bias_step" && std::fabs(e.time_s - first_after_s) <= 0.015);
    }
    placed += ok ? 1 : 0;
    outliers += is_named(r, "outliers") ? 1 : 0;
    if (!ok || is_named(r, "outliers")) {
      print_report("large step", seed, r);
    }
  }
  std::printf("large step: placed within one sample on %d of 4, outliers named on %d\n", placed,
              outliers);
  EXPECT_EQ(placed, 4);
  EXPECT_EQ(outliers, 0);
}

// A flicker floor far above the white noise and a faint GM (B = 0.01, N = 0.003, 2e6 samples
// at 100 Hz; seeds 900001..900006). Where the record's likelihood requires bias instability,
// it stays named even where its bank (within a few % of the ideal floor) and one realisation
// leave a residual run: the run is unexplained beside it. Removing it for that run left a
// model that missed the ADEV by up to 94 % (3 of these 6 seeds before). B's 95 % interval
// holds the true B: its bank reaches down to where the floor begins (1e-3 T/10 here), so the
// fit need not raise B to fill the ADEV between the white noise and a bank cut at 1e-2 T/10
// (B +2 % to +15 %, the interval holding it on 2 of these 6 seeds).
TEST(AnalyzeSynthetic, ADominantFlickerTheRecordRequiresStaysNamed) {
  int named = 0;
  int inside = 0;
  for (std::uint64_t seed = 900001; seed <= 900006; ++seed) {
    ia::SynthSpec spec = faint_gm_record(2000000, seed);
    spec.flicker_b = 1e-2;
    ia::Report r;
    std::string err;
    ASSERT_TRUE(ia::analyze(ia::synthesize(spec), "flicker", ia::Options{}, r, err)) << err;
    std::string why;
    EXPECT_TRUE(ia::report_consistent(r, why)) << why;
    const bool ok = is_named(r, "bias_instability") && !is_named(r, "rate_random_walk");
    named += ok ? 1 : 0;
    inside += interval_holds(r, "bias_instability", "b", spec.flicker_b);
    EXPECT_LE(r.error_after.adev_max_rel, r.error_before.adev_max_rel) << describe(r);
    if (!ok) {
      print_report("flicker", seed, r);
    }
  }
  std::printf("dominant flicker: bias_instability named (no walk) on %d of 6, B inside its "
              "95 %% interval on %d\n", named, inside);
  EXPECT_GE(named, 5);
  EXPECT_GE(inside, 4);
}

// A ramp under flicker: over [Ts, T/10] a line plus flicker's long excursions is a walk's
// curve too, and the walk's likelihood beside a GM alone rises with both. White noise, a GM
// peaking at 8 s, B = 1.4e-3 and R = sqrt(2) x 2e-4 per T/300 (the ramp dominates from about
// T/100), 2^20 samples at 100 Hz: the walk must not be named, the ramp and B should be.
TEST(AnalyzeSynthetic, ARampUnderFlickerIsNotAWalk) {
  int walk = 0;
  int ramp = 0;
  int flicker = 0;
  for (std::uint64_t seed = 980101; seed <= 980106; ++seed) {
    ia::SynthSpec spec = gm_record(1048576, seed, 2.6e-3, 2e-4, 8.0);
    spec.flicker_b = 1.4e-3;
    const double t_rec_s = static_cast<double>(spec.samples) / spec.fs_hz;
    spec.ramp_r = std::sqrt(2.0) * spec.b / (t_rec_s / 300.0);
    const ia::Report r = analyze_spec(spec, "ramp_flicker");
    walk += is_named(r, "rate_random_walk") ? 1 : 0;
    ramp += is_named(r, "ramp") ? 1 : 0;
    flicker += is_named(r, "bias_instability") ? 1 : 0;
    if (is_named(r, "rate_random_walk") || !is_named(r, "ramp")) {
      print_report("ramp under flicker", seed, r);
    }
  }
  std::printf("ramp under flicker: walk named on %d of 6, ramp on %d, bias instability on %d\n",
              walk, ramp, flicker);
  EXPECT_EQ(walk, 0);
  EXPECT_GE(ramp, 5);
  EXPECT_GE(flicker, 4);
}

// A ramp that dominates the ADEV from T/100 beside what bends a straight line's record: a rate
// random walk (K = 2e-5, a third of the ramp's ADEV at T/10), or a warm-up transient (a level
// of 0.01 decaying with a time constant of 300 s from the start); N = 3e-3, a GM of peak ADEV
// 3e-4 at 50 s, R = 1e-6, 2^21 samples at 100 Hz (seeds 990401..990404 each). The ramp is named, R
// inside its interval: its bend check's null holds a walk of any K and the start's decay.
// Before, the check's null had neither and the ramp was withdrawn as bending on 4 of these 8.
TEST(AnalyzeSynthetic, ARampBesideAWalkOrAWarmUpTransientIsNamed) {
  constexpr double kWarmUpA = 0.01;
  int named = 0;
  int inside = 0;
  for (std::uint64_t seed = 990401; seed <= 990404; ++seed) {
    for (const bool walk : {true, false}) {
      ia::SynthSpec spec = gm_record(2097152, seed, 3e-3, 3e-4, 50.0);
      spec.ramp_r = 1e-6;
      spec.k = walk ? 2e-5 : 0.0;
      std::vector<double> y = ia::synthesize(spec);
      if (!walk) {
        for (std::size_t i = 0; i < y.size(); ++i) {
          y[i] += kWarmUpA * std::exp(-static_cast<double>(i) / spec.fs_hz / 300.0);
        }
      }
      const ia::Report r = analyze_record(y, spec, "ramp_bent");
      named += is_named(r, "ramp") ? 1 : 0;
      inside += interval_holds(r, "ramp", "r", spec.ramp_r);
      if (!is_named(r, "ramp")) {
        print_report(walk ? "ramp beside a walk" : "ramp after a warm-up", seed, r);
      }
    }
  }
  std::printf("ramp beside a walk or a warm-up transient: named on %d of 8, R inside on %d\n",
              named, inside);
  EXPECT_GE(named, 7);
  EXPECT_GE(inside, 6);
}

// Flicker beside white noise at 400 Hz, a faint GM, 2^20 samples, the flicker generated as a
// sampled 1/f sequence (Kasdin's, no anti-alias filter): at tau = Ts its AVAR is 1.44 x the
// floor (0.64 B^2 against 0.44 B^2), an excess that falls off within a few samples and that the
// white noise takes. The model's bank also stops a decade or more above Ts, the white noise
// taking the flicker's AVAR below it, so N comes out high against a Gauss-Newton interval of
// about +-0.2 %. N's interval also holds the readings with the bank down below Ts and with the
// flicker a sampled sequence. B twice N (the excess 0.2 % of the white AVAR at Ts) and 6 x N
// (1.8 %).
TEST(AnalyzeSynthetic, WhiteNoiseAndFlickerIntervalsHoldBesideStrongFlicker) {
  for (const double n_white : {6e-4, 2e-4}) {
    int n_in = 0;
    int b_in = 0;
    int b_named = 0;
    for (std::uint64_t seed = 990201; seed <= 990206; ++seed) {
      ia::SynthSpec spec = gm_record(1048576, seed, n_white, 1e-5, 8.0);
      spec.fs_hz = 400.0;
      spec.flicker_b = 1.2e-3;
      const ia::Report r = analyze_spec(spec, "strong_flicker");
      ASSERT_FALSE(r.model_after_ci95.empty());
      const ia::ParamInterval& n = r.model_after_ci95.front();
      const int in = spec.n >= n.lo && spec.n <= n.hi ? 1 : 0;
      n_in += in;
      b_named += is_named(r, "bias_instability") ? 1 : 0;
      b_in += interval_holds(r, "bias_instability", "b", spec.flicker_b);
      std::printf("strong flicker, N %.0e, seed %llu: N in [%.5g, %.5g]: %s\n", n_white,
                  static_cast<unsigned long long>(seed), n.lo, n.hi, in ? "yes" : "no");
    }
    std::printf("strong flicker, N %.0e: N inside its 95 %% interval on %d of 6, B named on %d, "
                "inside on %d\n", n_white, n_in, b_named, b_in);
    EXPECT_GE(n_in, 5);
    EXPECT_GE(b_named, 5);
    EXPECT_GE(b_in, 4);
  }
}

// A band narrower than the spectrum's resolution shows a line: white noise (sd 0.05 per
// sample), a GM peaking at 36 s and a faint oscillation (sigma 6 % of the white sd) at 0.2 Hz
// whose half-power width is 1.5 % of f0 (correlation time 106 s), 2^22 samples at 100 Hz. Its
// amplitude and phase wander over the record, so it is not named a sinusoid (what it leaves
// is unexplained).
TEST(AnalyzeSynthetic, ABandNarrowerThanTheSpectrumIsNotASinusoid) {
  int sine = 0;
  for (std::uint64_t seed = 990101; seed <= 990106; ++seed) {
    ia::SynthSpec spec = gm_record(4194304, seed, 5e-3, 1e-4, 36.0);
    spec.osc_sigma = 3e-3;
    spec.osc_f0_hz = 0.2;
    spec.osc_beta_per_s = 3.14159265358979323846 * 0.015 * spec.osc_f0_hz;
    const ia::Report r = analyze_spec(spec, "narrow_band");
    if (is_named(r, "sinusoid")) {
      ++sine;
      print_report("narrow band", seed, r);
    }
  }
  std::printf("band 1.5 %% of f0 wide: named a sinusoid on %d of 6\n", sine);
  EXPECT_EQ(sine, 0);
}

TEST(AnalyzeSynthetic, TwentyControlsGiveNoEffect) {
  int clean = 0;
  for (std::uint64_t seed = 201; seed <= 220; ++seed) {
    const ia::Report r = run("control", seed);
    clean += r.effects.empty() ? 1 : 0;
    if (!r.effects.empty()) {
      print_report("control", seed, r);
    }
  }
  std::printf("controls without an effect: %d of 20\n", clean);
  EXPECT_GE(clean, 19);  // target: >= 19 of 20
}

// The types of a report's effects.
std::set<std::string> effect_types(const ia::Report& r) {
  std::set<std::string> t;
  for (const auto& e : r.effects) {
    t.insert(e.type);
  }
  return t;
}

TEST(AnalyzeSynthetic, NanDropoutsGiveTheControlsAnswer) {
  int same = 0;
  for (int i = 0; i < kSeeds11; ++i) {
    const std::uint64_t seed = kFirst11 + static_cast<std::uint64_t>(i);
    const ia::Report c = run("control", seed);
    const ia::Report r = run("control_nan", seed);
    EXPECT_EQ(r.gap_samples, 5000U);  // five dropouts of 1000 samples (synth_cases.hpp)
    EXPECT_EQ(r.gap_runs, 5U);
    const std::set<std::string> tc_types = effect_types(c);
    const std::set<std::string> tn_types = effect_types(r);
    same += tc_types == tn_types ? 1 : 0;
    if (tc_types != tn_types) {
      std::printf("seed %llu differs:\n%s", static_cast<unsigned long long>(seed),
                  describe(r).c_str());
    }
  }
  std::printf("NaN dropouts: the control's answer on %d of %d\n", same, kSeeds11);
  EXPECT_GE(same, 9);
}

TEST(AnalyzeSynthetic, AnEffectWithoutATermIsUnexplainedNotAWrongName) {
  // A random walk of the drift rate (AVAR ~ tau^3): no term of the analysis has that shape.
  int honest = 0;
  for (int i = 0; i < kSeeds11; ++i) {
    const ia::Report r = run("drift_walk", kFirst11 + static_cast<std::uint64_t>(i));
    bool named = false;
    for (const auto& e : r.effects) {
      named = named || e.type != "outliers";
    }
    const bool ok = !named && !r.unexplained.empty();
    honest += ok ? 1 : 0;
    if (!ok) {
      const std::uint64_t seed = kFirst11 + static_cast<std::uint64_t>(i);
      print_report("drift walk", seed, r);
    }
  }
  std::printf("drift walk: unexplained and no wrong name on %d of %d\n", honest, kSeeds11);
  EXPECT_GE(honest, 9);
}

// A sawtooth: the level ramps up by `height` over each period and drops back (periodic resets,
// stick-slip). Its drops are level shifts far above the noise at every period: naming a few of
// them bias steps would leave the rest unsaid. Periods 40, 50 and 63 s in white noise and a GM
// (4000 s at 100 Hz, height 2 x the white noise's std per sample; seeds 990401..990403).
TEST(AnalyzeSynthetic, RepeatedResetsAreOneUnexplainedTimeRangeNotSteps) {
  const double periods_s[] = {40.0, 50.0, 63.0};
  int honest = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const ia::SynthSpec spec = gm_record(400000, 990401 + i, 1e-3, 1.2e-3, 95.0);
    std::vector<double> y = ia::synthesize(spec);
    const double height = 2.0 * spec.n * std::sqrt(spec.fs_hz);
    const auto period = static_cast<std::size_t>(periods_s[i] * spec.fs_hz);
    for (std::size_t k = 0; k < y.size(); ++k) {
      y[k] += height * static_cast<double>(k % period) / static_cast<double>(period);
    }
    const ia::Report r = analyze_record(y, spec, "sawtooth");
    const double t_s = static_cast<double>(y.size()) / spec.fs_hz;
    bool spans = false;
    for (const auto& u : r.unexplained) {
      spans = spans || (u.t_max_s - u.t_min_s >= 0.5 * t_s);
    }
    const bool ok = !is_named(r, "bias_step") && spans;
    honest += ok ? 1 : 0;
    if (!ok) {
      print_report("sawtooth", spec.seed, r);
    }
  }
  std::printf("sawtooth: no step named and one time range over half the record on %d of 3\n",
              honest);
  EXPECT_EQ(honest, 3);
}

// A step far above the noise (5 x the white noise's std per sample, 26 GM sigmas) beside a GM:
// the model after is fitted to the record without the step and describes it. The before-model,
// fitted to the record with the step in it, is no stand-in there: on the record without the
// step its GM is the step's (error above 100 %). Seeds 990411..990413.
TEST(AnalyzeSynthetic, AfterALargeStepTheModelIsTheRecordsWithoutIt) {
  int kept = 0;
  for (std::uint64_t seed = 990411; seed <= 990413; ++seed) {
    ia::SynthSpec spec = gm_record(200000, seed, 1e-3, 1.2e-3, 95.0);
    spec.step_time_s = 1000.0;
    spec.step_size = 5.0 * spec.n * std::sqrt(spec.fs_hz);
    const ia::Report r = analyze_spec(spec, "large_step_model");
    const double tb_true = spec.tp_s / imu::kGmPeakTauFactor;
    const double tb = r.model_after.n_gm > 0 ? r.model_after.gm[0].tb_s : 0.0;
    const bool ok = is_named(r, "bias_step") && tb > 0.5 * tb_true && tb < 2.0 * tb_true &&
                    r.error_after.adev_rms_rel < 0.2;
    kept += ok ? 1 : 0;
    if (!ok) {
      print_report("large step, model after", seed, r);
    }
  }
  std::printf("large step: the GM's Tb within a factor 2 and RMS error after < 0.2 on %d of 3\n",
              kept);
  EXPECT_EQ(kept, 3);
}

// Faults of the recording: a frozen output (30 s of one repeated value) is taken as missing and
// leaves N as the record without it gives; a clipped output (every value below the mean less
// two stds of the white noise held there) is an unexplained time range. Neither is seen on the
// same records as recorded, nor on them rounded to a lattice of 3 x the white std (where the
// level dwells on one value for a while). 200000 samples at 100 Hz, seeds 990421..990423.
TEST(AnalyzeSynthetic, AFrozenOutputIsMissingAndAClippedOneIsSaid) {
  const auto has_note = [](const ia::Report& r, const char* what) {
    return std::any_of(r.notes.begin(), r.notes.end(),
                       [&](const std::string& n) { return n.find(what) != std::string::npos; });
  };
  int right = 0;
  for (std::uint64_t seed = 990421; seed <= 990423; ++seed) {
    const ia::SynthSpec spec = gm_record(200000, seed, 1e-3, 1.2e-3, 95.0);
    const std::vector<double> y = ia::synthesize(spec);
    const double sd = spec.n * std::sqrt(spec.fs_hz);
    std::vector<double> frozen = y;
    std::fill(frozen.begin() + 120000, frozen.begin() + 123000, frozen[120000]);
    double mean = 0.0;
    for (const double v : y) {
      mean += v / static_cast<double>(y.size());
    }
    std::vector<double> clipped = y;
    std::vector<double> lattice = y;
    for (std::size_t i = 0; i < y.size(); ++i) {
      clipped[i] = std::max(y[i], mean - 2.0 * sd);
      lattice[i] = 3.0 * sd * std::round(y[i] / (3.0 * sd));
    }
    const ia::Report rf = analyze_record(frozen, spec, "frozen");
    const ia::Report rc = analyze_record(clipped, spec, "clipped");
    bool fault_free = true;
    const std::vector<double>* clean_records[] = {&y, &lattice};
    for (const std::vector<double>* rec : clean_records) {
      const ia::Report r = analyze_record(*rec, spec, "no fault");
      fault_free = fault_free && !has_note(r, "frozen") && !has_note(r, "clipped");
    }
    const double n_rel = rf.model_after.n / spec.n - 1.0;
    bool clip_range = false;
    for (const auto& u : rc.unexplained) {
      clip_range = clip_range || (u.t_max_s > u.t_min_s && u.what.find("clips") != std::string::npos);
    }
    const bool ok = has_note(rf, "frozen output") && rf.gap_samples == 2999 &&
                    std::fabs(n_rel) < 0.03 && clip_range && fault_free;
    right += ok ? 1 : 0;
    if (!ok) {
      std::printf("seed %llu: frozen N %+.3f, gaps %llu; clip range %d; fault free %d\n",
                  static_cast<unsigned long long>(seed), n_rel,
                  static_cast<unsigned long long>(rf.gap_samples), clip_range ? 1 : 0,
                  fault_free ? 1 : 0);
      print_report("frozen", seed, rf);
    }
  }
  std::printf("recording faults: right on %d of 3\n", right);
  EXPECT_EQ(right, 3);
}

TEST(AnalyzeSynthetic, MillionSamplesUnderTenSeconds) {
  // Target: < 10 s for a 1e6-sample channel on this machine (Release build). The sinusoid case
  // is the slowest path (periodogram, extra ADEVs and fits).
  const ia::Report r = run("sinusoid", 1);
  EXPECT_LT(r.cpu_seconds, 10.0);  // CPU time: the machine is shared (wall printed)
  std::printf("analysis of 1e6 samples (sinusoid case): %.2f s wall, %.2f s CPU\n", r.seconds,
              r.cpu_seconds);
}

// A strong line whose amplitude wanders (80 % amplitude modulation, three cycles per record:
// a motor's vibration; no term of the analysis, and no sinusoid by its coherence test) at 0.6 to
// 1.2 Hz, 4 white stds, in white noise and the example's GM (1e6 samples at 100 Hz, seeds
// 730101..730103). The least-squares fit bent the GM onto the line's ADEV bump: the model after
// lay 5 to 16 times above the data at every longer tau (RMS error 5 to 7), its GM at 0.2 s. The
// lower-envelope refit (robust_after) keeps the bias model of the same record without the line:
// its GM's peak ADEV within 40 % and its peak time within a factor of 2 of that analysis's, N
// within 40 % (the line's leakage at the middle taus raises it), the error after under 1,
// nothing named for the line.
TEST(AnalyzeSynthetic, ALineWhoseAmplitudeWandersLeavesTheBiasModel) {
  int right = 0;
  for (std::uint64_t seed = 730101; seed <= 730103; ++seed) {
    const ia::SynthSpec spec = tc::make_case("control", seed);
    const std::vector<double> clean = ia::synthesize(spec);
    std::vector<double> y = clean;
    std::mt19937_64 g(seed);
    const double f_hz = std::uniform_real_distribution<double>(0.6, 1.2)(g);
    const double amp = 4.0 * spec.n * std::sqrt(spec.fs_hz);
    const double t_rec = static_cast<double>(y.size()) / spec.fs_hz;
    constexpr double kPi = 3.14159265358979323846;
    for (std::size_t i = 0; i < y.size(); ++i) {
      const double t = static_cast<double>(i) / spec.fs_hz;
      y[i] += amp * (1.0 + 0.8 * std::sin(2.0 * kPi * 3.0 * t / t_rec)) *
              std::sin(2.0 * kPi * f_hz * t);
    }
    const ia::Report r0 = analyze_record(clean, spec, "am_line_without_it");
    const ia::Report r = analyze_record(y, spec, "am_line");
    double tp0 = 0.0;
    double tp = 0.0;
    const double peak0 = gm_peak(r0.model_after, tp0);
    const double peak = gm_peak(r.model_after, tp);
    const double n_rel = r.model_after.n / r0.model_after.n - 1.0;
    const bool ok = r.error_after.adev_rms_rel < 1.0 && std::fabs(n_rel) < 0.4 &&
                    std::fabs(peak / peak0 - 1.0) < 0.4 && tp > 0.5 * tp0 && tp < 2.0 * tp0 &&
                    r.effects.empty();
    right += ok ? 1 : 0;
    std::printf("seed %llu (%.3f Hz): error after RMS %.3f; N %.4g, GM peak %.4g at %.0f s; "
                "without the line N %.4g, GM peak %.4g at %.0f s; %zu effects\n",
                static_cast<unsigned long long>(seed), f_hz, r.error_after.adev_rms_rel,
                r.model_after.n, peak, tp, r0.model_after.n, peak0, tp0, r.effects.size());
    if (!ok) {
      print_report("am_line", seed, r);
    }
  }
  EXPECT_EQ(right, 3);
}

// A chirp (a line sweeping from f0 in [0.2, 1] Hz to 2 to 4 times f0 over the record: a motor
// spinning up; no term of the analysis) of 3 white stds in white noise and the example's GM,
// stored on a lattice of 0.7 white std with gravity's offset (1e6 samples at 100 Hz, seeds
// 730201..730206). Without the lower envelope the fit traded the white noise for the chirp's
// bump: N = 0 beside a quantization named, or N = 0 and a GM at the shortest taus lying 2 to
// 3 times above the data at every longer tau (RMS error under 1, so the RMS trigger alone
// missed it). Now: nothing named, N within 40 % of the same record's analysis without the
// chirp, the model after nowhere more than twice above the data's 68 % interval. The GM is
// printed, not checked: on 5 of the 6 its peak is within 10 % of the analysis without the chirp,
// on 730202 it stays on the chirp's bump (peak at the shortest taus, the bias's GM lost).
TEST(AnalyzeSynthetic, AChirpLeavesTheWhiteNoiseAndNamesNothing) {
  int right = 0;
  for (std::uint64_t seed = 730201; seed <= 730206; ++seed) {
    const ia::SynthSpec spec = tc::make_case("control", seed);
    std::vector<double> clean = ia::synthesize(spec);
    std::vector<double> y = clean;
    std::mt19937_64 g(seed);
    const double f0_hz = std::uniform_real_distribution<double>(0.2, 1.0)(g);
    const double f1_hz = f0_hz * std::uniform_real_distribution<double>(2.0, 4.0)(g);
    const double white_sd = spec.n * std::sqrt(spec.fs_hz);
    const double lsb = 0.7 * white_sd;
    constexpr double kGravity = 9.81;
    const double t_rec = static_cast<double>(y.size()) / spec.fs_hz;
    constexpr double kPi = 3.14159265358979323846;
    const auto on_lattice = [&](double v) { return std::round((v - kGravity) / lsb) * lsb; };
    for (std::size_t i = 0; i < y.size(); ++i) {
      const double t = static_cast<double>(i) / spec.fs_hz;
      const double phase = 2.0 * kPi * (f0_hz * t + 0.5 * (f1_hz - f0_hz) / t_rec * t * t);
      y[i] = on_lattice(y[i] + 3.0 * white_sd * std::sin(phase));
      clean[i] = on_lattice(clean[i]);
    }
    const ia::Report r0 = analyze_record(clean, spec, "chirp_without_it");
    const ia::Report r = analyze_record(y, spec, "chirp");
    double worst_above = 0.0;  // model ADEV / the data's 68 % upper bound, over [Ts, T/10]
    for (const auto& pt : r.adev_clean) {
      if (pt.tau_s <= 0.1 * t_rec && pt.ci_hi > 0.0) {
        worst_above = std::max(worst_above, std::sqrt(imu::model_avar(r.model_after, pt.tau_s)) /
                                                pt.ci_hi);
      }
    }
    const double n_rel = r.model_after.n / r0.model_after.n - 1.0;
    double tp0 = 0.0;
    double tp = 0.0;
    const double peak0 = gm_peak(r0.model_after, tp0);
    const double peak = gm_peak(r.model_after, tp);
    const bool ok = r.effects.empty() && std::fabs(n_rel) < 0.4 && worst_above <= 2.0;
    right += ok ? 1 : 0;
    std::printf("seed %llu (%.3f to %.3f Hz): N %.4g, GM peak %.4g at %.0f s (without the chirp "
                "%.4g, %.4g at %.0f s), model at most %.2f x the data's upper bound, error after "
                "RMS %.3f, %zu effects\n",
                static_cast<unsigned long long>(seed), f0_hz, f1_hz, r.model_after.n, peak, tp,
                r0.model_after.n, peak0, tp0, worst_above, r.error_after.adev_rms_rel,
                r.effects.size());
    if (!ok) {
      print_report("chirp", seed, r);
    }
  }
  EXPECT_EQ(right, 6);
}

// The consistency check itself: a model term without its effect, an effect without its term,
// a second GM left unnamed and an effect whose stated statistic does not pass its threshold are
// each caught (the check can fail).
TEST(ReportConsistency, EveryDisagreementIsCaught) {
  ia::Report r;
  r.model_after.n = 1e-3;
  r.model_after.n_gm = 1;
  r.model_after.gm[0] = imu::GmParam{1e-8, 50.0};
  std::string why;
  EXPECT_TRUE(ia::report_consistent(r, why)) << why;
  r.model_after.k = 2e-5;  // a walk in the model, no effect
  EXPECT_FALSE(ia::report_consistent(r, why));
  EXPECT_NE(why.find("rate_random_walk"), std::string::npos) << why;
  ia::Effect e;
  e.type = "rate_random_walk";
  e.k = 3e-5;  // named, with another value than the model's
  e.statistic = 33.7;
  e.threshold = 6.63;
  r.effects.push_back(e);
  EXPECT_FALSE(ia::report_consistent(r, why));
  r.effects[0].k = 2e-5;
  EXPECT_TRUE(ia::report_consistent(r, why)) << why;
  r.model_after.n_gm = 2;  // a second GM, unnamed
  r.model_after.gm[1] = imu::GmParam{4e-6, 0.1};
  EXPECT_FALSE(ia::report_consistent(r, why));
  ia::Effect g;
  g.type = "gauss_markov";
  g.amplitude = std::sqrt(4e-6 * 0.1 / 2.0);
  g.tb_s = 0.1;
  r.effects.push_back(g);  // named, its evidence unset: "statistic 0 > threshold 0"
  EXPECT_FALSE(ia::report_consistent(r, why));
  EXPECT_NE(why.find("statistic"), std::string::npos) << why;
  r.effects.back().statistic = 140.0;
  r.effects.back().threshold = 26.5;
  EXPECT_TRUE(ia::report_consistent(r, why)) << why;
  ia::Effect ramp;  // named, not in the model
  ramp.type = "ramp";
  ramp.r = 1e-6;
  ramp.statistic = 275.0;
  ramp.threshold = 26.5;
  r.effects.push_back(ramp);
  EXPECT_FALSE(ia::report_consistent(r, why));
  EXPECT_NE(why.find("ramp"), std::string::npos) << why;
  r.effects.pop_back();
  ia::Effect step;  // cleaning of the record, not a model term
  step.type = "bias_step";
  step.size = 0.01;
  step.time_s = 100.0;
  step.statistic = 9.0;
  step.threshold = 5.7;
  r.effects.push_back(step);
  EXPECT_TRUE(ia::report_consistent(r, why)) << why;
}

// White noise of density n_density through a first-order low-pass of time constant tf_s, seen
// by an averaging sampler (each sample the mean over its period, 16 sub-steps per period): the
// shape the analysis's output filter describes, generated here without its formulas.
void add_filtered_white(std::vector<double>& y, double fs_hz, double n_density, double tf_s,
                        std::uint64_t seed) {
  constexpr int kSub = 16;
  const double dt = 1.0 / fs_hz / kSub;
  const double a = std::exp(-dt / tf_s);
  std::mt19937_64 g(seed);
  std::normal_distribution<double> w(0.0, n_density / std::sqrt(dt));
  double x = 0.0;
  for (double& v : y) {
    double sum = 0.0;
    for (int k = 0; k < kSub; ++k) {
      x = a * x + (1.0 - a) * w(g);
      sum += x;
    }
    v += sum / kSub;
  }
}

// White noise kN = 5e-3 through an output filter of kTf = 3 ms (a third of the sample period)
// beside a GM peaking at 0.4 s (and, with `oscillation`, a narrowband oscillation at 0.7 Hz:
// sigma 5e-3, beta 0.4 /s), `samples` at 100 Hz, analysed.
constexpr double kFilteredN = 5e-3;
constexpr double kFilteredTf = 3e-3;
ia::Report analyze_filtered_white(std::size_t samples, std::uint64_t seed, bool oscillation) {
  ia::SynthSpec spec = gm_record(samples, seed, 1e-7, 4e-3, 0.4);
  if (oscillation) {
    spec.osc_sigma = 5e-3;
    spec.osc_f0_hz = 0.7;
    spec.osc_beta_per_s = 0.4;
  }
  std::vector<double> y = ia::synthesize(spec);
  add_filtered_white(y, spec.fs_hz, kFilteredN, kFilteredTf, seed + 17);
  return analyze_record(y, spec, "filtered_white");
}

// analyze_filtered_white with the oscillation, 2^20 samples, seeds 990501..990506: the model
// after has the filter with Tf within x1.5 of the truth on at least 5 of 6 (the oscillation and
// the GM bend the same first ADEV points; a filter lost with them leaves the node's innovations
// correlated at lag 1).
TEST(AnalyzeSynthetic, TheSensorsOutputFilterIsKeptBesideItsOtherTerms) {
  int kept = 0;
  int near = 0;
  for (std::uint64_t seed = 990501; seed <= 990506; ++seed) {
    const ia::Report r = analyze_filtered_white(1048576, seed, true);
    const double tf = r.model_after.n_filter_s;
    kept += tf > 0.0 ? 1 : 0;
    near += tf > kFilteredTf / 1.5 && tf < kFilteredTf * 1.5 ? 1 : 0;
    if (!(tf > kFilteredTf / 1.5 && tf < kFilteredTf * 1.5)) {
      print_report("output filter", seed, r);
    }
  }
  std::printf("output filter kept on %d of 6, within x1.5 of its Tf on %d\n", kept, near);
  EXPECT_GE(kept, 5);
  EXPECT_GE(near, 5);
}

// N's 95 % interval beside an output filter it is estimated with: N and Tf both move the first
// ADEV points, so N's interval holds Tf's uncertainty too. analyze_filtered_white without the
// oscillation, 2^18 samples, seeds 990601..990620.
TEST(AnalyzeSynthetic, NsIntervalBesideTheOutputFilterHoldsIt) {
  int filtered = 0;
  int n_in = 0;
  for (std::uint64_t seed = 990601; seed <= 990620; ++seed) {
    const ia::Report r = analyze_filtered_white(262144, seed, false);
    ASSERT_FALSE(r.model_after_ci95.empty());
    const ia::ParamInterval& n = r.model_after_ci95.front();
    filtered += r.model_after.n_filter_s > 0.0 ? 1 : 0;
    n_in += kFilteredN >= n.lo && kFilteredN <= n.hi ? 1 : 0;
    std::printf("filtered white, seed %llu: Tf %.3g ms, N %.4g in [%.5g, %.5g]\n",
                static_cast<unsigned long long>(seed), 1e3 * r.model_after.n_filter_s,
                kFilteredN, n.lo, n.hi);
  }
  std::printf("output filter in the model on %d of 20, N inside its 95 %% interval on %d\n",
              filtered, n_in);
  EXPECT_GE(n_in, 17);
}

}  // namespace

// ---- 95 % intervals (ParamInterval): the true parameter inside the reported interval on at
// least 9 of 10 records per case (seeds 401..410, which no other test uses) for the model's
// white noise N and for Q; each interval narrower than a decade on these 2.8-hour records,
// where every parameter is determined. The walk: K inside on at least 7 of the 10 where it is
// named, and where it is not (a walk beside no GM the ADEV shows is the first-order model's GM
// slower than the record resolves, slow_gm_for_walk), that GM's Tb interval open above (the
// walk's Tb, infinity, inside it): at least 7 of 10 in all, 8 here (K inside on 5 of 6 named,
// the GM on 3; with the GM standing in wherever the record did not tell them apart: 9, K on 1
// of 1 named, the GM on 8). When a rise without a peak was named a walk: K inside on 8 of 9
// named, 4 with the ADEV fit's interval alone (its long-tau points count the walk's few
// increments as independent readings).
TEST(AnalyzeSynthetic, IntervalsHoldTheTrueParameter) {
  for (const char* name : {"quantization", "rate_random_walk"}) {
    SCOPED_TRACE(name);
    int named = 0;
    int effect_in = 0;
    int n_in = 0;
    for (std::uint64_t seed = 401; seed <= 410; ++seed) {
      const ia::SynthSpec spec = tc::make_case(name, seed);
      const ia::Report r = run(name, seed);
      const double truth = std::string(name) == "quantization" ? spec.q : spec.k;
      for (const auto& e : r.effects) {
        if (e.type != name) {
          continue;
        }
        ++named;
        ASSERT_FALSE(e.ci95.empty());
        const ia::ParamInterval& iv = e.ci95.front();
        EXPECT_LT(iv.hi, 10.0 * iv.lo) << describe(r);
        effect_in += truth >= iv.lo && truth <= iv.hi ? 1 : 0;
        std::printf("%s seed %llu: %s %.4g in [%.4g, %.4g]\n", name,
                    static_cast<unsigned long long>(seed), iv.name.c_str(), truth, iv.lo, iv.hi);
      }
      if (std::string(name) == "rate_random_walk" && ia::gm_stands_in_for_walk(r)) {
        ++effect_in;  // the walk's Tb (infinity) inside the GM's Tb interval, open above
        std::printf("%s seed %llu: no walk named, one GM with Tb's interval open above\n", name,
                    static_cast<unsigned long long>(seed));
      }
      ASSERT_FALSE(r.model_after_ci95.empty());
      const ia::ParamInterval& n = r.model_after_ci95.front();
      EXPECT_EQ(n.name, "n");
      EXPECT_LT(n.hi, 10.0 * n.lo);
      n_in += spec.n >= n.lo && spec.n <= n.hi ? 1 : 0;
      std::printf("%s seed %llu: N %.5g in [%.5g, %.5g]\n", name,
                  static_cast<unsigned long long>(seed), spec.n, n.lo, n.hi);
    }
    std::printf("%s: the true parameter inside the effect's 95 %% interval on %d (of %d named; "
                "the walk: or in the GM's Tb interval where none is named), N inside its "
                "interval on %d of 10\n", name, effect_in, named, n_in);
    if (std::string(name) == "quantization") {
      EXPECT_GE(named, 9);
      EXPECT_GE(effect_in, 9) << effect_in << " of " << named;
    } else {
      EXPECT_GE(effect_in, 7) << effect_in << " of " << named;
    }
    EXPECT_GE(n_in, 9);
  }
}

// A record on a lattice coarser than its noise (step 2, 2.8 and 3.5 x the white noise's std per
// sample, an offset of 1 g, a GM of a fifth of the white std, 2e5 samples): the values sit on
// three to five levels and the MAD of the innovations sees only the fraction of a step the
// filter's prediction lies off the middle one; a sample two steps out is a normal tail of the
// rounded noise, not an outlier. No outliers on 9 records; 30 real ones (12 white stds) on the
// 2.8 x lattice are found, and no others. With the gate's spread the MAD plus the rounding's
// q^2 / 12, the 2 x records named 654-694 "outliers", the 2.8 x ones 5-11, and the record with
// 30 real ones 47.
TEST(AnalyzeSynthetic, ALatticeCoarserThanTheNoiseMakesNoFalseOutliersAndKeepsRealOnes) {
  constexpr double kFs = 100.0;
  constexpr std::size_t kN = 200000;
  constexpr double kWhiteSd = 0.01;
  const auto record = [&](double ratio, std::uint64_t seed, std::size_t outliers) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    const double a = std::exp(-1.0 / (kFs * 50.0));  // GM, Tb = 50 s
    const double gm_sd = 0.2 * kWhiteSd * std::sqrt(1.0 - a * a);
    const double q = ratio * kWhiteSd;
    double b = 0.0;
    std::vector<double> y(kN);
    for (std::size_t i = 0; i < kN; ++i) {
      b = a * b + gm_sd * g(rng);
      double v = b + kWhiteSd * g(rng);
      if (outliers > 0 && i % (kN / outliers) == kN / (2 * outliers)) {
        v += (i % 2 == 0 ? 12.0 : -12.0) * kWhiteSd;
      }
      y[i] = 9.80665 + std::round(v / q) * q;
    }
    ia::Options o;
    o.fs_hz = kFs;
    ia::Report r;
    std::string err;
    EXPECT_TRUE(ia::analyze(y, "acc_z", o, r, err)) << err;
    std::string why;
    EXPECT_TRUE(ia::report_consistent(r, why)) << why;
    std::uint64_t found = 0;
    for (const ia::Effect& e : r.effects) {
      found += e.type == "outliers" ? e.count : 0U;
    }
    std::printf("lattice %.1f x the white std, seed %llu, %zu outliers put in: %llu named\n",
                ratio, static_cast<unsigned long long>(seed), outliers,
                static_cast<unsigned long long>(found));
    return found;
  };
  for (const double ratio : {2.0, 2.8, 3.5}) {
    for (std::uint64_t seed = 7401; seed <= 7403; ++seed) {
      EXPECT_EQ(record(ratio, seed, 0), 0U) << "lattice " << ratio << " seed " << seed;
    }
  }
  const std::uint64_t real = record(2.8, 7404, 30);
  EXPECT_GE(real, 27U);
  EXPECT_LE(real, 30U);
}

// One sample in twenty missing, scattered (5 % of 10^6 samples at 100 Hz, white noise and the
// example's GM): the long taus come from the bin means of the recorded samples. With each gap
// bridged by a line between its neighbours the ADEV lay 3-4 % high from 0.08 s on: effects on
// 4 of these 6 records and N 3 % off. The report names what the whole record's names, with N
// within 1 %.
TEST(AnalyzeSynthetic, FivePercentMissingSamplesReadAsTheWholeRecord) {
  int same = 0;
  for (std::uint64_t seed = 7421; seed <= 7426; ++seed) {
    ia::SynthSpec spec = tc::make_case("control", seed);
    const ia::Report whole = analyze_spec(spec, "control");
    spec.nan_gaps = 50000;
    spec.nan_gap_len = 1;
    const ia::Report holed = analyze_spec(spec, "control_5pct_nan");
    EXPECT_GT(holed.gap_samples, 45000U);
    EXPECT_NEAR(holed.model_after.n / whole.model_after.n, 1.0, 0.01) << describe(holed);
    EXPECT_EQ(holed.model_after.n_filter_s > 0.0, whole.model_after.n_filter_s > 0.0)
        << describe(holed);
    same += effect_types(whole) == effect_types(holed) ? 1 : 0;
    std::printf("seed %llu: N %.5g (whole %.5g), effects %zu (whole %zu)\n",
                static_cast<unsigned long long>(seed), holed.model_after.n, whole.model_after.n,
                holed.effects.size(), whole.effects.size());
  }
  EXPECT_GE(same, 5);
}

// One sample in 2000 missing, scattered (1000 gaps of one sample in a 5.6-hour record at 100 Hz,
// white noise and the example's GM): no ADEV term spans a gap, so without the gaps bridged the
// estimator keeps no term beyond 18 s (39 of the 66 taus) and the GM's correlation time is
// lost. The report covers the same taus as on the record without gaps, and N and the GM's Tb
// agree with it.
TEST(AnalyzeSynthetic, ScatteredMissingSamplesKeepTheLongTaus) {
  for (std::uint64_t seed = 7411; seed <= 7412; ++seed) {
    ia::SynthSpec spec = tc::make_case("control", seed);
    spec.samples = 2000000;
    const ia::Report whole = analyze_spec(spec, "control");
    spec.nan_gaps = 1000;
    spec.nan_gap_len = 1;
    const ia::Report holed = analyze_spec(spec, "control_scattered_nan");
    EXPECT_EQ(holed.error_before.n_taus, whole.error_before.n_taus) << describe(holed);
    EXPECT_NEAR(holed.model_after.n / whole.model_after.n, 1.0, 0.005) << describe(holed);
    ASSERT_GT(holed.model_after.n_gm, 0U);
    ASSERT_GT(whole.model_after.n_gm, 0U);
    EXPECT_NEAR(std::log(holed.model_after.gm[0].tb_s / whole.model_after.gm[0].tb_s), 0.0,
                std::log(1.3)) << describe(holed);
    EXPECT_TRUE(holed.effects.empty()) << describe(holed);
  }
}

// Bias instability (B = 5.3e-3, its floor above the GM's peak) beside an oscillation of 0.012
// at 9.8 Hz, white N = 4.7e-3 and a GM peaking at 1.1e-3 at 23 s, 151 Hz, 1.8e6 samples
// (3.3 h): no sinusoid is in the record, and none may be named; a line at a few hundred
// seconds whose frequency and amplitude the record leaves undetermined over decades is the
// fit's shape for flicker's wander (drop_undetermined_sinusoid). Seeds 962101..962110.
TEST(AnalyzeSynthetic, FlickerBesideAnOscillationIsNoSinusoid) {
  constexpr int kRecords = 10;
  int sines = 0;
  int bi = 0;
  for (int i = 0; i < kRecords; ++i) {
    ia::SynthSpec spec;
    spec.seed = 962101 + static_cast<std::uint64_t>(i);
    spec.fs_hz = 151.0;
    spec.samples = 1795763;
    spec.n = 4.7e-3;
    spec.b = 1.13e-3;
    spec.tp_s = 23.0;
    spec.flicker_b = 5.3e-3;
    spec.osc_sigma = 0.012;
    spec.osc_f0_hz = 9.8;
    spec.osc_beta_per_s = 7.6;
    const ia::Report r = analyze_spec(spec, "bi_osc_no_sine");
    sines += is_named(r, "sinusoid") ? 1 : 0;
    bi += is_named(r, "bias_instability") ? 1 : 0;
    if (is_named(r, "sinusoid")) {
      print_report("flicker beside an oscillation, a sinusoid named", spec.seed, r);
    }
  }
  std::printf("flicker beside an oscillation (seeds 962101..962110): a sinusoid named on %d of "
              "%d, bias instability on %d\n", sines, kRecords, bi);
  EXPECT_EQ(sines, 0);
}

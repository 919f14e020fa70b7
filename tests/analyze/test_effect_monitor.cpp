// fw effect detectors: outlier gate, two-window step detector, ADEV residual runs.
#include "imu/effect_monitor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "imu/noise_sim.hpp"
#include "imu/online_adev.hpp"

namespace {

TEST(TwoSidedNormalThreshold, MatchesTables) {
  // Reference values from standard normal tables (Abramowitz & Stegun 26.2), 4 decimals given:
  // tolerance 1e-4 is their rounding.
  EXPECT_NEAR(imu::two_sided_normal_threshold(0.05), 1.9600, 1e-4);
  EXPECT_NEAR(imu::two_sided_normal_threshold(0.01), 2.5758, 1e-4);
  EXPECT_NEAR(imu::two_sided_normal_threshold(1e-6), 4.8916, 1e-4);
  EXPECT_EQ(imu::two_sided_normal_threshold(0.0), 0.0);  // out of range: documented 0
  EXPECT_EQ(imu::two_sided_normal_threshold(1.5), 0.0);
}

TEST(OutlierGate, CountsOnlyAboveThreshold) {
  imu::OutlierGate g;
  ASSERT_EQ(g.configure(5.0), imu::EffectStatus::kOk);
  EXPECT_FALSE(g.push(4.99));
  EXPECT_FALSE(g.push(-4.99));
  EXPECT_TRUE(g.push(5.01));
  EXPECT_TRUE(g.push(-7.0));
  EXPECT_TRUE(g.push(std::nan("")));
  EXPECT_EQ(g.stats().samples, 5U);
  EXPECT_EQ(g.stats().outliers, 3U);
  EXPECT_EQ(g.stats().rejected_nonfinite, 1U);
  EXPECT_NEAR(g.stats().max_abs, 7.0, 1e-12);  // exact copy of an input
  EXPECT_EQ(g.configure(0.0), imu::EffectStatus::kBadConfig);
  EXPECT_EQ(g.configure(std::nan("")), imu::EffectStatus::kBadConfig);
}

TEST(OutlierGate, FalseAlarmRateOnGaussianNoise) {
  // Threshold for P(|N| > z) = 1e-3: over 2e5 draws expect 200, Poisson sd 14; accept +-5 sd.
  imu::OutlierGate g;
  ASSERT_EQ(g.configure(imu::two_sided_normal_threshold(1e-3)), imu::EffectStatus::kOk);
  imu::GaussianRng rng(11);
  for (int i = 0; i < 200000; ++i) {
    (void)g.push(rng.normal());
  }
  EXPECT_NEAR(static_cast<double>(g.stats().outliers), 200.0, 70.0);
}

// White noise counts (sd 20) with an optional step; returns the detector after the record.
imu::StepDetector<16, 4> run_step(double step_counts, std::size_t step_at, std::uint64_t seed) {
  constexpr double kSd = 20.0;
  constexpr std::uint32_t kBlock = 64;
  constexpr std::uint32_t kW = 8;
  // White noise: AVAR at tau = W B samples is sd^2 / (W B) (counts^2).
  const double avar = kSd * kSd / (kW * kBlock);
  imu::StepDetector<16, 4> d;
  EXPECT_EQ(d.configure(kBlock, kW, avar, 5.0), imu::EffectStatus::kOk);
  imu::GaussianRng rng(seed);
  for (std::size_t i = 0; i < 200000; ++i) {
    const double v = kSd * rng.normal() + (i >= step_at ? step_counts : 0.0);
    d.push(static_cast<std::int32_t>(std::lround(v)));
  }
  d.finish();
  return d;
}

TEST(StepDetector, LocatesAndSizesAStep) {
  // Step of 10 counts: sigma_d = sqrt(2 * 400 / 512) = 1.25 counts, so z ~ 8 at the peak.
  const auto d = run_step(10.0, 123456, 3);
  ASSERT_EQ(d.n_events(), 1U);
  const imu::StepEvent& e = d.event(0);
  // Location resolution is one block (64 samples); the peak may sit one block off by noise.
  EXPECT_NEAR(static_cast<double>(e.sample_index), 123456.0, 2.0 * 64.0);
  // Size: d has sd 1.25 counts; 4 sd.
  EXPECT_NEAR(e.size_counts, 10.0, 5.0);
  EXPECT_GT(e.z, 5.0);
}

TEST(StepDetector, SilentWithoutStep) {
  // 200000 / 512 * 2 ~ 800 effective positions at 5 sigma: P(any) ~ 5e-4 per seed.
  for (std::uint64_t seed = 20; seed < 25; ++seed) {
    const auto d = run_step(0.0, 0, seed);
    EXPECT_EQ(d.stats().events, 0U) << "seed " << seed;
    EXPECT_LT(d.stats().max_abs_z, 5.0);
  }
}

TEST(StepDetector, RejectsBadConfig) {
  imu::StepDetector<16, 4> d;
  EXPECT_EQ(d.configure(0, 8, 1.0, 5.0), imu::EffectStatus::kBadConfig);
  EXPECT_EQ(d.configure(8, 9, 1.0, 5.0), imu::EffectStatus::kBadConfig);  // 2 W > 16
  EXPECT_EQ(d.configure(8, 8, 0.0, 5.0), imu::EffectStatus::kBadConfig);
  EXPECT_EQ(d.configure(8, 8, 1.0, -1.0), imu::EffectStatus::kBadConfig);
  ASSERT_EQ(d.configure(8, 8, 1.0, 5.0), imu::EffectStatus::kOk);
  EXPECT_EQ(d.set_reference_avar(-1.0), imu::EffectStatus::kBadConfig);
}

// Points whose ADEV equals a white-noise model times (1 + bump) with a 1 % interval.
std::vector<imu::AdevPoint> make_points(double n, const std::vector<double>& factor) {
  std::vector<imu::AdevPoint> p(factor.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    p[i].tau_s = 0.01 * std::pow(2.0, static_cast<double>(i) / 4.0);
    p[i].adev = n / std::sqrt(p[i].tau_s) * factor[i];
    p[i].ci_lo = p[i].adev * std::exp(-0.01);
    p[i].ci_hi = p[i].adev * std::exp(0.01);
    p[i].edf = 5000.0;
  }
  return p;
}

TEST(AdevResidualCheck, FindsARunAndIgnoresSmallResiduals) {
  imu::ModelParams m{};
  m.n = 3e-3;
  // 20 points; data 5 % above the model on points 8..12 (z = ln(1/1.05)/0.01 = -4.9), 0.5 %
  // elsewhere alternating (|z| = 0.5).
  std::vector<double> f(20);
  for (std::size_t i = 0; i < f.size(); ++i) {
    f[i] = (i % 2 == 0) ? 1.005 : 0.995;
  }
  for (std::size_t i = 8; i <= 12; ++i) {
    f[i] = 1.05;
  }
  const auto p = make_points(m.n, f);
  imu::AdevCheckOptions o;
  o.threshold = 2.0;
  o.min_run = 4;
  imu::AdevCheckResult<8> r;
  std::vector<double> z(p.size());
  ASSERT_EQ(imu::check_adev_residual(p.data(), p.size(), m, o, r, z.data()), imu::EffectStatus::kOk);
  EXPECT_EQ(r.n_checked, 20U);
  ASSERT_EQ(r.n_runs, 1U);
  EXPECT_EQ(r.runs[0].first, 8U);
  EXPECT_EQ(r.runs[0].count, 5U);
  EXPECT_EQ(r.runs[0].sign, -1);
  // z = ln(1/1.05) / 0.01 computed by hand: -4.879; 1e-3 covers the rounding of the exp()'s.
  EXPECT_NEAR(z[10], -4.879, 1e-3);
  EXPECT_NEAR(r.max_rel, 1.0 - 1.0 / 1.05, 1e-9);  // exact arithmetic on the inputs
  EXPECT_TRUE(r.alarm());

  // The same bump on 3 points only: no run of 4, and no single |z| above z_single = 6.
  for (std::size_t i = 8; i <= 12; ++i) {
    f[i] = (i % 2 == 0) ? 1.005 : 0.995;
  }
  for (std::size_t i = 8; i <= 10; ++i) {
    f[i] = 1.05;
  }
  const auto p3 = make_points(m.n, f);
  o.z_single = 6.0;
  ASSERT_EQ(imu::check_adev_residual(p3.data(), p3.size(), m, o, r, nullptr),
            imu::EffectStatus::kOk);
  EXPECT_EQ(r.n_runs, 0U);
  EXPECT_FALSE(r.alarm());
  // A single point far outside (20 %, z = -18) is significant through z_single.
  f[15] = 1.2;
  const auto p1 = make_points(m.n, f);
  ASSERT_EQ(imu::check_adev_residual(p1.data(), p1.size(), m, o, r, nullptr),
            imu::EffectStatus::kOk);
  ASSERT_EQ(r.n_runs, 1U);  // the 3-point bump stays below z_single, the single point passes
  EXPECT_EQ(r.runs[0].first, 15U);
  EXPECT_EQ(r.runs[0].count, 1U);
}

// The co-processor scenario: OnlineAdev snapshot of the first-order model against the true model (no
// alarm), and of the same record with a sinusoid added (alarm, run at the bump near 0.371 / f).
TEST(AdevResidualCheck, OnlineSnapshotAgainstTheTrueModel) {
  imu::FirstOrderGm gm{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, gm), imu::ModelStatus::kOk);
  imu::ModelParams p{};
  p.n = 3.3e-3;
  p.n_gm = 1;
  p.gm[0] = imu::GmParam{gm.sb, gm.tb_s};
  imu::ContinuousModel<6> c;
  imu::DiscreteModel<6> d;
  ASSERT_EQ(imu::build_model(p, c), imu::ModelStatus::kOk);
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  imu::ModelSimulator<6> sim;
  ASSERT_EQ(sim.configure(d, 5), imu::ModelStatus::kOk);
  constexpr double kLsb = 1e-5;
  constexpr double kF = 0.2;  // Hz: bump near 1.9 s, well inside a 2^18-sample record
  imu::OnlineAdev<8, 22> clean(0.01, kLsb);
  imu::OnlineAdev<8, 22> with_sine(0.01, kLsb);
  for (std::size_t i = 0; i < (std::size_t{1} << 18); ++i) {
    const double z = sim.next();
    const double s = 4e-3 * std::sin(2.0 * 3.14159265358979 * kF * 0.01 * static_cast<double>(i));
    clean.push(imu::quantize(z, kLsb).counts);
    with_sine.push(imu::quantize(z + s, kLsb).counts);
  }
  imu::AdevPoint pts[imu::OnlineAdev<8, 22>::kMaxPoints];
  imu::AdevCheckOptions o;
  o.tau_max_s = 262.0;  // T / 10
  o.threshold = 2.0;
  o.min_run = 4;
  o.z_single = imu::two_sided_normal_threshold(0.01 / 60.0);  // Bonferroni over ~60 taus
  imu::AdevCheckResult<8> r;
  std::size_t n = clean.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  ASSERT_EQ(imu::check_adev_residual(pts, n, p, o, r, nullptr), imu::EffectStatus::kOk);
  EXPECT_FALSE(r.alarm()) << "max |z| " << r.max_abs_z;
  n = with_sine.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  ASSERT_EQ(imu::check_adev_residual(pts, n, p, o, r, nullptr), imu::EffectStatus::kOk);
  ASSERT_TRUE(r.alarm());
  bool bump_seen = false;
  for (std::size_t i = 0; i < r.n_runs; ++i) {
    const double tau0 = pts[r.runs[i].first].tau_s;
    const double tau1 = pts[r.runs[i].first + r.runs[i].count - 1].tau_s;
    // The model lies below the data (negative z) around the bump at 0.371 / f = 1.86 s.
    bump_seen = bump_seen || (r.runs[i].sign < 0 && tau0 <= 1.86 && tau1 >= 1.86);
  }
  EXPECT_TRUE(bump_seen);
}

}  // namespace

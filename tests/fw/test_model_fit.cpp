// Tests of imu/model_fit.hpp: exact recovery from noise-free AVAR curves, option checking, and
// the acceptance test on the first-order model simulated for 10,000 s.
#include "imu/model_fit.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "imu/edf.hpp"
#include "imu/error_model.hpp"
#include "imu/noise_sim.hpp"
#include "imu/online_adev.hpp"

namespace {

// Noise-free points on a log grid, with a plausible EDF (the weights only).
std::vector<imu::AdevPoint> exact_points(const imu::ModelParams& p, double tau_lo, double tau_hi,
                                         int per_decade) {
  std::vector<imu::AdevPoint> pts;
  const double decades = std::log10(tau_hi / tau_lo);
  const int count = static_cast<int>(std::floor(decades * per_decade + 1e-6)) + 1;
  for (int i = 0; i < count; ++i) {
    const double tau = tau_lo * std::pow(10.0, static_cast<double>(i) / per_decade);
    imu::AdevPoint a{};
    a.tau_s = tau;
    a.avar = imu::model_avar(p, tau);
    a.adev = std::sqrt(a.avar);
    a.edf = 1e4 / tau + 5.0;
    pts.push_back(a);
  }
  return pts;
}

TEST(ModelFit, RecoversWhitePlusGmFromExactCurve) {
  imu::ModelParams p;
  p.n = 3.3e-3;
  p.n_gm = 1;
  p.gm[0] = {2.6783e-8, 158.73};
  const auto pts = exact_points(p, 0.01, 100.0, 8);
  imu::FitOptions o;
  const imu::FitResult r = imu::fit(pts.data(), pts.size(), o);
  ASSERT_EQ(r.status, imu::FitStatus::kOk);
  // Noise-free data: the only errors are the golden-section tolerance on Tb (the cost is flat
  // near the optimum, so Tb is the least determined) and rounding. 1e-3 relative on Tb, 1e-4 on
  // the rest; the curve itself to 1e-5.
  EXPECT_NEAR(r.params.n, p.n, 1e-6 * p.n);
  ASSERT_EQ(r.params.n_gm, 1U);
  EXPECT_NEAR(r.params.gm[0].tb_s, p.gm[0].tb_s, 1e-3 * p.gm[0].tb_s);
  EXPECT_NEAR(r.params.gm[0].sb, p.gm[0].sb, 1e-3 * p.gm[0].sb);
  EXPECT_LT(r.rms_rel, 1e-5);
  EXPECT_EQ(r.n_points, pts.size());
  EXPECT_FALSE(r.tb_at_bound);
}

TEST(ModelFit, RecoversQuantWhiteTwoGmAndRrw) {
  imu::ModelParams p;
  p.q = 2e-5;
  p.n = 1e-3;
  p.n_gm = 2;
  p.gm[0] = {1e-7, 2.0};
  p.gm[1] = {2e-9, 200.0};
  p.k = 3e-5;
  const auto pts = exact_points(p, 0.01, 5000.0, 10);
  imu::FitOptions o;
  o.terms = imu::kFitWhite | imu::kFitQuantization | imu::kFitGm1 | imu::kFitGm2 | imu::kFitRrw;
  o.tau_max_s = 5000.0;
  const imu::FitResult r = imu::fit(pts.data(), pts.size(), o);
  ASSERT_EQ(r.status, imu::FitStatus::kOk);
  // Five parameters from a smooth curve: coordinate search converges to the exact optimum only
  // approximately; 1 % on every parameter and 0.1 % on the curve.
  EXPECT_LT(r.rms_rel, 1e-3);
  EXPECT_NEAR(r.params.n, p.n, 0.01 * p.n);
  EXPECT_NEAR(r.params.q, p.q, 0.01 * p.q);
  EXPECT_NEAR(r.params.k, p.k, 0.01 * p.k);
  ASSERT_EQ(r.params.n_gm, 2U);
  EXPECT_NEAR(r.params.gm[0].tb_s, 2.0, 0.01 * 2.0);
  EXPECT_NEAR(r.params.gm[1].tb_s, 200.0, 0.01 * 200.0);
}

TEST(ModelFit, AbsentTermIsClampedToZeroNotNegative) {
  // White noise only, but white + RRW + ramp requested: NNLS must return K = R = 0.
  imu::ModelParams p;
  p.n = 1e-3;
  const auto pts = exact_points(p, 0.01, 100.0, 8);
  imu::FitOptions o;
  o.terms = imu::kFitWhite | imu::kFitRrw | imu::kFitRamp;
  const imu::FitResult r = imu::fit(pts.data(), pts.size(), o);
  ASSERT_EQ(r.status, imu::FitStatus::kOk);
  EXPECT_NEAR(r.params.n, 1e-3, 1e-9);  // exact data, one active parameter
  EXPECT_LT(r.params.k * r.params.k * 100.0 / 3.0, 1e-6 * 1e-6 / 100.0);  // negligible at 100 s
  EXPECT_LT(r.params.r, 1e-12);
}

// K held (FitOptions::k_fixed): the other terms are fitted beside it. Held at the truth they
// come back exactly; held at half of it, a GM takes the walk's rise and the cost grows, never
// below the free fit's (a profile of the cost over K).
TEST(ModelFit, HeldWalkLeavesTheOtherTermsToTheFit) {
  imu::ModelParams p;
  p.n = 1e-3;
  p.n_gm = 1;
  p.gm[0] = {2e-9, 50.0};
  p.k = 3e-5;
  const auto pts = exact_points(p, 0.01, 2000.0, 10);
  imu::FitOptions o;
  o.terms = imu::kFitWhite | imu::kFitGm1 | imu::kFitRrw;
  o.tau_max_s = 2000.0;
  const imu::FitResult free_fit = imu::fit(pts.data(), pts.size(), o);
  ASSERT_EQ(free_fit.status, imu::FitStatus::kOk);
  o.k_fixed = p.k;
  const imu::FitResult held = imu::fit(pts.data(), pts.size(), o);
  ASSERT_EQ(held.status, imu::FitStatus::kOk);
  EXPECT_EQ(held.params.k, p.k);
  EXPECT_NEAR(held.params.n, p.n, 1e-3 * p.n);
  ASSERT_EQ(held.params.n_gm, 1U);
  EXPECT_NEAR(held.params.gm[0].tb_s, 50.0, 0.01 * 50.0);
  EXPECT_LT(held.rms_rel, 1e-3);
  o.k_fixed = 0.5 * p.k;
  const imu::FitResult half = imu::fit(pts.data(), pts.size(), o);
  ASSERT_EQ(half.status, imu::FitStatus::kOk);
  EXPECT_EQ(half.params.k, 0.5 * p.k);
  EXPECT_GT(half.cost, held.cost);
  EXPECT_GE(half.cost, free_fit.cost);
  EXPECT_GT(half.params.gm[0].tb_s, 50.0);  // the GM reaches for the walk's rise
  o.k_fixed = -1.0;
  EXPECT_EQ(imu::fit(pts.data(), pts.size(), o).status, imu::FitStatus::kBadOptions);
}

TEST(ModelFit, RejectsBadOptionsAndTooFewPoints) {
  imu::ModelParams p;
  p.n = 1e-3;
  const auto pts = exact_points(p, 0.01, 100.0, 8);
  imu::FitOptions o;
  o.tau_min_s = 10.0;
  o.tau_max_s = 1.0;
  EXPECT_EQ(imu::fit(pts.data(), pts.size(), o).status, imu::FitStatus::kBadOptions);
  o = imu::FitOptions{};
  o.terms = imu::kFitGm2;
  EXPECT_EQ(imu::fit(pts.data(), pts.size(), o).status, imu::FitStatus::kBadOptions);
  o = imu::FitOptions{};
  o.terms = 0;
  EXPECT_EQ(imu::fit(pts.data(), pts.size(), o).status, imu::FitStatus::kBadOptions);
  o = imu::FitOptions{};
  EXPECT_EQ(imu::fit(pts.data(), 1, o).status, imu::FitStatus::kTooFewPoints);
  std::vector<imu::AdevPoint> many(imu::kMaxFitPoints + 1, pts[0]);
  EXPECT_EQ(imu::fit(many.data(), many.size(), o).status, imu::FitStatus::kTooManyPoints);
}

// The acceptance test: the first-order model (N = 3.3e-3, B = 9e-4, Tp = 300 s, 100 Hz)
// simulated for 10,000 s, quantized with LSB 1e-5, through OnlineAdev<8, 22>, white + GM fitted
// over [0.01, 100] s.
TEST(ModelFit, SeedModelSimulatedTenThousandSecondsIsRecovered) {
  const auto t0 = std::chrono::steady_clock::now();
  imu::FirstOrderGm ex{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, ex), imu::ModelStatus::kOk);
  imu::ContinuousModel<1> c;
  ASSERT_EQ(c.add_white(ex.n), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(ex.sb, ex.tb_s), imu::ModelStatus::kOk);
  imu::DiscreteModel<1> d;
  ASSERT_EQ(imu::discretize(c, ex.ts_s, d), imu::ModelStatus::kOk);
  imu::ModelSimulator<1> sim;
  ASSERT_EQ(sim.configure(d, 20251121), imu::ModelStatus::kOk);
  constexpr double kLsb = 1e-5;
  imu::OnlineAdev<8, 22> adev(ex.ts_s, kLsb);
  for (int i = 0; i < 1000000; ++i) {
    const imu::QuantizeResult q = imu::quantize(sim.next(), kLsb);
    ASSERT_FALSE(q.saturated);
    adev.push(q.counts);
  }
  imu::AdevPoint pts[imu::OnlineAdev<8, 22>::kMaxPoints];
  const std::size_t n = adev.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  imu::FitOptions o;  // white + GM over [0.01, 100] s
  const imu::FitResult r = imu::fit(pts, n, o);
  ASSERT_EQ(r.status, imu::FitStatus::kOk);
  ASSERT_EQ(r.params.n_gm, 1U);

  EXPECT_NEAR(r.params.n, 3.3e-3, 0.05 * 3.3e-3);  // target: N within 5 %
  std::size_t inside = 0;
  std::size_t total = 0;
  double ss = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (pts[i].tau_s < 0.01 * (1 - 1e-9) || pts[i].tau_s > 100.0 * (1 + 1e-9)) {
      continue;
    }
    const double model = std::sqrt(imu::model_avar(r.params, pts[i].tau_s));
    const imu::DevInterval ci = imu::deviation_interval(pts[i].adev, pts[i].edf, 0.95);
    ++total;
    inside += (model >= ci.lo && model <= ci.hi) ? 1U : 0U;
    const double rel = model / pts[i].adev - 1.0;
    ss += rel * rel;
  }
  const double rms = std::sqrt(ss / static_cast<double>(total));
  const double frac = static_cast<double>(inside) / static_cast<double>(total);
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("example fit: N = %.4e (true 3.3000e-03), Sb = %.4e (true 2.6783e-08), Tb = %.1f s "
              "(true %.1f s), B = %.3e; %zu/%zu taus inside the 95%% interval (%.1f %%), RMS rel "
              "%.2f %%, %u NNLS solves, Tb at the search bound: %s, %.2f s\n",
              r.params.n, r.params.gm[0].sb, r.params.gm[0].tb_s, ex.tb_s,
              imu::kGmPeakAdevFactor * std::sqrt(r.params.gm[0].sb * r.params.gm[0].tb_s), inside,
              total, 100.0 * frac, 100.0 * rms, r.evaluations, r.tb_at_bound ? "yes" : "no",
              secs);
  EXPECT_GE(total, 40U);     // [0.01, 100] s holds 48 taus of OnlineAdev<8, 22>
  EXPECT_GE(frac, 0.90);     // target: >= 90 % inside the data's 95 % interval
  EXPECT_LT(rms, 0.03);      // target: RMS relative error < 3 %
  EXPECT_NEAR(r.rms_rel, rms, 1e-12);  // the fit's own figure is the same quantity
}

}  // namespace

// Bias instability: white + the ideal flicker floor (the exact (2 ln 2 / pi) B^2, not the bank)
// over [0.1, 1000] s; the fit's B within 5 % (the bank's own ripple is -4.6 % / +0.8 % in ADEV).
TEST(ModelFit, RecoversBiasInstabilityFromTheIdealFlickerFloor) {
  const double n = 3.3e-3;
  const double b = 2e-3;
  std::vector<imu::AdevPoint> pts;
  for (int i = 0; i <= 40; ++i) {
    const double tau = 0.1 * std::pow(10.0, i / 10.0);
    imu::AdevPoint a{};
    a.tau_s = tau;
    a.avar = n * n / tau + 2.0 * std::log(2.0) / 3.14159265358979323846 * b * b;
    a.adev = std::sqrt(a.avar);
    a.edf = 1e4 / tau + 5.0;
    pts.push_back(a);
  }
  imu::FitOptions o;
  o.terms = imu::kFitWhite | imu::kFitFlicker;
  o.tau_min_s = 0.1;
  o.tau_max_s = 1000.0;
  const imu::FitResult f = imu::fit(pts.data(), pts.size(), o);
  ASSERT_EQ(f.status, imu::FitStatus::kOk);
  EXPECT_NEAR(f.params.n, n, 0.01 * n);
  EXPECT_NEAR(f.params.bi, b, 0.05 * b);
  EXPECT_DOUBLE_EQ(f.params.bi_tau_lo_s, 0.1);
  EXPECT_DOUBLE_EQ(f.params.bi_tau_hi_s, 1000.0);
  EXPECT_LT(f.rms_rel, 0.03);
}

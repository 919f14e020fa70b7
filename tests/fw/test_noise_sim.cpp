// Tests of imu/noise_sim.hpp: the PRNG against values from an independent implementation, the
// Gaussian draws' moments, the oscillator's exact rotation, and the ADEV of a simulated
// multi-term model against the analytic sum of the MODELS.md terms.
#include "imu/noise_sim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>

#include "imu/edf.hpp"
#include "imu/error_model.hpp"
#include "imu/online_adev.hpp"

namespace {

TEST(NoiseSim, XoshiroMatchesAnIndependentImplementation) {
  // Python transcription of xoshiro256** 1.0 and splitmix64 (prng.di.unimi.it), seed 12345;
  // splitmix64's first output for seed 0 is the published 0xe220a8397b1dcdaf.
  imu::Xoshiro256ss g(12345);
  const std::uint64_t want[] = {0xbe6a36374160d49bULL, 0x214aaa0637a688c6ULL,
                                0xf69d16de9954d388ULL, 0x0c60048c4e96e033ULL,
                                0x8e2076aeed51c648ULL};
  for (const std::uint64_t w : want) {
    EXPECT_EQ(g.next(), w);
  }
}

TEST(NoiseSim, GaussianMomentsAndDeterminism) {
  imu::GaussianRng a(42);
  imu::GaussianRng b(42);
  double s1 = 0.0;
  double s2 = 0.0;
  double s4 = 0.0;
  constexpr int kN = 1000000;
  for (int i = 0; i < kN; ++i) {
    const double x = a.normal();
    const double y = b.normal();
    ASSERT_NEAR(x, y, 0.0);  // same seed, same stream, bit for bit
    s1 += x;
    s2 += x * x;
    s4 += x * x * x * x;
  }
  // Standard errors for 1e6 draws: mean 1e-3, variance sqrt(2)e-3, 4th moment sqrt(96)e-3.
  // Tolerance 5 standard errors.
  EXPECT_NEAR(s1 / kN, 0.0, 5e-3);
  EXPECT_NEAR(s2 / kN, 1.0, 5.0 * 1.414e-3);
  EXPECT_NEAR(s4 / kN, 3.0, 5.0 * 9.8e-3);
}

TEST(NoiseSim, OscillatorRotatesExactly) {
  // Sinusoid term, no noise: z_k = x0 cos(w k Ts) + x1 sin(w k Ts) for all k (Van Loan Phi is an
  // exact rotation; 1e5 steps of rounding accumulate to ~1e5 ulp of the amplitude).
  imu::ContinuousModel<2> c;
  ASSERT_EQ(c.add_sinusoid(1.0, 0.37), imu::ModelStatus::kOk);
  imu::DiscreteModel<2> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  imu::ModelSimulator<2> sim;
  ASSERT_EQ(sim.configure(d, 1), imu::ModelStatus::kOk);
  const double x0 = sim.state()[0];
  const double x1 = sim.state()[1];
  const double w = 2.0 * 3.14159265358979323846 * 0.37;
  for (int k = 0; k < 100000; ++k) {
    const double t = 0.01 * k;
    const double z = sim.next();
    ASSERT_NEAR(z, x0 * std::cos(w * t) + x1 * std::sin(w * t), 1e-10) << k;
  }
}

TEST(NoiseSim, UnconfiguredSimulatorReturnsZeroAndBadModelIsRejected) {
  imu::ModelSimulator<1> sim;
  EXPECT_NEAR(sim.next(), 0.0, 0.0);
  imu::DiscreteModel<1> d;  // ts_s = 0
  EXPECT_EQ(sim.configure(d, 1), imu::ModelStatus::kBadParameter);
  imu::OnlineAdev<8, 22> adev(0.01, 1e-6);
  EXPECT_EQ(imu::simulate_adev(d, 1, 10, 1e-6, adev).status, imu::ModelStatus::kBadParameter);
  d.ts_s = 0.01;
  d.r_white = 1.0;
  EXPECT_EQ(imu::simulate_adev(d, 1, 10, 0.0, adev).status, imu::ModelStatus::kBadParameter);
  EXPECT_EQ(adev.samples(), 0U);  // nothing pushed on failure
}

TEST(NoiseSim, SimulatedAdevMatchesTheAnalyticSumOfTerms) {
  // White + quantization + two GMs + RRW, 1e6 samples at 100 Hz through OnlineAdev<8, 22>.
  imu::ContinuousModel<6> c;
  ASSERT_EQ(c.add_white(3.3e-3), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_quantization(3e-4), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(1e-5, 0.5), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(3e-8, 150.0), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_rrw(1.3e-4), imu::ModelStatus::kOk);
  imu::DiscreteModel<6> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  constexpr double kLsb = 1e-6;
  imu::OnlineAdev<8, 22> adev(0.01, kLsb);
  const imu::SimAdevResult sr = imu::simulate_adev(d, 2024, 1000000, kLsb, adev);
  ASSERT_EQ(sr.status, imu::ModelStatus::kOk);
  EXPECT_EQ(sr.samples, 1000000U);
  EXPECT_EQ(sr.saturated, 0U);
  EXPECT_EQ(adev.samples(), 1000000U);
  imu::AdevPoint pts[imu::OnlineAdev<8, 22>::kMaxPoints];
  const std::size_t n = adev.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  std::size_t inside = 0;
  std::size_t total = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (pts[i].tau_s > 100.0 * (1 + 1e-9)) {
      continue;  // beyond 100 s the white-FM EDF overstates the confidence for RRW data
    }
    const double model = std::sqrt(c.avar(pts[i].tau_s));
    const imu::DevInterval ci = imu::deviation_interval(pts[i].adev, pts[i].edf, 0.99);
    ++total;
    inside += (model >= ci.lo && model <= ci.hi) ? 1U : 0U;
    const double rel = std::fabs(model / pts[i].adev - 1.0);
    worst = rel > worst ? rel : worst;
  }
  std::printf("simulated vs analytic ADEV: %zu/%zu taus in [0.01, 100] s inside the 99%% "
              "interval, worst relative difference %.2f %%\n",
              inside, total, 100.0 * worst);
  // Adjacent taus are strongly correlated, so the fraction is lumpy; 90 % of taus inside the
  // 99 % interval still fails for any wrong term (a 10 % error in one term breaks it).
  EXPECT_GE(static_cast<double>(inside), 0.90 * static_cast<double>(total));
  EXPECT_LT(worst, 0.15);  // the widest interval in the range (tau = 100 s) is about +-15 %
}

TEST(NoiseSim, SinusoidAndRampAdevMatchTheFormulas) {
  // One realisation with a chosen amplitude (the prior N(0, A^2/2) per state gives a Rayleigh
  // amplitude, so the formula holds only on average): state (x0, x1) = (0, A) is A sin(w t).
  constexpr double kA = 2e-3;
  constexpr double kF0 = 0.2;
  imu::ContinuousModel<2> c;
  ASSERT_EQ(c.add_sinusoid(kA, kF0), imu::ModelStatus::kOk);
  imu::DiscreteModel<2> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  imu::ModelSimulator<2> sim;
  ASSERT_EQ(sim.configure(d, 1), imu::ModelStatus::kOk);
  const double x0[2] = {0.0, kA};
  sim.set_state(x0, 2);
  constexpr double kLsb = 1e-9;
  imu::OnlineAdev<8, 22> adev(0.01, kLsb);
  for (int i = 0; i < 1000000; ++i) {  // 2000 periods
    adev.push(imu::quantize(sim.next(), kLsb).counts);
  }
  imu::AdevPoint pts[imu::OnlineAdev<8, 22>::kMaxPoints];
  std::size_t n = adev.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  const double peak_avar = imu::avar_sinusoid(kA, kF0, 0.371 / kF0);
  std::size_t checked = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (pts[i].tau_s > 100.0) {
      continue;
    }
    ++checked;
    // Sampled (100 Hz) vs continuous averaging differs by O((pi f0 Ts)^2) = 4e-5 relative; the
    // finite record (2000 periods, a partial period at the ends) by ~1/2000 of the peak. 0.5 %
    // of the peak AVAR, absolute, so the nulls at tau = k / f0 are compared sensibly.
    EXPECT_NEAR(pts[i].avar, imu::avar_sinusoid(kA, kF0, pts[i].tau_s), 5e-3 * peak_avar)
        << "tau " << pts[i].tau_s;
  }
  EXPECT_GE(checked, 40U);

  // Ramp with slope R: the phase is quadratic, every second difference is exactly R tau^2.
  constexpr double kR = 1e-5;
  imu::ContinuousModel<2> cr;
  ASSERT_EQ(cr.add_ramp(kR), imu::ModelStatus::kOk);
  imu::DiscreteModel<2> dr;
  ASSERT_EQ(imu::discretize(cr, 0.01, dr), imu::ModelStatus::kOk);
  imu::ModelSimulator<2> simr;
  ASSERT_EQ(simr.configure(dr, 1), imu::ModelStatus::kOk);
  const double r0[2] = {0.0, kR};
  simr.set_state(r0, 2);
  imu::OnlineAdev<8, 22> adev_r(0.01, kLsb);
  for (int i = 0; i < 100000; ++i) {  // 1000 s, up to 1e-2: quantization to 1e-9 is 1e-7 rel.
    adev_r.push(imu::quantize(simr.next(), kLsb).counts);
  }
  n = adev_r.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  for (std::size_t i = 0; i < n; ++i) {
    if (pts[i].tau_s < 0.1 || pts[i].tau_s > 100.0) {
      continue;  // below 0.1 s the LSB rounding (1e-9 vs a step of 1e-7 per sample) shows
    }
    const double want = imu::avar_ramp(kR, pts[i].tau_s);
    // Rounding of z to the LSB adds white-phase-like noise of ~(1e-9 Ts)^2 / tau^2 relative
    // to R^2 tau^2 / 2; at tau >= 0.1 s that is below 1e-4 relative.
    EXPECT_NEAR(pts[i].avar, want, 1e-4 * want) << "tau " << pts[i].tau_s;
  }
}

}  // namespace

// AveragedKf against the dense KalmanFilter on the same averaged models: the same innovations,
// innovation variances and bias estimates (double: to rounding; float: within float's
// accumulated error), the structure it refuses, and the steady-state gain.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdio>

#include "imu/averaged_kf.hpp"
#include "imu/bias_kf.hpp"
#include "imu/error_model.hpp"
#include "imu/noise_sim.hpp"

namespace {

constexpr std::size_t kCap = 16;
constexpr double kTs = 0.01;

// The node's largest kind of model and one with every 2-state term.
imu::ModelParams largest_gm_model() {
  imu::ModelParams p{};
  p.n = 3.3e-3;
  p.n_filter_s = 2.5e-3;
  p.n_gm = 2;
  p.gm[0] = {2.0e-6, 0.2};
  p.gm[1] = {4.0e-9, 300.0};
  p.k = 1.4e-4;
  p.bi = 5e-4;
  p.bi_tau_lo_s = 1.0;
  p.bi_tau_hi_s = 1000.0;
  return p;
}

imu::ModelParams two_state_terms_model(double memory_s) {
  imu::ModelParams p{};
  p.n = 3.3e-3;
  p.q = 1e-5;
  p.n_gm = 1;
  p.gm[0] = {5.4e-9, 158.7};
  p.r = -2e-6;  // its sign is the realisation's: the filter's prior uses R^2
  p.sin_a = 2e-3;
  p.sin_f0_hz = 0.05;
  p.sin2_a = 1e-3;
  p.sin2_f0_hz = 0.1;
  p.osc_sigma = 4e-3;
  p.osc_f0_hz = 10.0;
  p.osc_beta_per_s = 3.0;
  p.signal_memory_s = memory_s;
  return p;
}

imu::DiscreteModel<kCap> averaged(const imu::ModelParams& p) {
  imu::ContinuousModel<kCap> c;
  EXPECT_EQ(imu::build_model(p, c), imu::ModelStatus::kOk);
  imu::DiscreteModel<kCap> d;
  EXPECT_EQ(imu::discretize_averaged(c, kTs, d), imu::ModelStatus::kOk);
  return d;
}

struct Worst {
  double innovation = 0.0;  // |e - e'| / sqrt(S')
  double variance = 0.0;    // |S - S'| / S'
  double bias = 0.0;        // |b - b'| / sqrt(var')
};

// Both filters over the same simulated record (with a stretch not static and a rejected
// sample), the largest differences against the dense double filter.
template <typename T, std::size_t kN>
Worst compare(const imu::DiscreteModel<kCap>& d, int samples, std::uint64_t seed) {
  imu::KalmanFilter<double, kN> dense;
  EXPECT_EQ(dense.configure(d, 9.81), imu::KfStatus::kOk);
  imu::AveragedKf<T, kN - 1> fast;
  EXPECT_EQ(fast.configure(d, 9.81), imu::KfStatus::kOk);
  EXPECT_EQ(fast.process_states(), kN - 1);
  imu::ModelSimulator<kCap> sim;
  EXPECT_EQ(sim.configure(d, seed), imu::ModelStatus::kOk);
  Worst w;
  for (int i = 0; i < samples; ++i) {
    const double z = 9.81 + sim.next();
    const bool is_static = !(i >= 3000 && i < 3500);  // 5 s of motion: predictions only
    const double zi = i == 7000 ? std::nan("") : z;    // a rejected sample
    const auto a = dense.step(zi, is_static);
    const auto b = fast.step(static_cast<T>(zi), is_static);
    EXPECT_EQ(a.updated, b.updated) << i;
    if (!a.updated) {
      continue;
    }
    const double sd = std::sqrt(a.innovation_var);
    w.innovation = std::fmax(w.innovation, std::fabs(static_cast<double>(b.innovation) -
                                                     a.innovation) / sd);
    w.variance = std::fmax(w.variance, std::fabs(static_cast<double>(b.innovation_var) -
                                                 a.innovation_var) / a.innovation_var);
    w.bias = std::fmax(w.bias, std::fabs(static_cast<double>(fast.bias()) - dense.bias()) /
                                   std::sqrt(dense.bias_variance()));
  }
  EXPECT_NEAR(static_cast<double>(fast.bias_variance()), dense.bias_variance(),
              1e-3 * dense.bias_variance());
  EXPECT_EQ(fast.stats().rejected_nonfinite, 1U);
  return w;
}

TEST(AveragedKf, MatchesTheDenseFilterInDouble) {
  // Rounding only: the two filters order their sums differently.
  const auto d1 = averaged(largest_gm_model());
  ASSERT_EQ(d1.n_states, 10U);  // filter 1 + 2 GM + 5-member bank + walk + mean
  const Worst w1 = compare<double, 10>(d1, 20000, 11);
  EXPECT_LT(w1.innovation, 1e-9);
  EXPECT_LT(w1.variance, 1e-9);
  EXPECT_LT(w1.bias, 1e-7);
  const auto d2 = averaged(two_state_terms_model(0.0));
  ASSERT_EQ(d2.n_states, 10U);  // GM 1 + ramp 2 + 2 sinusoids 4 + oscillation 2 + mean
  const Worst w2 = compare<double, 10>(d2, 20000, 12);
  EXPECT_LT(w2.innovation, 1e-9);
  EXPECT_LT(w2.variance, 1e-9);
  EXPECT_LT(w2.bias, 1e-7);
}

TEST(AveragedKf, FloatStaysWithinItsRoundingOfTheDoubleFilter) {
  // Float carries ~6e-8 relative per operation; the filter is stable, so the error stays
  // bounded: a few 1e-4 of an innovation's sd over 10^5 samples is what float gives here
  // (test_bias_kf measures the dense float filter the same way).
  for (const auto& p : {largest_gm_model(), two_state_terms_model(3600.0)}) {
    const auto d = averaged(p);
    const Worst w = compare<float, 10>(d, 100000, 13);
    std::printf("float vs double: innovation %.2e sd, S %.2e, bias %.2e sd\n", w.innovation,
                w.variance, w.bias);
    EXPECT_LT(w.innovation, 2e-3);
    EXPECT_LT(w.variance, 2e-3);
    EXPECT_LT(w.bias, 2e-2);
  }
}

TEST(AveragedKf, RefusesModelsWithoutTheAveragedStructure) {
  imu::AveragedKf<double, 9> kf;
  // Point samples (discretize): no sample-mean state.
  imu::ContinuousModel<kCap> c;
  ASSERT_EQ(imu::build_model(largest_gm_model(), c), imu::ModelStatus::kOk);
  imu::DiscreteModel<kCap> point;
  ASSERT_EQ(imu::discretize(c, kTs, point), imu::ModelStatus::kOk);
  EXPECT_EQ(kf.configure(point), imu::KfStatus::kBadModel);
  // Too many states for the capacity.
  const auto big = averaged(largest_gm_model());
  imu::AveragedKf<double, 8> small;
  EXPECT_EQ(small.configure(big), imu::KfStatus::kBadModel);
  // A coupling between two terms (not block diagonal), a mean that feeds a state, a NaN.
  auto coupled = big;
  coupled.phi(0, 5) = 1e-3;
  EXPECT_EQ(kf.configure(coupled), imu::KfStatus::kBadModel);
  auto feeds = big;
  feeds.phi(2, 9) = 0.5;
  EXPECT_EQ(kf.configure(feeds), imu::KfStatus::kBadModel);
  auto nan = big;
  nan.qd(3, 3) = std::nan("");
  EXPECT_EQ(kf.configure(nan), imu::KfStatus::kBadModel);
  EXPECT_EQ(kf.configure(big, std::nan("")), imu::KfStatus::kBadModel);
  EXPECT_EQ(kf.process_states(), 0U);  // nothing was taken
  EXPECT_EQ(kf.configure(big), imu::KfStatus::kOk);
  EXPECT_EQ(kf.process_states(), 9U);
}

TEST(AveragedKf, DrivenSignalsLetTheGainFreezeConstantOnesDoNot) {
  // Constant ramp and sinusoids (memory 0): persistent undriven states, never steady.
  const auto constant = averaged(two_state_terms_model(0.0));
  imu::AveragedKf<float, 9> kc;
  ASSERT_EQ(kc.configure(constant), imu::KfStatus::kOk);
  kc.set_steady_state(true);
  EXPECT_FALSE(kc.steady_allowed());
  // Known for an hour: driven, the gain settles and freezes; the frozen filter goes on with the
  // innovation variance it converged to, and a sample without an update unfreezes it.
  const auto driven = averaged(two_state_terms_model(3600.0));
  imu::AveragedKf<float, 9> kf;
  ASSERT_EQ(kf.configure(driven), imu::KfStatus::kOk);
  kf.set_steady_state(true);
  EXPECT_TRUE(kf.steady_allowed());
  imu::ModelSimulator<kCap> sim;
  ASSERT_EQ(sim.configure(driven, 14), imu::ModelStatus::kOk);
  int i = 0;
  for (; i < 3000000 && !kf.steady(); ++i) {
    (void)kf.step(static_cast<float>(sim.next()), true);
  }
  ASSERT_TRUE(kf.steady()) << "not steady after " << i << " samples";
  std::printf("steady after %d samples\n", i);
  // Frozen vs the time-varying filter from the same point: the same innovations.
  imu::AveragedKf<float, 9> tv = kf;
  tv.set_steady_state(false);
  double worst = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const auto z = static_cast<float>(sim.next());
    const auto a = kf.step(z, true);
    const auto b = tv.step(z, true);
    worst = std::fmax(worst, std::fabs(static_cast<double>(a.innovation - b.innovation)) /
                                 std::sqrt(static_cast<double>(b.innovation_var)));
    ASSERT_NEAR(a.innovation_var, b.innovation_var, 1e-4F * b.innovation_var);
  }
  EXPECT_LT(worst, 1e-3);
  (void)kf.step(0.0F, false);
  EXPECT_FALSE(kf.steady());
}

}  // namespace

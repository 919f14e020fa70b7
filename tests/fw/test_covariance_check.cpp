// Tests of imu/covariance_check.hpp: closed forms for white and quantization noise, the robust
// standard deviation against a sort-based reference, and the exact prediction against Monte
// Carlo from the simulator (the example's check on model-simulated data).
#include "imu/covariance_check.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "imu/error_model.hpp"
#include "imu/noise_sim.hpp"

namespace {

double reference_robust_std(std::vector<double> v) {
  auto median = [](std::vector<double> x) {
    std::sort(x.begin(), x.end());
    const std::size_t n = x.size();
    return n % 2 == 1 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
  };
  const double m = median(v);
  for (double& x : v) {
    x = std::fabs(x - m);
  }
  return 1.4826 * median(v);
}

TEST(CovarianceCheck, RobustStdMatchesSortReference) {
  std::mt19937_64 gen(5);
  std::normal_distribution<double> nd(1.0, 3.0);
  for (std::size_t n : {1U, 2U, 3U, 10U, 11U, 1000U, 1001U}) {  // +1 duplicate below
    std::vector<double> v;
    for (std::size_t i = 0; i < n; ++i) {
      v.push_back(nd(gen));
    }
    v.push_back(v.front());  // duplicates must not break the selection
    n = v.size();
    const double want = reference_robust_std(v);
    EXPECT_NEAR(imu::robust_std(v.data(), n), want, 1e-15 * (1.0 + want)) << n;  // same values
  }
  std::vector<double> same(7, 2.5);
  EXPECT_NEAR(imu::robust_std(same.data(), same.size()), 0.0, 0.0);
  EXPECT_NEAR(imu::robust_std(nullptr, 0), 0.0, 0.0);
}

TEST(CovarianceCheck, WhiteAndQuantizationMatchClosedForms) {
  // White: var(I_j) = Ts^2 sigma^2 (j + j^2 / n_avg). Quantization (phase noise Q):
  // I_j = Q [u_{na+j-1} - (1 + j/na) u_{na-1} + (j/na) u_{-1}], var = Q^2 [1 + (1+j/na)^2 + (j/na)^2].
  imu::ContinuousModel<1> c;
  ASSERT_EQ(c.add_white(2e-3), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_quantization(1e-4), imu::ModelStatus::kOk);
  imu::DiscreteModel<1> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  constexpr std::size_t kNa = 1000;
  constexpr std::size_t kNi = 2000;
  std::vector<double> sd(kNi);
  ASSERT_EQ(imu::predict_integral_std(d, kNa, kNi, sd.data()), imu::ModelStatus::kOk);
  const double sigma2 = 2e-3 * 2e-3 / 0.01;
  for (std::size_t j : {std::size_t{1}, std::size_t{10}, std::size_t{999}, kNi}) {
    const double jj = static_cast<double>(j);
    const double r = jj / kNa;
    const double want =
        0.01 * 0.01 * sigma2 * (jj + jj * jj / kNa) + 1e-8 * (1.0 + (1.0 + r) * (1.0 + r) + r * r);
    // Sums of ~3000 positive terms in double: 1e-12 relative.
    EXPECT_NEAR(sd[j - 1] * sd[j - 1], want, 1e-12 * want) << j;
  }
  EXPECT_EQ(imu::predict_integral_std(d, 0, kNi, sd.data()), imu::ModelStatus::kBadParameter);
}

struct McResult {
  double robust_end;
  double plain_end;
};

// Independent windows: each starts a new realisation from the model's prior (steady state).
McResult monte_carlo(const imu::DiscreteModel<1>& d, std::size_t na, std::size_t ni,
                     std::size_t windows, std::uint64_t seed) {
  imu::ModelSimulator<1> sim;
  EXPECT_EQ(sim.configure(d, seed), imu::ModelStatus::kOk);
  std::vector<double> z(na + ni);
  std::vector<double> traj(ni);
  std::vector<double> ends(windows);
  double ss = 0.0;
  for (std::size_t w = 0; w < windows; ++w) {
    sim.restart();
    for (double& v : z) {
      v = sim.next();
    }
    imu::integrate_window(z.data(), na, ni, d.ts_s, traj.data());
    ends[w] = traj[ni - 1];
    ss += traj[ni - 1] * traj[ni - 1];  // mean is 0 by construction of the model
  }
  const double plain = std::sqrt(ss / static_cast<double>(windows));
  return McResult{imu::robust_std(ends.data(), windows), plain};
}

TEST(CovarianceCheck, ExactPredictionMatchesMonteCarloOnTheSeedModel) {
  // The example's check: T_avg = 10 s, T_int = 20 s, 100 Hz, first-order model; 2000 windows.
  imu::FirstOrderGm m{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, m), imu::ModelStatus::kOk);
  imu::ContinuousModel<1> c;
  ASSERT_EQ(c.add_white(m.n), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(m.sb, m.tb_s), imu::ModelStatus::kOk);
  imu::DiscreteModel<1> d;
  ASSERT_EQ(imu::discretize(c, m.ts_s, d), imu::ModelStatus::kOk);
  constexpr std::size_t kNa = 1000;
  constexpr std::size_t kNi = 2000;
  constexpr std::size_t kWindows = 2000;
  std::vector<double> exact(kNi);
  std::vector<double> ignored(kNi);
  ASSERT_EQ(imu::predict_integral_std(d, kNa, kNi, exact.data()), imu::ModelStatus::kOk);
  ASSERT_EQ(imu::predict_integral_std(d, kNa, kNi, ignored.data(),
                                      imu::CovPrediction::kCorrelationIgnored),
            imu::ModelStatus::kOk);
  const McResult mc = monte_carlo(d, kNa, kNi, kWindows, 99);
  const double ratio_robust = mc.robust_end / exact[kNi - 1];
  const double ratio_plain = mc.plain_end / exact[kNi - 1];
  const double ratio_ignored = mc.robust_end / ignored[kNi - 1];
  std::printf("covariance check (first-order model, %zu windows, T_avg 10 s, T_int 20 s): predicted std "
              "at 20 s %.4e (exact), %.4e (correlation ignored); empirical robust %.4e, plain "
              "%.4e; ratio robust/exact %.3f, plain/exact %.3f, robust/ignored %.3f\n",
              kWindows, exact[kNi - 1], ignored[kNi - 1], mc.robust_end, mc.plain_end,
              ratio_robust, ratio_plain, ratio_ignored);
  // Sampling error of the ratio with 2000 windows: plain std 1/sqrt(2 n) = 1.6 %, MAD-based
  // std 1.166/sqrt(n) = 2.6 % (normal data). Tolerance 4 standard errors.
  EXPECT_NEAR(ratio_plain, 1.0, 4.0 * 0.016);
  EXPECT_NEAR(ratio_robust, 1.0, 4.0 * 0.026);
  // Ignoring the correlation must be visibly wrong here (the bias barely changes in 30 s, so
  // the averaged estimate removes it almost entirely).
  EXPECT_LT(ratio_ignored, 1.0 - 4.0 * 0.026);
}

}  // namespace

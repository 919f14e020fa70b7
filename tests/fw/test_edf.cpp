// Tests of fw/include/imu/edf.hpp: chi-square quantiles against published values, the
// Greenhall-Riley EDF against allantools' intervals in ../shared/golden, the partially
// overlapping estimator's EDF against the fully overlapping one, and a Monte Carlo check.
#include "imu/edf.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../golden/golden_csv.hpp"
#include "imu/online_adev.hpp"

namespace {

TEST(Chi2, QuantilesMatchTables) {
  // Reference values: standard chi-square tables (e.g. NIST/SEMATECH e-Handbook 1.3.6.7.4).
  EXPECT_NEAR(imu::chi2_quantile(0.95, 10.0), 18.307038053275146, 1e-9);
  EXPECT_NEAR(imu::chi2_quantile(0.05, 10.0), 3.940299136119, 1e-9);
  EXPECT_NEAR(imu::chi2_quantile(0.975, 1.0), 5.023886187314888, 1e-9);
  EXPECT_NEAR(imu::chi2_quantile(0.5, 2.0), 2.0 * std::log(2.0), 1e-12);  // exact: 2 ln 2
  EXPECT_NEAR(imu::chi2_quantile(0.99, 100.0), 135.80672317102676, 1e-7);
  EXPECT_NEAR(imu::chi2_quantile(0.01, 100.0), 70.06489492788839, 1e-7);
  EXPECT_EQ(imu::chi2_quantile(0.0, 3.0), 0.0);
  EXPECT_EQ(imu::chi2_quantile(0.5, -1.0), 0.0);
}

TEST(Chi2, WilsonHilfertyBranchIsContinuous) {
  // The quantile switches method above dof 20000; compare both sides of the switch.
  for (double p : {0.158655, 0.841345, 0.025, 0.975}) {
    const double below = imu::chi2_quantile(p, 20000.0);
    const double above = imu::chi2_quantile(p, 20000.0 + 1e-9);
    EXPECT_NEAR(above / below, 1.0, 1e-7) << p;
  }
}

TEST(Chi2, GammaPLimits) {
  EXPECT_NEAR(imu::gamma_p(1.0, 1.0), 1.0 - std::exp(-1.0), 1e-14);
  EXPECT_NEAR(imu::gamma_p(0.5, 2.0), std::erf(std::sqrt(2.0)), 1e-14);
  EXPECT_NEAR(imu::gamma_p(300.0, 300.0), 0.5076771, 2e-5);  // 1/2 + 1/(3 sqrt(2 pi a))
}

using imu::test::read_golden;

// allantools computes its intervals with Greenhall's EDF (white FM, fully overlapping: stride
// factor S = m) and scipy's chi2.ppf. Our independent implementation must give the same interval
// to the 7 digits printed.
TEST(GreenhallEdf, ReproducesAllantoolsIntervals) {
  const std::string dir = std::string(IMU_SHARED_DIR) + "/golden";
  if (!std::filesystem::exists(dir)) {
    GTEST_SKIP() << "no " << dir;
  }
  int checked = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    for (const auto& r : read_golden(e.path().string())) {
      const double edf = imu::edf_greenhall(0, 2, r.af, r.af, r.n_terms);
      const imu::DevInterval ci = imu::deviation_interval(r.adev, edf);
      // Reason: the golden file prints 7 significant digits; at af > 3e5 (edf ~ 1, Greenhall case
      // 2.3) the two implementations differ by up to 3e-6.
      EXPECT_NEAR(ci.lo / r.lo, 1.0, 5e-6) << e.path() << " af " << r.af;
      EXPECT_NEAR(ci.hi / r.hi, 1.0, 5e-6) << e.path() << " af " << r.af;
      ++checked;
    }
  }
  EXPECT_GT(checked, 800);
}

// The partially overlapping estimate keeps >= 90 % of the fully overlapping EDF for
// white FM at every tau. Prints the table for the README.
TEST(GreenhallEdf, PartialOverlapKeepsNinetyPercent) {
  const double n_samples = 1e6;
  imu::OnlineAdev<8, 22> a;
  std::mt19937 rng(1);
  for (int i = 0; i < 1000000; ++i) {
    a.push(static_cast<std::int32_t>(rng() % 1000));
  }
  std::vector<imu::AdevPoint> pts(a.kMaxPoints);
  pts.resize(a.snapshot(pts.data(), pts.size()));
  std::printf("%10s %8s %12s %12s %12s %7s\n", "af", "stride", "terms", "edf_partial",
              "edf_full", "ratio");
  double worst = 1.0;
  for (const auto& p : pts) {
    const double full_terms = n_samples + 1.0 - 2.0 * p.af;
    const double edf_full = imu::edf_greenhall(0, 2, p.af, p.af, full_terms);
    const double ratio = p.edf / edf_full;
    worst = std::min(worst, ratio);
    std::printf("%10u %8u %12llu %12.5g %12.5g %7.4f\n", p.af, p.stride,
                static_cast<unsigned long long>(p.n_terms), p.edf, edf_full, ratio);
    EXPECT_GE(ratio, 0.90) << "af " << p.af;
  }
  std::printf("worst ratio %.4f\n", worst);
}

// Monte Carlo: the spread of the online estimate over independent white-noise records gives
// edf = 2 mean^2 / var (chi-square); it must agree with Greenhall's value for the partially
// overlapping estimate. 600 records of 4096 samples; the Monte Carlo edf has a relative standard
// error of sqrt(2/600) = 6 %, so 20 % is a 3-sigma bound.
TEST(GreenhallEdf, MonteCarloAgrees) {
  constexpr int kRecords = 600;
  constexpr int kSamples = 4096;
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 100.0);
  std::vector<std::vector<double>> avars;
  std::vector<imu::AdevPoint> last;
  for (int r = 0; r < kRecords; ++r) {
    imu::OnlineAdev<8, 10> a;
    for (int i = 0; i < kSamples; ++i) {
      a.push(static_cast<std::int32_t>(std::lround(g(rng))));
    }
    last.resize(a.kMaxPoints);
    last.resize(a.snapshot(last.data(), last.size()));
    avars.resize(last.size());
    for (std::size_t i = 0; i < last.size(); ++i) {
      avars[i].push_back(last[i].avar);
    }
  }
  int checked = 0;
  for (std::size_t i = 0; i < last.size(); ++i) {
    if (last[i].af < 10 || last[i].af > 128) {
      continue;  // partial overlap only; edf large enough for the chi-square picture
    }
    double mean = 0.0;
    for (double v : avars[i]) {
      mean += v;
    }
    mean /= kRecords;
    double var = 0.0;
    for (double v : avars[i]) {
      var += (v - mean) * (v - mean);
    }
    var /= (kRecords - 1);
    const double edf_mc = 2.0 * mean * mean / var;
    EXPECT_NEAR(edf_mc / last[i].edf, 1.0, 0.20) << "af " << last[i].af;
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(GreenhallEdf, InvalidArgumentsGiveZero) {
  EXPECT_EQ(imu::edf_greenhall(0, 2, 4.0, 8.0, 100.0), 0.0);  // stride factor > m
  EXPECT_EQ(imu::edf_greenhall(-3, 1, 4.0, 4.0, 100.0), 0.0); // alpha + 2d <= 1
  EXPECT_EQ(imu::edf_greenhall(0, 2, 4.0, 4.0, 0.0), 0.0);
  EXPECT_EQ(imu::edf_greenhall_modified(0, 2, 4.0, 8.0, 100.0), 0.0);
  EXPECT_EQ(imu::edf_greenhall_modified(-3, 1, 4.0, 4.0, 100.0), 0.0);
  EXPECT_EQ(imu::edf_greenhall_modified(0, 2, 4.0, 4.0, 0.0), 0.0);
  const imu::DevInterval ci = imu::deviation_interval(1.0, 0.0);
  EXPECT_EQ(ci.lo, 0.0);
  EXPECT_TRUE(std::isinf(ci.hi));
}

// The modified variance's EDF (MDEV, TDEV; fully overlapping, S = m) in each of Greenhall and
// Riley's three branches of case 1: the basic sum (J <= 100), table 1 (r > d + 1) and the basic
// sum with m' = 100 / r. Reference: allantools 2024.06 ci.edf_greenhall(alpha, d=2, m, N=3073,
// overlapping=True, modified=True), an independent implementation, printed with repr; the
// number of terms is N - 3m + 1. Both evaluate the same closed forms: 1e-12 relative covers
// the order of the sums.
TEST(GreenhallEdf, ModifiedMatchesAllantools) {
  struct Ref {
    int alpha;
    double m;
    double edf;
  };
  const Ref refs[] = {
      {0, 1.0, 2403.595480481969},     // basic sum, J = 3
      {0, 32.0, 90.63253973277344},    // basic sum, J = 96
      {0, 64.0, 44.16904931425355},    // table 1
      {0, 700.0, 2.230581804527173},   // m' = 100 / r
      {0, 1024.0, 1.0000028594748331}, // two terms
      {2, 64.0, 58.735822312179415},   {1, 64.0, 45.795084035244344},
      {-1, 64.0, 43.460518692903264},  {-2, 64.0, 34.904716061110385},
  };
  for (const Ref& r : refs) {
    const double n_terms = 3073.0 - 3.0 * r.m + 1.0;
    EXPECT_NEAR(imu::edf_greenhall_modified(r.alpha, 2, r.m, r.m, n_terms) / r.edf, 1.0, 1e-12)
        << "alpha " << r.alpha << " m " << r.m;
  }
}

}  // namespace

namespace {

// imu::log_gamma (fw's own, because newlib's lgamma writes outside its reent struct on the M4)
// against the host C library's std::lgamma, an independent implementation: over a from 1e-3
// to 1e5 (chi2_quantile uses a = dof / 2), agreement to 1e-13 relative or 1e-14 absolute (near
// a = 1 and 2, where ln Gamma crosses 0, only the absolute error is meaningful). Values typed
// from the definition: ln Gamma(1) = ln Gamma(2) = 0, ln Gamma(1/2) = ln sqrt(pi).
TEST(Edf, LogGammaMatchesTheCLibrary) {
  EXPECT_NEAR(imu::log_gamma(1.0), 0.0, 1e-14);
  EXPECT_NEAR(imu::log_gamma(2.0), 0.0, 1e-14);
  EXPECT_NEAR(imu::log_gamma(0.5), 0.5723649429247001, 1e-14);  // ln sqrt(pi)
  EXPECT_TRUE(std::isnan(imu::log_gamma(0.0)));
  EXPECT_TRUE(std::isnan(imu::log_gamma(-1.5)));
  double worst = 0.0;
  for (int i = 0; i < 273; ++i) {  // a = 1e-3 ... 1e5 in steps of 7 %
    const double a = 1e-3 * std::pow(1.07, i);
    const double want = std::lgamma(a);
    const double err = std::fabs(imu::log_gamma(a) - want);
    EXPECT_LE(err, std::fmax(1e-13 * std::fabs(want), 1e-14)) << "a = " << a;
    worst = std::fmax(worst, err / std::fmax(std::fabs(want), 1.0));
  }
  std::printf("log_gamma vs std::lgamma: worst error %.2e (relative, absolute below 1)\n", worst);
}

}  // namespace

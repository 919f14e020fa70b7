// Tests of imu/error_model.hpp and imu/linalg.hpp (expm, solve): the example's printed numbers,
// closed forms written here from MODELS.md, and Van Loan against known discretisations.
#include "imu/error_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "imu/linalg.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;

// Relative agreement to the 5 significant digits of a %.4e print: half a unit in the last
// printed digit is 5e-5 relative at worst (mantissa 1.0000).
void expect_printed(double value, double printed) {
  EXPECT_NEAR(value, printed, 0.5e-4 * std::fabs(printed) * 1.0001) << "printed " << printed;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4e", value);
  char want[32];
  std::snprintf(want, sizeof want, "%.4e", printed);
  EXPECT_STREQ(buf, want);
}

TEST(ErrorModel, SeedFirstOrderNumbersMatchThePrintedSeed) {
  imu::FirstOrderGm m{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, m), imu::ModelStatus::kOk);
  // Values typed from Farrell's ASD-to-state-space example (its printed output) and MODELS.md.
  expect_printed(m.mu_per_s, 6.3000e-03);
  expect_printed(m.sn, 1.0890e-05);
  expect_printed(m.sb, 2.6783e-08);
  expect_printed(m.pss, 2.1256e-06);
  expect_printed(m.qn, 1.0890e-03);
  expect_printed(std::sqrt(m.qn), 3.3000e-02);
  expect_printed(m.qw, 2.6781e-10);
  expect_printed(std::sqrt(m.qw), 1.6365e-05);
  expect_printed(m.pss_d, 2.1256e-06);
  char phi[16];
  std::snprintf(phi, sizeof phi, "%.4f", m.phi);
  EXPECT_STREQ(phi, "0.9999");
  // MODELS.md: phi = 0.99993700...; exp(-6.3e-5) to 1e-12 (double rounding).
  EXPECT_NEAR(m.phi, 0.99993700198, 1e-11);
}

TEST(ErrorModel, VanLoanMatchesClosedFormForFirstOrderGm) {
  imu::FirstOrderGm m{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, m), imu::ModelStatus::kOk);
  const double closed = (1.0 - m.phi * m.phi) * m.sb / (2.0 * m.mu_per_s);
  // expm in double: relative error a few ulp times the squarings; 1e-10 is generous.
  EXPECT_NEAR(m.qw, closed, 1e-10 * closed);
  EXPECT_NEAR(m.pss_d, m.pss, 1e-8 * m.pss);
}

TEST(ErrorModel, RejectsBadInputs) {
  imu::FirstOrderGm m{};
  EXPECT_EQ(imu::first_order_gm_from_asd(-1.0, 9e-4, 300.0, 100.0, m),
            imu::ModelStatus::kBadParameter);
  EXPECT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 0.0, 100.0, m),
            imu::ModelStatus::kBadParameter);
  EXPECT_EQ(imu::first_order_gm_from_asd(3.3e-3, std::nan(""), 300.0, 100.0, m),
            imu::ModelStatus::kBadParameter);
  // Finite, positive, but absurd: each gave kOk with a NaN phi, phi = 1 or an
  // infinite Qn before the derived quantities were checked.
  EXPECT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 1e-300, 100.0, m),
            imu::ModelStatus::kBadParameter);
  EXPECT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 1e300, 100.0, m),
            imu::ModelStatus::kBadParameter);
  EXPECT_EQ(imu::first_order_gm_from_asd(1e300, 9e-4, 300.0, 100.0, m),
            imu::ModelStatus::kBadParameter);
  imu::ContinuousModel<2> c;
  EXPECT_EQ(c.add_gauss_markov(1e-8, 100.0), imu::ModelStatus::kOk);
  EXPECT_EQ(c.add_ramp(1e-6), imu::ModelStatus::kCapacity);  // needs 2 states, 1 left
  EXPECT_EQ(c.n_states, 1U);
  EXPECT_EQ(c.add_rrw(0.0), imu::ModelStatus::kBadParameter);
  imu::DiscreteModel<2> d;
  EXPECT_EQ(imu::discretize(c, 0.0, d), imu::ModelStatus::kBadParameter);
}

TEST(ErrorModel, GmPeakMatchesTheTableConstants) {
  // MODELS.md: peak ADEV 0.4365 sqrt(Sb Tb) at tau = 1.89 Tb (4 printed digits).
  const double sb = 2e-8;
  const double tb = 50.0;
  double best = 0.0;
  double best_tau = 0.0;
  for (int i = 0; i < 9212; ++i) {  // 10 s to 1000 s in steps of 0.05 %
    const double tau = 10.0 * std::pow(1.0005, i);
    const double a = std::sqrt(imu::avar_gauss_markov(sb, tb, tau));
    if (a > best) {
      best = a;
      best_tau = tau;
    }
  }
  EXPECT_NEAR(best / std::sqrt(sb * tb), 0.4365, 1e-4);  // the table rounds to 4 digits
  EXPECT_NEAR(best_tau / tb, 1.89, 0.01);                // flat peak: 1.89 is 3 digits
}

TEST(ErrorModel, GmSmallTauSeriesIsContinuousWithTheExactForm) {
  // Across the switch at tau/Tb = 1e-3 the two forms must agree: the series is truncated at x^4
  // (relative error ~ x^3 = 1e-9), the expm1 form loses ~1e-16/x^2 = 1e-10 relative.
  const double tb = 100.0;
  const double lo = imu::avar_gauss_markov(1.0, tb, 0.1 * (1.0 - 1e-12));
  const double hi = imu::avar_gauss_markov(1.0, tb, 0.1 * (1.0 + 1e-12));
  EXPECT_NEAR(lo, hi, 1e-8 * hi);
  // Short tau: Sb (tau/3 - tau^2/(4 Tb)) from the Taylor expansion of the MODELS.md formula;
  // the next term is O((tau/Tb)^2) = 1e-12 relative.
  const double tau = 1e-4;
  const double want = tau / 3.0 - tau * tau / (4.0 * tb);
  EXPECT_NEAR(imu::avar_gauss_markov(1.0, tb, tau), want, 1e-11 * want);
}

TEST(ErrorModel, TermFormulas) {
  EXPECT_DOUBLE_EQ(imu::avar_white(2.0, 4.0), 1.0);
  EXPECT_DOUBLE_EQ(imu::avar_quantization(1.0, 3.0), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(imu::avar_rrw(3.0, 2.0), 6.0);
  EXPECT_DOUBLE_EQ(imu::avar_ramp(2.0, 3.0), 18.0);
  // Sinusoid: zero at tau = 1/f0, A^2 sin^4(pi/2)/(pi/2)^2 at tau = 1/(2 f0).
  EXPECT_NEAR(imu::avar_sinusoid(1.0, 2.0, 0.5), 0.0, 1e-30);
  EXPECT_NEAR(imu::avar_sinusoid(1.0, 2.0, 0.25), 4.0 / (kPi * kPi), 1e-15);
  imu::ModelParams p;
  p.n = 2.0;
  p.k = 3.0;
  EXPECT_DOUBLE_EQ(imu::model_avar(p, 2.0), 2.0 + 6.0);
}

TEST(Linalg, ExpmOfRotationAndNilpotent) {
  // expm([[0, w], [-w, 0]] t) = [[cos, sin], [-sin, cos]] (w t = 2.5 rad, needs squarings).
  imu::Mat<double, 3, 3> a{};
  a(0, 1) = 2.5;
  a(1, 0) = -2.5;
  imu::Mat<double, 3, 3> e{};
  ASSERT_TRUE(imu::expm(a, e, 2));
  // Pade [6/6] with scaling: accurate to a few ulp times 2^s; 1e-13 leaves margin.
  EXPECT_NEAR(e(0, 0), std::cos(2.5), 1e-13);
  EXPECT_NEAR(e(0, 1), std::sin(2.5), 1e-13);
  EXPECT_NEAR(e(1, 0), -std::sin(2.5), 1e-13);
  EXPECT_NEAR(e(2, 2), 0.0, 1e-300);  // outside the leading block: untouched zero
  // Nilpotent [[0, 1], [0, 0]] * 7: exact [[1, 7], [0, 1]].
  imu::Mat<double, 2, 2> nil{};
  nil(0, 1) = 7.0;
  imu::Mat<double, 2, 2> en{};
  ASSERT_TRUE(imu::expm(nil, en));
  EXPECT_NEAR(en(0, 1), 7.0, 1e-13);
  EXPECT_NEAR(en(0, 0), 1.0, 1e-14);
}

TEST(Linalg, LuSolveReportsSingular) {
  imu::Mat<double, 2, 2> a{};
  a(0, 0) = 1.0;
  a(0, 1) = 2.0;
  a(1, 0) = 2.0;
  a(1, 1) = 4.0;
  imu::Mat<double, 2, 1> b{};
  b(0, 0) = 1.0;
  imu::Mat<double, 2, 1> x{};
  x(0, 0) = 42.0;
  EXPECT_FALSE(imu::lu_solve(a, b, x));
  EXPECT_NEAR(x(0, 0), 42.0, 0.0);  // untouched on failure
  a(1, 1) = 5.0;
  b(1, 0) = 1.0;  // [1 2; 2 5] x = [1; 1] -> x = [3, -1]
  ASSERT_TRUE(imu::lu_solve(a, b, x));
  EXPECT_NEAR(x(0, 0), 3.0, 1e-14);
  EXPECT_NEAR(x(1, 0), -1.0, 1e-14);
}

TEST(ErrorModel, VanLoanForRampAndRrwIsExact) {
  // Ramp: Phi = [[1, Ts], [0, 1]], no process noise. RRW: Phi = 1, Qd = K^2 Ts.
  imu::ContinuousModel<6> c;
  ASSERT_EQ(c.add_rrw(2e-3), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_ramp(1e-5), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_sinusoid(1e-3, 0.5), imu::ModelStatus::kOk);
  EXPECT_EQ(c.n_states, 5U);
  imu::DiscreteModel<6> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  // All entries are O(1): 1e-14 absolute is ~100 ulp.
  EXPECT_NEAR(d.phi(0, 0), 1.0, 1e-14);
  EXPECT_NEAR(d.qd(0, 0), 4e-6 * 0.01, 1e-20);
  EXPECT_NEAR(d.phi(1, 2), 0.01, 1e-14);
  EXPECT_NEAR(d.phi(1, 1), 1.0, 1e-14);
  EXPECT_NEAR(d.qd(1, 1), 0.0, 1e-25);
  const double wt = 2.0 * kPi * 0.5 * 0.01;
  EXPECT_NEAR(d.phi(3, 3), std::cos(wt), 1e-14);
  EXPECT_NEAR(d.phi(3, 4), std::sin(wt), 1e-14);
  EXPECT_NEAR(d.phi(4, 3), -std::sin(wt), 1e-14);
  EXPECT_NEAR(d.phi(0, 3), 0.0, 1e-14);
}

TEST(ErrorModel, BuildModelRoundTripsParams) {
  imu::ModelParams p;
  p.n = 3.3e-3;
  p.q = 1e-5;
  p.n_gm = 2;
  p.gm[0] = {2e-8, 50.0};
  p.gm[1] = {1e-9, 500.0};
  p.k = 1e-4;
  imu::ContinuousModel<6> c;
  ASSERT_EQ(imu::build_model(p, c), imu::ModelStatus::kOk);
  EXPECT_EQ(c.n_states, 3U);
  for (double tau : {0.01, 1.0, 100.0, 1000.0}) {
    EXPECT_NEAR(c.avar(tau), imu::model_avar(p, tau), 1e-15 * imu::model_avar(p, tau));
  }
  p.n_gm = 3;  // more GM terms than kMaxGmTerms
  EXPECT_EQ(imu::build_model(p, c), imu::ModelStatus::kCapacity);
}

}  // namespace

// Bias instability: the flicker bank's ADEV against the exact flicker floor sqrt(2 ln 2 / pi) B
// (IEEE Std 952; computed here from the constant, not from the bank), and its state cost.
TEST(ErrorModel, FlickerBankFollowsTheFlickerFloor) {
  const double b = 2e-3;
  const double floor_adev = std::sqrt(2.0 * std::log(2.0) / 3.14159265358979323846) * b;
  EXPECT_NEAR(floor_adev / b, 0.664, 5e-4);  // MODELS.md's 0.664
  EXPECT_NEAR(std::sqrt(imu::avar_flicker_ideal(b)), floor_adev, 1e-15);
  // Three decades [1, 1000] s: 5 GMs; the documented band -4.6 % / +0.8 % (measured -4.6 / +0.8).
  imu::GmParam bank[imu::kMaxFlickerGm];
  EXPECT_EQ(imu::flicker_bank(b, 1.0, 1000.0, bank), 5U);
  double lo = 1.0;
  double hi = -1.0;
  for (int i = 0; i <= 60; ++i) {
    const double tau = std::pow(10.0, 3.0 * i / 60.0);
    const double rel = std::sqrt(imu::avar_flicker_bank(b, 1.0, 1000.0, tau)) / floor_adev - 1.0;
    lo = std::min(lo, rel);
    hi = std::max(hi, rel);
  }
  EXPECT_GT(lo, -0.047);
  EXPECT_LT(hi, 0.009);
  // Four decades (the analysis's range): 6 GMs, the same band.
  EXPECT_EQ(imu::flicker_bank(b, 0.1, 1000.0, bank), 6U);
  // More decades than kMaxFlickerGm members allow, or a bad range: refused.
  EXPECT_EQ(imu::flicker_bank(b, 1e-6, 1e6, bank), 0U);
  EXPECT_EQ(imu::flicker_bank(b, 10.0, 1.0, bank), 0U);
  EXPECT_EQ(imu::flicker_bank(0.0, 1.0, 10.0, bank), 0U);
}

TEST(ErrorModel, FlickerBankIsOneStatePerMemberAndDiscretises) {
  imu::ModelParams p;
  p.n = 3.3e-3;
  p.bi = 1e-3;
  p.bi_tau_lo_s = 0.1;
  p.bi_tau_hi_s = 1000.0;
  imu::ContinuousModel<16> c;
  ASSERT_EQ(imu::build_model(p, c), imu::ModelStatus::kOk);
  EXPECT_EQ(c.n_states, 6U);
  EXPECT_DOUBLE_EQ(c.params.bi, p.bi);
  imu::DiscreteModel<16> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  // Each member is a GM: phi = exp(-Ts/Tb) and steady variance Sb Tb / 2 (closed forms).
  imu::GmParam bank[imu::kMaxFlickerGm];
  ASSERT_EQ(imu::flicker_bank(p.bi, 0.1, 1000.0, bank), 6U);
  for (std::size_t i = 0; i < 6; ++i) {
    const double phi = std::exp(-0.01 / bank[i].tb_s);
    EXPECT_NEAR(d.phi(i, i), phi, 1e-12);
    const double qd = (1.0 - phi * phi) * bank[i].sb * bank[i].tb_s / 2.0;
    EXPECT_NEAR(d.qd(i, i), qd, 1e-9 * qd);
  }
  // Too many states for the capacity: refused, model unchanged.
  imu::ContinuousModel<4> small;
  EXPECT_EQ(imu::build_model(p, small), imu::ModelStatus::kCapacity);
}

// Narrowband oscillation: the closed form against a direct numerical evaluation of
// AVAR = Var(mean over tau) - Cov(consecutive means) from R(t) = s^2 e^-b|t| cos(w t)
// (written here: AVAR(tau) = (1/tau^2) [int_0^tau 2 (tau - u) R du - int_0^2tau min(u, 2tau - u)
// R du]), and its two limits: f0 = 0 is a first-order GM with Tb = 1/beta and Sb Tb / 2 =
// sigma^2; beta -> 0 is a sinusoid with A^2 / 2 = sigma^2.
double osc_avar_numeric(double sigma, double f0, double beta, double tau) {
  const auto r = [&](double u) {
    return sigma * sigma * std::exp(-beta * u) * std::cos(2.0 * kPi * f0 * u);
  };
  const int n = 200000;  // Simpson on [0, 2 tau]: error ~ (h^4) R'''' << 1e-9 relative here
  const double h = 2.0 * tau / n;
  double var = 0.0;
  double cov = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double u = i * h;
    const double wgt = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    const double ru = r(u);
    var += wgt * (u <= tau ? 2.0 * (tau - u) * ru : 0.0);
    cov += wgt * std::min(u, 2.0 * tau - u) * ru;
  }
  return (var - cov) * h / 3.0 / (tau * tau);
}

TEST(ErrorModel, OscillationAvarMatchesNumericAndItsLimits) {
  for (const double tau : {0.003, 0.01, 0.02, 0.05, 0.3, 2.0}) {
    const double exact = imu::avar_oscillation(2e-3, 19.6, 3.3, tau);
    const double num = osc_avar_numeric(2e-3, 19.6, 3.3, tau);
    // Simpson with 2e5 intervals over at most 80 periods: 1e-6 relative is ample margin.
    EXPECT_NEAR(exact, num, 1e-6 * num + 1e-18) << "tau " << tau;
  }
  // The series branch agrees with the closed form across the switch (|x| = 0.5): the two
  // sides 1e-6 apart in tau differ by the curve's own slope (~1e-6) plus rounding.
  const double t_switch = 0.5 / std::hypot(3.3, 2.0 * kPi * 19.6);
  EXPECT_NEAR(imu::avar_oscillation(1.0, 19.6, 3.3, t_switch * (1.0 - 1e-6)),
              imu::avar_oscillation(1.0, 19.6, 3.3, t_switch * (1.0 + 1e-6)),
              1e-5 * imu::avar_oscillation(1.0, 19.6, 3.3, t_switch));
  // f0 = 0: a GM with Tb = 1/beta, Sb = 2 sigma^2 beta. 1e-9: the GM's expm1 form itself
  // loses ~eps/x^2 (6e-11 relative at tau/Tb = 2e-3).
  for (const double tau : {0.01, 1.0, 30.0}) {
    EXPECT_NEAR(imu::avar_oscillation(1.5, 0.0, 0.2, tau),
                imu::avar_gauss_markov(2.0 * 1.5 * 1.5 * 0.2, 5.0, tau),
                1e-9 * imu::avar_gauss_markov(2.0 * 1.5 * 1.5 * 0.2, 5.0, tau));
  }
  // beta -> 0: a sinusoid of amplitude sqrt(2) sigma (tau well below 1/beta).
  for (const double tau : {0.013, 0.1, 0.37}) {
    const double sine = imu::avar_sinusoid(std::sqrt(2.0) * 0.7, 2.0, tau);
    EXPECT_NEAR(imu::avar_oscillation(0.7, 2.0, 1e-7, tau), sine, 1e-5 * sine + 1e-15);
  }
  imu::ModelParams p;
  p.osc_sigma = 2e-3;
  p.osc_f0_hz = 19.6;
  p.osc_beta_per_s = 3.3;
  EXPECT_DOUBLE_EQ(imu::model_avar(p, 0.02), imu::avar_oscillation(2e-3, 19.6, 3.3, 0.02));
}

// AVAR of means of m samples of a process with autocovariance r(d), d in samples, written from
// the definition: E (S2 - S1)^2 / (2 m^2) with S1, S2 the sums of samples 0..m-1 and m..2m-1.
template <typename R>
double sampled_avar_direct(R r, int m) {
  double e = 0.0;
  for (int i = 0; i < 2 * m; ++i) {
    for (int j = 0; j < 2 * m; ++j) {
      const double si = i < m ? -1.0 : 1.0;
      const double sj = j < m ? -1.0 : 1.0;
      e += si * sj * r(std::abs(i - j));
    }
  }
  return e / (2.0 * m * m);
}

TEST(ErrorModel, SampledOscillationAvarIsTheAvarOfSampleMeans) {
  // f0 = fs / 5 and a wide band: the case where sample means and continuous averages differ.
  constexpr double kTs = 0.01;
  constexpr double kSigma = 2e-3;
  for (const auto& shape : {std::pair{20.0, 12.0}, std::pair{3.1, 0.4}}) {
    const double f0 = shape.first;
    const double beta = shape.second;
    const auto r = [&](int d) {
      return kSigma * kSigma * std::exp(-beta * d * kTs) * std::cos(2.0 * kPi * f0 * d * kTs);
    };
    for (const int m : {1, 2, 3, 7, 40, 251}) {
      const double direct = sampled_avar_direct(r, m);
      const double formula = imu::avar_oscillation_sampled(kSigma, f0, beta, kTs, m * kTs);
      EXPECT_NEAR(formula, direct, 1e-9 * direct) << "f0 " << f0 << " m " << m;
    }
  }
  // A sinusoid (beta -> 0): sample means scale the continuous average's AVAR by
  // ((pi f0 Ts) / sin(pi f0 Ts))^2 at every m, 1.068^2 at f0 = fs / 5.
  const double x = kPi * 20.0 * kTs;
  const double factor = (x / std::sin(x)) * (x / std::sin(x));
  for (const int m : {3, 7, 12}) {
    const double cont = imu::avar_sinusoid(std::sqrt(2.0) * kSigma, 20.0, m * kTs);
    EXPECT_NEAR(imu::avar_oscillation_sampled(kSigma, 20.0, 1e-9, kTs, m * kTs), factor * cont,
                1e-5 * factor * cont)
        << "m " << m;
  }
  // Many samples per period: the continuous average's AVAR; off the sample grid, or Ts = 0: it.
  const double cont = imu::avar_oscillation(kSigma, 0.5, 0.3, 1.3);
  EXPECT_NEAR(imu::avar_oscillation_sampled(kSigma, 0.5, 0.3, 1e-4, 1.3), cont, 1e-6 * cont);
  EXPECT_DOUBLE_EQ(imu::avar_oscillation_sampled(kSigma, 0.5, 0.3, 0.0, 1.3), cont);
  EXPECT_DOUBLE_EQ(imu::avar_oscillation_sampled(kSigma, 0.5, 0.3, 0.3, 1.3), cont);
}

// A sinusoid in a record's samples (random phase: R(d) = A^2 / 2 cos(2 pi f0 d Ts)): the AVAR of
// its means of m samples from the definition, at f0 = fs / 5 (14 % above the continuous
// average's) and near Nyquist; off the sample grid or without a period, the continuous one.
TEST(ErrorModel, SampledSinusoidAvarIsTheAvarOfSampleMeans) {
  constexpr double kTs = 0.004;
  constexpr double kA = 3e-3;
  for (const double f0 : {50.0, 111.3, 0.7}) {
    const auto r = [&](int d) { return kA * kA / 2.0 * std::cos(2.0 * kPi * f0 * d * kTs); };
    for (const int m : {1, 2, 5, 9, 64, 301}) {
      const double direct = sampled_avar_direct(r, m);
      const double formula = imu::avar_sinusoid_sampled(kA, f0, kTs, m * kTs);
      EXPECT_NEAR(formula, direct, 1e-9 * kA * kA + 1e-9 * direct) << "f0 " << f0 << " m " << m;
    }
  }
  const double x = kPi * 50.0 * kTs;
  EXPECT_NEAR(imu::avar_sinusoid_sampled(kA, 50.0, kTs, 7 * kTs) /
                  imu::avar_sinusoid(kA, 50.0, 7 * kTs),
              (x / std::sin(x)) * (x / std::sin(x)), 1e-12);
  EXPECT_GT((x / std::sin(x)) * (x / std::sin(x)), 1.13);
  const double cont = imu::avar_sinusoid(kA, 50.0, 0.0301);
  EXPECT_DOUBLE_EQ(imu::avar_sinusoid_sampled(kA, 50.0, kTs, 0.0301), cont);
  EXPECT_DOUBLE_EQ(imu::avar_sinusoid_sampled(kA, 50.0, 0.0, 0.0301), cont);
}

TEST(ErrorModel, OscillationIsTwoStatesAndDiscretisesToADampedRotation) {
  imu::ModelParams p;
  p.n = 6.8e-4;
  p.osc_sigma = 4.7e-3;
  p.osc_f0_hz = 19.6;
  p.osc_beta_per_s = 3.3;
  imu::ContinuousModel<4> c;
  ASSERT_EQ(imu::build_model(p, c), imu::ModelStatus::kOk);
  EXPECT_EQ(c.n_states, 2U);
  imu::DiscreteModel<4> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  // Exact: Phi = e^(-beta Ts) [[cos, -sin], [sin, cos]](w Ts), Qd = sigma^2 (1 - e^(-2 beta Ts)) I
  // (the stationary covariance sigma^2 I is kept: P = Phi P Phi^T + Qd).
  const double rho = std::exp(-3.3 * 0.01);
  const double th = 2.0 * kPi * 19.6 * 0.01;
  EXPECT_NEAR(d.phi(0, 0), rho * std::cos(th), 1e-12);
  EXPECT_NEAR(d.phi(0, 1), -rho * std::sin(th), 1e-12);
  EXPECT_NEAR(d.phi(1, 0), rho * std::sin(th), 1e-12);
  const double qd = 4.7e-3 * 4.7e-3 * (1.0 - rho * rho);
  EXPECT_NEAR(d.qd(0, 0), qd, 1e-9 * qd);
  EXPECT_NEAR(d.qd(1, 1), qd, 1e-9 * qd);
  EXPECT_NEAR(d.qd(0, 1), 0.0, 1e-9 * qd);
  // A second oscillation does not fit the one-per-model slot; bad parameters are refused.
  EXPECT_EQ(c.add_oscillation(1e-3, 5.0, 1.0), imu::ModelStatus::kCapacity);
  imu::ContinuousModel<4> e;
  EXPECT_EQ(e.add_oscillation(1e-3, 5.0, 0.0), imu::ModelStatus::kBadParameter);
  EXPECT_EQ(e.add_oscillation(1e-3, -1.0, 1.0), imu::ModelStatus::kBadParameter);
  EXPECT_EQ(e.add_oscillation(std::nan(""), 5.0, 1.0), imu::ModelStatus::kBadParameter);
}

// Autocovariance c_l = H Phi^l Sigma H^T of the measured sequence (without the white part) of a
// stationary discrete model, Sigma = Phi Sigma Phi^T + Qd iterated to convergence.
template <std::size_t N>
void measured_autocovariance(const imu::DiscreteModel<N>& d, std::size_t lags, double* c) {
  using Sq = typename imu::DiscreteModel<N>::Square;
  Sq s = d.qd;
  for (int it = 0; it < 4000; ++it) {
    s = d.phi * s * d.phi.transpose() + d.qd;
  }
  Sq ps = s;  // Phi^l Sigma
  for (std::size_t l = 0; l <= lags; ++l) {
    double v = 0.0;
    for (std::size_t i = 0; i < d.n_states; ++i) {
      for (std::size_t j = 0; j < d.n_states; ++j) {
        v += d.h(0, i) * ps(i, j) * d.h(0, j);
      }
    }
    c[l] = v;
    ps = d.phi * ps;
  }
}

// AVAR at m samples of a stationary sequence with autocovariance c (c[0..2m]):
// (1 / 2m^2) var(S2 - S1), S1, S2 sums of m consecutive samples.
double avar_from_autocovariance(const double* c, std::size_t m) {
  double var_sum = 0.0;  // var(S1)
  double cov12 = 0.0;    // cov(S1, S2)
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      var_sum += c[i > j ? i - j : j - i];
      cov12 += c[m + j - i];
    }
  }
  return (2.0 * var_sum - 2.0 * cov12) / (2.0 * static_cast<double>(m * m));
}

TEST(ErrorModel, AveragedSamplingGivesTheGmAveragesAndTheAvarFormula) {
  // A GM of PSD Sb and time Tb has R(t) = P e^(-|t|/Tb), P = Sb Tb / 2. The mean of each
  // interval of Ts (a = Ts / Tb, g = Tb / Ts) has, by integrating R over two intervals:
  //   c_0 = 2 P g^2 (a - 1 + e^-a),  c_l = P g^2 e^(-(l-1) a) (1 - e^-a)^2  (l >= 1),
  // and its AVAR at tau = m Ts is the continuous-time formula (MODELS.md) exactly.
  const double ts = 0.01;
  for (const double tb : {0.25 * ts, 3.0 * ts, 40.0 * ts}) {
    imu::ContinuousModel<4> c;
    const double sb = 2.0e-3;
    ASSERT_EQ(c.add_white(5e-4), imu::ModelStatus::kOk);
    ASSERT_EQ(c.add_gauss_markov(sb, tb), imu::ModelStatus::kOk);
    imu::DiscreteModel<4> d;
    ASSERT_EQ(imu::discretize_averaged(c, ts, d), imu::ModelStatus::kOk);
    ASSERT_EQ(d.n_states, 2U);
    EXPECT_EQ(d.phi(1, 1), 0.0);
    EXPECT_NEAR(d.r_white, 5e-4 * 5e-4 / ts, 1e-15);
    constexpr std::size_t kLags = 17;
    double cv[kLags + 1] = {};
    measured_autocovariance(d, kLags, cv);
    const double p = sb * tb / 2.0;
    const double a = ts / tb;
    const double g = tb / ts;
    EXPECT_NEAR(cv[0], 2.0 * p * g * g * (a - 1.0 + std::exp(-a)), 1e-9 * cv[0]) << tb;
    for (std::size_t l = 1; l <= 3; ++l) {
      const double want = p * g * g * std::exp(-static_cast<double>(l - 1) * a) *
                          std::pow(1.0 - std::exp(-a), 2.0);
      EXPECT_NEAR(cv[l], want, 1e-9 * cv[0]) << tb << " lag " << l;
    }
    for (const std::size_t m : {1U, 2U, 4U, 8U}) {
      const double want = imu::avar_gauss_markov(sb, tb, static_cast<double>(m) * ts);
      EXPECT_NEAR(avar_from_autocovariance(cv, m), want, 1e-8 * want) << tb << " m " << m;
    }
    // Point samples of the same GM: lag-1 correlation e^-a, much less than the averages' for
    // Tb < Ts (0.018 against 0.13 of the GM part at Tb = Ts / 4).
    imu::DiscreteModel<4> dp;
    ASSERT_EQ(imu::discretize(c, ts, dp), imu::ModelStatus::kOk);
    EXPECT_NEAR(dp.phi(0, 0), std::exp(-a), 1e-12);
  }
  // No room for the mean, or nothing to average: refused.
  imu::ContinuousModel<2> full;
  ASSERT_EQ(full.add_gauss_markov(1e-3, 1.0), imu::ModelStatus::kOk);
  ASSERT_EQ(full.add_gauss_markov(1e-3, 10.0), imu::ModelStatus::kOk);
  imu::DiscreteModel<2> dd;
  EXPECT_EQ(imu::discretize_averaged(full, 0.01, dd), imu::ModelStatus::kCapacity);
  imu::ContinuousModel<2> empty;
  EXPECT_EQ(imu::discretize_averaged(empty, 0.01, dd), imu::ModelStatus::kBadParameter);
}

TEST(ErrorModel, FilteredWhiteIsAGmWhoseAveragesHaveTheWhiteAvarBentDown) {
  // White noise N through a first-order low-pass of Tf: a GM of Sb = N^2 / Tf^2, Tb = Tf. Its
  // AVAR tends to N^2 / tau (the same N at long tau) and lies below it by 1.5 N^2 Tf / tau^2.
  const double n = 7e-4;
  const double tf = 2.6e-3;
  const double ts = 0.01;
  for (const double tau : {0.01, 0.02, 0.1, 1.0}) {
    const double v = imu::avar_white_filtered(n, tf, tau);
    EXPECT_LT(v, n * n / tau);
    const double x = tau / tf;
    const double exact = n * n / tau * (1.0 - (3.0 - 4.0 * std::exp(-x) + std::exp(-2.0 * x)) /
                                                  (2.0 * x));
    EXPECT_NEAR(v, exact, 1e-12 * exact) << tau;
    if (x > 30.0) {
      EXPECT_NEAR(v, n * n / tau - 1.5 * n * n * tf / (tau * tau), 1e-6 * n * n / tau) << tau;
    }
  }
  EXPECT_DOUBLE_EQ(imu::avar_white_filtered(n, 0.0, 0.5), n * n / 0.5);
  imu::ModelParams p;
  p.n = n;
  p.n_filter_s = tf;
  EXPECT_DOUBLE_EQ(imu::model_avar(p, 0.03), imu::avar_white_filtered(n, tf, 0.03));
  imu::ContinuousModel<4> c;
  ASSERT_EQ(imu::build_model(p, c), imu::ModelStatus::kOk);
  ASSERT_EQ(c.n_states, 1U);
  EXPECT_EQ(c.sn, 0.0);
  EXPECT_DOUBLE_EQ(c.params.n, n);
  EXPECT_DOUBLE_EQ(c.params.n_filter_s, tf);
  imu::DiscreteModel<4> d;
  ASSERT_EQ(imu::discretize_averaged(c, ts, d), imu::ModelStatus::kOk);
  // No white measurement noise left: R is the floor, far below a sample's variance.
  EXPECT_GT(d.r_filter(), 0.0);
  EXPECT_LT(d.r_filter(), 1e-3 * n * n / ts);
  double cv[18] = {};
  measured_autocovariance(d, 17, cv);
  for (const std::size_t m : {1U, 2U, 8U}) {
    const double want = imu::avar_white_filtered(n, tf, static_cast<double>(m) * ts);
    EXPECT_NEAR(avar_from_autocovariance(cv, m), want, 1e-8 * want) << m;
  }
  // The lag-1 correlation of the samples: what the shared gyros show (about 0.17 at Tf = Ts/4).
  EXPECT_NEAR(cv[1] / cv[0], 0.166, 0.01);
  // A second white term, or a bad Tf, is refused.
  EXPECT_EQ(c.add_filtered_white(n, tf), imu::ModelStatus::kBadParameter);
  imu::ContinuousModel<4> e;
  EXPECT_EQ(e.add_filtered_white(n, -1.0), imu::ModelStatus::kBadParameter);
}

namespace {

// Van Loan of the whole model at once, written here from its definition (expm of the 2n x 2n
// matrix [[-F, Qc], [0, F^T]] Ts), with the sample mean J appended as one more state
// (J' = H x / Ts).
template <std::size_t kN>
void whole_van_loan(const imu::ContinuousModel<kN>& c, double ts, imu::Mat<double, kN, kN>& phi,
                    imu::Mat<double, kN, kN>& qd) {
  const std::size_t n = c.n_states + 1;
  imu::Mat<double, kN, kN> f = c.f;
  for (std::size_t j = 0; j + 1 < n; ++j) {
    f(n - 1, j) = c.h(0, j) / ts;
  }
  imu::Mat<double, 2 * kN, 2 * kN> a{};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      a(i, j) = -f(i, j) * ts;
      a(i, n + j) = c.qc(i, j) * ts;
      a(n + i, n + j) = f(j, i) * ts;
    }
  }
  imu::Mat<double, 2 * kN, 2 * kN> e{};
  ASSERT_TRUE(imu::expm(a, e, 2 * n));
  imu::Mat<double, kN, kN> m12{};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      phi(i, j) = e(n + j, n + i);
      m12(i, j) = e(i, n + j);
    }
  }
  qd = phi * m12;
}

}  // namespace

TEST(ErrorModel, BlockwiseVanLoanEqualsTheWholeModelAtOnce) {
  // Every kind of term at once (white, 2 GMs, a flicker bank, RRW, ramp, a sinusoid and an
  // oscillation: blocks of 1 and 2 states): discretising each block alone must give the
  // Phi and Qd of one matrix exponential of the whole model, sample mean included.
  imu::ModelParams p;
  p.n = 3e-3;
  p.gm[0] = {2e-4, 40.0};
  p.gm[1] = {5e-3, 0.3};
  p.bi = 1e-4;
  p.bi_tau_lo_s = 1.0;
  p.bi_tau_hi_s = 100.0;
  p.k = 2e-5;
  p.r = 1e-6;
  p.sin_a = 3e-4;
  p.sin_f0_hz = 0.05;
  p.osc_sigma = 1e-3;
  p.osc_f0_hz = 3.0;
  p.osc_beta_per_s = 0.4;
  imu::ContinuousModel<imu::kModelMaxStates> c;
  ASSERT_EQ(imu::build_model(p, c), imu::ModelStatus::kOk);
  ASSERT_GE(c.n_states, 10U);
  ASSERT_LT(c.n_states, imu::kModelMaxStates);
  for (const double ts : {0.001, 0.01, 0.5}) {
    imu::DiscreteModel<imu::kModelMaxStates> d;
    ASSERT_EQ(imu::discretize_averaged(c, ts, d), imu::ModelStatus::kOk);
    imu::Mat<double, imu::kModelMaxStates, imu::kModelMaxStates> phi{};
    imu::Mat<double, imu::kModelMaxStates, imu::kModelMaxStates> qd{};
    whole_van_loan(c, ts, phi, qd);
    const std::size_t n = c.n_states;
    phi(n, n) = 0.0;  // the mean is reset at every sample
    for (std::size_t i = 0; i <= n; ++i) {
      for (std::size_t j = 0; j <= n; ++j) {
        const double qscale = std::sqrt(std::fabs(qd(i, i) * qd(j, j)));
        EXPECT_NEAR(d.phi(i, j), phi(i, j), 1e-12 * (1.0 + std::fabs(phi(i, j))))
            << ts << " phi " << i << "," << j;
        EXPECT_NEAR(d.qd(i, j), qd(i, j), 1e-10 * qscale + 1e-300) << ts << " qd " << i << "," << j;
      }
    }
  }
}

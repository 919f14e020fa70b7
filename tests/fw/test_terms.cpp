// Tests of imu/terms.hpp, the term registry: its rows against the MODELS.md formulas (written
// here, not taken from the library), its state counts against the models build_model makes, and
// its accessors against the ModelParams fields they read.
#include "imu/terms.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "imu/model_fit.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;

// Every term once (two GMs and two sinusoids), with round numbers.
imu::ModelParams every_term() {
  imu::ModelParams p;
  p.n = 2e-3;
  p.q = 1e-4;
  p.n_gm = 2;
  p.gm[0] = {2.0 * 0.01 * 0.01 / 50.0, 50.0};   // sigma 0.01, Tb 50 s
  p.gm[1] = {2.0 * 0.003 * 0.003 / 0.5, 0.5};  // sigma 0.003, Tb 0.5 s
  p.k = 3e-5;
  p.r = 4e-7;
  p.sin_a = 5e-3;
  p.sin_f0_hz = 0.01;
  p.sin2_a = 2e-3;
  p.sin2_f0_hz = 0.02;
  p.bi = 6e-4;
  p.bi_tau_lo_s = 1.0;
  p.bi_tau_hi_s = 100.0;
  p.osc_sigma = 1e-3;
  p.osc_f0_hz = 2.0;
  p.osc_beta_per_s = 0.3;
  return p;
}

TEST(Terms, EveryRowIsAtItsKindsIndexWithAUniqueNameAndItsUnits) {
  for (std::size_t i = 0; i < imu::kTermKinds; ++i) {
    const imu::TermInfo& t = imu::kTermTable[i];
    EXPECT_EQ(static_cast<std::size_t>(t.kind), i);
    EXPECT_EQ(imu::term_by_name(t.name), &t) << t.name;
    ASSERT_GE(t.n_params, 1U);
    ASSERT_LE(t.n_params, imu::kMaxTermParams);
    EXPECT_LT(t.main_param, t.n_params);
    for (std::size_t j = 0; j < t.n_params; ++j) {
      EXPECT_NE(t.params[j].key, nullptr);
      EXPECT_NE(t.params[j].unit, nullptr);
    }
    EXPECT_GE(t.max_instances, 1U);
  }
  EXPECT_EQ(imu::term_by_name("bias_step"), nullptr);  // cleans the record, not a model term
  EXPECT_EQ(imu::term_by_name(nullptr), nullptr);
  EXPECT_STREQ(imu::term_info(imu::TermKind::kRateRandomWalk).params[0].unit, "u/sqrt(s)");
  EXPECT_STREQ(imu::term_info(imu::TermKind::kWhite).params[0].unit, "u/sqrt(Hz)");
}

TEST(Terms, FitBitsNameTheirRowAndTheSecondGmIsAGaussMarkov) {
  EXPECT_EQ(imu::term_by_fit_bit(imu::kFitRrw)->kind, imu::TermKind::kRateRandomWalk);
  EXPECT_EQ(imu::term_by_fit_bit(imu::kFitQuantization)->kind, imu::TermKind::kQuantization);
  EXPECT_EQ(imu::term_by_fit_bit(imu::kFitFlicker)->kind, imu::TermKind::kBiasInstability);
  EXPECT_EQ(imu::term_by_fit_bit(imu::kFitGm1)->kind, imu::TermKind::kGaussMarkov);
  EXPECT_EQ(imu::term_by_fit_bit(imu::kFitGm2)->kind, imu::TermKind::kGaussMarkov);
  EXPECT_EQ(imu::term_by_fit_bit(1U << 30), nullptr);
  EXPECT_EQ(imu::term_info(imu::TermKind::kSinusoid).fit_bit, 0U);  // fitted in the time domain
}

// MODELS.md's table, typed here.
TEST(Terms, EachRowsAvarIsTheFormulaSheets) {
  const imu::ModelParams p = every_term();
  for (const double tau : {0.01, 0.37, 1.0, 12.5, 300.0, 4000.0}) {
    const double x = kPi * 0.01 * tau;
    const double x2 = kPi * 0.02 * tau;
    const auto gm = [tau](double sb, double tb) {
      return sb * tb * tb / tau *
             (1.0 - tb / (2.0 * tau) *
                        (3.0 - 4.0 * std::exp(-tau / tb) + std::exp(-2.0 * tau / tb)));
    };
    using imu::TermKind;
    const auto rel = [](double a, double b) { return std::fabs(a - b) / b; };
    EXPECT_LT(rel(imu::term_avar(p, TermKind::kQuantization, 0, tau), 3e-8 / (tau * tau)), 1e-12);
    EXPECT_LT(rel(imu::term_avar(p, TermKind::kWhite, 0, tau), 4e-6 / tau), 1e-12);
    EXPECT_LT(rel(imu::term_avar(p, TermKind::kRateRandomWalk, 0, tau), 9e-10 * tau / 3.0), 1e-12);
    EXPECT_LT(rel(imu::term_avar(p, TermKind::kRamp, 0, tau), 16e-14 * tau * tau / 2.0), 1e-12);
    EXPECT_LT(rel(imu::term_avar(p, TermKind::kSinusoid, 0, tau),
                  25e-6 * std::pow(std::sin(x), 4) / (x * x)), 1e-9);
    EXPECT_LT(rel(imu::term_avar(p, TermKind::kSinusoid, 1, tau),
                  4e-6 * std::pow(std::sin(x2), 4) / (x2 * x2)), 1e-9);
    // (the closed form cancels below tau / Tb = 0.01; the library switches to a series there)
    if (tau >= 0.01 * 50.0) {
      EXPECT_LT(rel(imu::term_avar(p, TermKind::kGaussMarkov, 0, tau), gm(p.gm[0].sb, 50.0)),
                1e-9);
    }
    EXPECT_LT(rel(imu::term_avar(p, TermKind::kGaussMarkov, 1, tau), gm(p.gm[1].sb, 0.5)), 1e-9);
    // The model's AVAR is the sum of its rows' (each instance once).
    double sum = 0.0;
    for (const imu::TermInfo& t : imu::kTermTable) {
      for (std::size_t i = 0; i < t.max_instances; ++i) {
        sum += imu::term_avar(p, t.kind, i, tau);
      }
    }
    EXPECT_LT(rel(imu::model_avar(p, tau), sum), 1e-14);
  }
}

// The states column against the model build_model makes: every term alone, its states.
TEST(Terms, StatesPerInstanceAreThoseOfTheBuiltModel) {
  const imu::ModelParams all = every_term();
  for (const imu::TermInfo& t : imu::kTermTable) {
    imu::ModelParams only = all;  // with its white noise (a model needs it; it has no state)
    for (const imu::TermInfo& other : imu::kTermTable) {
      if (other.kind != t.kind && other.kind != imu::TermKind::kWhite) {
        imu::remove_term(only, other.kind);
      }
    }
    imu::ContinuousModel<imu::kModelMaxStates> m;
    ASSERT_EQ(imu::build_model(only, m), imu::ModelStatus::kOk) << t.name;
    std::size_t members = imu::term_instances(only, t.kind);
    if (t.kind == imu::TermKind::kBiasInstability) {
      imu::GmParam bank[imu::kMaxFlickerGm];
      members = imu::flicker_bank(all.bi, all.bi_tau_lo_s, all.bi_tau_hi_s, bank);
    }
    EXPECT_EQ(m.n_states, members * t.states) << t.name;
  }
}

// The first-order model of Farrell's example (N, B, Tp): white noise and one GM, as the
// first_order column says.
TEST(Terms, TheFirstOrderColumnIsTheExamplesModel) {
  imu::FirstOrderGm gm{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, gm), imu::ModelStatus::kOk);
  imu::ModelParams p;
  p.n = gm.n;
  p.n_gm = 1;
  p.gm[0] = {gm.sb, gm.tb_s};
  for (const imu::TermInfo& t : imu::kTermTable) {
    EXPECT_EQ(imu::term_instances(p, t.kind), t.first_order) << t.name;
  }
}

TEST(Terms, ParametersAreReadInTheRowsOrderAndUnits) {
  const imu::ModelParams p = every_term();
  using imu::TermKind;
  EXPECT_NEAR(imu::term_param(p, TermKind::kGaussMarkov, 0, 0), 0.01, 1e-15);  // sigma
  EXPECT_EQ(imu::term_param(p, TermKind::kGaussMarkov, 1, 1), 0.5);           // Tb
  EXPECT_EQ(imu::term_param(p, TermKind::kSinusoid, 1, 0), 0.02);             // f0
  EXPECT_EQ(imu::term_param(p, TermKind::kSinusoid, 1, 1), 2e-3);             // A
  EXPECT_NEAR(imu::term_param(p, TermKind::kOscillation, 0, 2), 0.3 / kPi, 1e-15);  // beta/pi
  EXPECT_EQ(imu::term_param(p, TermKind::kOscillation, 0, 1), 1e-3);          // sigma
  EXPECT_EQ(imu::term_param(p, TermKind::kBiasInstability, 0, 2), 100.0);     // tau_hi
  EXPECT_EQ(imu::term_param(p, TermKind::kRamp, 0, 1), 0.0);                  // no such param
  EXPECT_EQ(imu::term_param(p, TermKind::kRamp, 1, 0), 0.0);                  // no such instance
  for (const imu::TermInfo& t : imu::kTermTable) {
    EXPECT_EQ(imu::term_instances(p, t.kind), t.max_instances) << t.name;
  }
}

TEST(Terms, RemovingATermTakesExactlyItsAvarOut) {
  const imu::ModelParams all = every_term();
  for (const imu::TermInfo& t : imu::kTermTable) {
    for (std::size_t from = 0; from < t.max_instances; ++from) {
      imu::ModelParams p = all;
      imu::remove_term(p, t.kind, from);
      EXPECT_EQ(imu::term_instances(p, t.kind), from) << t.name;
      for (const double tau : {0.05, 3.0, 700.0}) {
        double gone = 0.0;
        for (std::size_t i = from; i < t.max_instances; ++i) {
          gone += imu::term_avar(all, t.kind, i, tau);
        }
        const double want = imu::model_avar(all, tau) - gone;
        EXPECT_NEAR(imu::model_avar(p, tau), want, 1e-12 * imu::model_avar(all, tau)) << t.name;
      }
    }
  }
}

// AVAR(tau) = 2 int_0^inf S(f) sin^4(pi f tau) / (pi f tau)^2 df, numerically: a fine linear
// grid up to 100 / tau, then a log grid with sin^4 at its mean 3/8 (its period in f, 1 / tau,
// is far below the grid's step there and S varies slowly).
double avar_from_psd(const imu::ModelParams& p, imu::TermKind k, std::size_t i, double tau_s,
                     double ts_s) {
  const auto integrand = [&](double f, bool mean) {
    const double x = kPi * f * tau_s;
    const double s4 = mean ? 0.375 : std::pow(std::sin(x), 4);
    return 2.0 * imu::term_psd(p, k, i, f, ts_s) * s4 / (x * x);
  };
  const double f_mid = 100.0 / tau_s;
  const int n_lin = 40000;
  const double df = f_mid / n_lin;
  double sum = 0.0;
  for (int j = 0; j < n_lin; ++j) {  // midpoints: no f = 0
    sum += integrand(df * (j + 0.5), false) * df;
  }
  const int per_decade = 4000;
  const double step = std::log(10.0) / per_decade;
  double prev = integrand(f_mid, true) * f_mid;
  for (int j = 1; j <= 6 * per_decade; ++j) {
    const double f = f_mid * std::exp(step * j);
    const double v = integrand(f, true) * f;
    sum += 0.5 * (prev + v) * step;
    prev = v;
  }
  return sum;
}

TEST(Terms, EachRowsPsdGivesItsAvar) {
  constexpr double kTs = 0.01;
  imu::ModelParams filtered;
  filtered.n = 3e-3;
  filtered.n_filter_s = 0.02;
  for (const imu::ModelParams& p : {every_term(), filtered}) {
    for (const imu::TermInfo& t : imu::kTermTable) {
      for (std::size_t i = 0; i < imu::term_instances(p, t.kind); ++i) {
        for (const double tau : {0.05, 3.0, 700.0}) {
          if (t.deterministic) {
            EXPECT_EQ(imu::term_psd(p, t.kind, i, 1.0 / tau, kTs), 0.0) << t.name;
            continue;
          }
          const double want = imu::term_avar(p, t.kind, i, tau);
          EXPECT_NEAR(avar_from_psd(p, t.kind, i, tau, kTs), want, 5e-3 * want)
              << t.name << " " << i << " at tau " << tau;
        }
      }
    }
  }
}

}  // namespace

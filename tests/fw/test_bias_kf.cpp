// Tests of imu/bias_kf.hpp: float on target vs double on host over 1e6 samples, covariance
// positivity and bound, steady state against the closed-form Riccati solution, static gating,
// the known signal, and the n-state filter against the scalar one.
#include "imu/bias_kf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>

#include "imu/error_model.hpp"
#include "imu/noise_sim.hpp"

namespace {

constexpr double kGravity = 9.80665;  // the known signal of a vertical accelerometer [m/s^2]

imu::FirstOrderGm example_model() {
  imu::FirstOrderGm m{};
  EXPECT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, m), imu::ModelStatus::kOk);
  return m;
}

imu::DiscreteModel<1> example_discrete(const imu::FirstOrderGm& m) {
  imu::ContinuousModel<1> c;
  EXPECT_EQ(c.add_white(m.n), imu::ModelStatus::kOk);
  EXPECT_EQ(c.add_gauss_markov(m.sb, m.tb_s), imu::ModelStatus::kOk);
  imu::DiscreteModel<1> d;
  EXPECT_EQ(imu::discretize(c, m.ts_s, d), imu::ModelStatus::kOk);
  return d;
}

// Posterior steady state of the scalar filter, written here from the Riccati equation:
// prior M = phi^2 P + Q, posterior P = M R / (M + R)  =>  phi^2 P^2 + (Q + R - phi^2 R) P - Q R = 0.
double riccati_posterior(double phi, double q, double r) {
  const double a = phi * phi;
  const double b = q + r - a * r;
  const double c = -q * r;
  return (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
}

TEST(BiasKf, FloatAgreesWithDoubleOverAMillionSamples) {
  const imu::FirstOrderGm m = example_model();
  const imu::DiscreteModel<1> d = example_discrete(m);
  imu::ModelSimulator<1> sim;
  ASSERT_EQ(sim.configure(d, 7), imu::ModelStatus::kOk);
  imu::ScalarBiasKf<float> kf_f;
  imu::ScalarBiasKf<double> kf_d;
  ASSERT_EQ(kf_f.configure(m, kGravity), imu::KfStatus::kOk);
  ASSERT_EQ(kf_d.configure(m, kGravity), imu::KfStatus::kOk);
  double max_db_sigma = 0.0;  // |b_float - b_double| / sqrt(P_double)
  double max_dp_rel = 0.0;    // |P_float / P_double - 1|
  double min_p = 1e30;
  double max_p = 0.0;
  for (int i = 0; i < 1000000; ++i) {
    const double z = kGravity + sim.next();
    // Static 9 s out of every 10 s: the filter also has to coast.
    const bool is_static = (i % 1000) < 900;
    (void)kf_d.step(z, is_static);
    (void)kf_f.step(static_cast<float>(z), is_static);
    const double p = kf_d.variance();
    const double db = std::fabs(static_cast<double>(kf_f.bias()) - kf_d.bias()) / std::sqrt(p);
    const double dp = std::fabs(static_cast<double>(kf_f.variance()) / p - 1.0);
    max_db_sigma = db > max_db_sigma ? db : max_db_sigma;
    max_dp_rel = dp > max_dp_rel ? dp : max_dp_rel;
    const double pf = static_cast<double>(kf_f.variance());
    min_p = pf < min_p ? pf : min_p;
    max_p = pf > max_p ? pf : max_p;
  }
  std::printf("float vs double over 1e6 samples: max |db| = %.3e sigma, max |dP/P| = %.3e, "
              "P_float in [%.3e, %.3e]\n", max_db_sigma, max_dp_rel, min_p, max_p);
  // Stated tolerance: the float bias stays within 1 % of the filter's own standard deviation
  // (measured: 4e-4). Why: z ~ 9.8 m/s^2 is rounded to float (half ulp 4.8e-7 m/s^2, 7e-4 of the
  // steady-state bias sigma 7e-4 m/s^2, and the filter averages those roundings over ~1/K =
  // 2000 samples); per-step rounding of b is 6e-8 relative and decays with the filter's time
  // constant, so the error stays a bounded sum of a few hundred ulp.
  EXPECT_LT(max_db_sigma, 0.01);
  // P in float: phi^2 = 1 - 1.26e-4 is rounded with 6e-8 absolute error, 5e-4 relative error in
  // the decay rate; the steady state moves by about that much. 1e-3 relative.
  EXPECT_LT(max_dp_rel, 1e-3);
  EXPECT_GT(min_p, 0.0);           // positive
  EXPECT_LE(max_p, m.pss_d * 1.001);  // bounded by the prior (Pss) up to float rounding
  EXPECT_EQ(kf_f.stats().covariance_floored, 0U);
  EXPECT_EQ(kf_f.stats().covariance_capped, 0U);
  EXPECT_EQ(kf_f.stats().updates, 900000U);
  EXPECT_EQ(kf_f.stats().predictions, 1000000U);
}

TEST(BiasKf, SteadyStateMatchesTheRiccatiSolution) {
  const imu::FirstOrderGm m = example_model();
  imu::ScalarBiasKf<double> kf;
  ASSERT_EQ(kf.configure(m), imu::KfStatus::kOk);
  for (int i = 0; i < 200000; ++i) {  // time constant ~ 1/sqrt(Q/R) = 2000 samples
    (void)kf.step(0.0, true);
  }
  const double want = riccati_posterior(m.phi, m.qw, m.qn);
  // Converged to machine precision after 100 time constants; 1e-9 relative.
  EXPECT_NEAR(kf.variance(), want, 1e-9 * want);
}

TEST(BiasKf, PredictsOnlyWhileNotStaticAndTracksAKnownSignal) {
  const imu::FirstOrderGm m = example_model();
  imu::ScalarBiasKf<double> kf;
  ASSERT_EQ(kf.configure(m, kGravity), imu::KfStatus::kOk);
  // Constant true bias 2e-3 on top of gravity, no noise: the estimate converges to it.
  for (int i = 0; i < 50000; ++i) {
    const imu::KfStep<double> s = kf.step(kGravity + 2e-3, true);
    ASSERT_TRUE(s.updated);
  }
  // The GM prior pulls b towards 0 at rate mu = 6.3e-3/s against gain K ~ 4e-4 per sample: the
  // fixed point is 2e-3 K / (K + (1 - phi)) ~ 2e-3 (1 - 0.15); 0.5e-3 absolute tolerance.
  EXPECT_NEAR(kf.bias(), 2e-3, 0.5e-3);
  const double p_static = kf.variance();
  const double b_static = kf.bias();
  for (int i = 0; i < 100; ++i) {
    const imu::KfStep<double> s = kf.step(1e9, false);  // garbage while moving: must be ignored
    EXPECT_FALSE(s.updated);
  }
  EXPECT_GT(kf.variance(), p_static);  // prediction only: P grows
  EXPECT_NEAR(kf.bias(), b_static * std::pow(m.phi, 100), 1e-15);  // b decays by phi^100
  EXPECT_EQ(kf.stats().updates, 50000U);
  (void)kf.step(std::nan(""), true);
  EXPECT_EQ(kf.stats().rejected_nonfinite, 1U);
}

// predict(k) replaces k prediction-only steps (lost samples). Up to kExactPredictSteps it is
// that loop; above, the closed form. Reference: the loop itself (k calls of step(z, false)) in
// double, which is what the closed form must reproduce; tolerance 1e-9 relative (pow and the
// geometric sum in double against k roundings of the loop, k <= 1e5: ~1e5 ulp = 2e-11).
TEST(BiasKf, PredictOfKStepsEqualsKPredictionsAndIsConstantTime) {
  const imu::FirstOrderGm m = example_model();
  for (std::uint64_t k : {std::uint64_t{1}, std::uint64_t{64}, std::uint64_t{65},
                          std::uint64_t{1000}, std::uint64_t{100000}}) {
    imu::ScalarBiasKf<double> a;
    imu::ScalarBiasKf<double> b;
    ASSERT_EQ(a.configure(m.phi, m.qw, m.qn, 1e-9, 1e-3, 0.0), imu::KfStatus::kOk);
    ASSERT_EQ(b.configure(m.phi, m.qw, m.qn, 1e-9, 1e-3, 0.0), imu::KfStatus::kOk);
    for (std::uint64_t i = 0; i < k; ++i) {
      (void)a.step(0.0, false);
    }
    b.predict(k);
    EXPECT_NEAR(b.variance(), a.variance(), 1e-9 * a.variance()) << "k = " << k;
    EXPECT_NEAR(b.bias(), a.bias(), 1e-9 * std::fabs(a.bias()) + 1e-300) << "k = " << k;
    EXPECT_EQ(b.stats().predictions, k);
  }
  // A jump of 2^31 samples (a hostile sequence number): far beyond the correlation time
  // (Tb = 159 s = 15,900 samples), so the prediction is the steady state Qw / (1 - phi^2) with
  // the bias forgotten; the node used to loop 2^31 steps here (seconds, test_node times it).
  imu::ScalarBiasKf<float> f;
  ASSERT_EQ(f.configure(m.phi, m.qw, m.qn, 1e-9, 1e-3, 0.0), imu::KfStatus::kOk);
  f.predict(std::uint64_t{1} << 31);
  // The float filter holds phi and Qw rounded to float, so its steady state is that of the
  // rounded parameters (1 - phi^2 = 1.3e-4 makes it 5e-4 away from m.pss_d); the result is one
  // rounding of the double closed form: 1e-6 relative.
  const auto phi_f = static_cast<double>(static_cast<float>(m.phi));
  const auto qw_f = static_cast<double>(static_cast<float>(m.qw));
  const double pss_f = qw_f / (1.0 - phi_f * phi_f);
  EXPECT_NEAR(static_cast<double>(f.variance()), pss_f, 1e-6 * pss_f);
  EXPECT_FLOAT_EQ(f.bias(), 0.0F);
  EXPECT_EQ(f.stats().predictions, std::uint64_t{1} << 31);
}

TEST(BiasKf, RejectsBadModels) {
  imu::ScalarBiasKf<float> kf;
  EXPECT_EQ(kf.configure(1.5, 1e-10, 1e-3, 1e-6, 0.0, 0.0), imu::KfStatus::kBadModel);
  EXPECT_EQ(kf.configure(0.99, -1.0, 1e-3, 1e-6, 0.0, 0.0), imu::KfStatus::kBadModel);
  EXPECT_EQ(kf.configure(0.99, 1e-10, 0.0, 1e-6, 0.0, 0.0), imu::KfStatus::kBadModel);
  imu::KalmanFilter<float, 2> kf2;
  imu::DiscreteModel<6> d;
  d.n_states = 3;
  d.ts_s = 0.01;
  d.r_white = 1.0;
  EXPECT_EQ(kf2.configure(d), imu::KfStatus::kBadModel);  // 3 states into a 2-state filter
}

TEST(BiasKf, NStateFilterWithOneStateEqualsTheScalarFilter) {
  const imu::FirstOrderGm m = example_model();
  const imu::DiscreteModel<1> d = example_discrete(m);
  imu::ScalarBiasKf<double> s;
  imu::KalmanFilter<double, 1> n;
  ASSERT_EQ(s.configure(d, kGravity), imu::KfStatus::kOk);
  ASSERT_EQ(n.configure(d, kGravity), imu::KfStatus::kOk);
  imu::ModelSimulator<1> sim;
  ASSERT_EQ(sim.configure(d, 3), imu::ModelStatus::kOk);
  for (int i = 0; i < 20000; ++i) {
    const double z = kGravity + sim.next();
    const bool st = (i / 500) % 2 == 0;
    const auto a = s.step(z, st);
    const auto b = n.step(z, st);
    ASSERT_EQ(a.updated, b.updated);
    // Same equations in a different order (matrix products): ~10 ulp of the values.
    ASSERT_NEAR(a.innovation, b.innovation, 1e-14);
    ASSERT_NEAR(s.bias(), n.bias(), 1e-14);
    ASSERT_NEAR(s.variance(), n.bias_variance(), 1e-12 * s.variance());
  }
}

TEST(BiasKf, ThreeStateFloatFilterIsConsistentOnSimulatedData) {
  // GM + RRW + white + quantization, simulated exactly; the float 3-state filter (GM, RRW and a
  // second GM) must give innovations with mean NIS ~ 1 and stay close to the double filter.
  imu::ContinuousModel<6> c;
  ASSERT_EQ(c.add_white(3.3e-3), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_quantization(2e-5), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(2.7e-8, 160.0), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(1e-6, 2.0), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_rrw(1.3e-4, 1e-6), imu::ModelStatus::kOk);
  imu::DiscreteModel<6> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  imu::ModelSimulator<6> sim;
  ASSERT_EQ(sim.configure(d, 11), imu::ModelStatus::kOk);
  imu::KalmanFilter<float, 3> kf;
  imu::KalmanFilter<double, 3> kd;
  ASSERT_EQ(kf.configure(d), imu::KfStatus::kOk);
  ASSERT_EQ(kd.configure(d), imu::KfStatus::kOk);
  double nis_sum = 0.0;
  double max_db_sigma = 0.0;
  constexpr int kN = 200000;
  for (int i = 0; i < kN; ++i) {
    const double z = sim.next();
    const auto sd = kd.step(z, true);
    (void)kf.step(static_cast<float>(z), true);
    nis_sum += sd.nis();
    const double db = std::fabs(static_cast<double>(kf.bias()) - kd.bias()) /
                      std::sqrt(kd.bias_variance());
    max_db_sigma = db > max_db_sigma ? db : max_db_sigma;
  }
  const double nis_mean = nis_sum / kN;
  std::printf("3-state: mean NIS %.4f, max |db| float vs double %.3e sigma\n", nis_mean,
              max_db_sigma);
  // The quantization MA(1) noise is treated as white: its variance 2 Q^2/Ts^2 = 8e-6 is 0.7 % of
  // R, so the NIS mean is 1 within that plus the sampling error sqrt(2/2e5) = 0.3 % (x 4 sigma).
  EXPECT_NEAR(nis_mean, 1.0, 0.007 + 4.0 * std::sqrt(2.0 / kN));
  // Float 3-state: rounding of the 3x3 products and of P entries spanning 1e-14..1e-6; 5 % sigma.
  EXPECT_LT(max_db_sigma, 0.05);
  EXPECT_EQ(kf.stats().covariance_floored, 0U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_GT(kf.covariance()(i, i), 0.0F);
  }
}

TEST(BiasKf, CovarianceOfAnUnobservedRandomWalkIsCappedAndStaysPsd) {
  // GM + RRW, never static: the RRW variance grows by K^2 Ts per sample without bound; the cap
  // (1e6 x the largest initial/per-step variance = 1e6 x 1e-2) must hold it, and the capped P
  // must stay positive semi-definite (2x2: diagonals >= 0, determinant >= 0).
  imu::ContinuousModel<6> c;
  ASSERT_EQ(c.add_white(1e-2), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(1e-4, 10.0), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_rrw(1.0), imu::ModelStatus::kOk);  // K^2 Ts = 1e-2 per sample
  imu::DiscreteModel<6> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  imu::KalmanFilter<double, 2> kf;
  ASSERT_EQ(kf.configure(d), imu::KfStatus::kOk);
  // A few updates first so that P has off-diagonal terms (the states are correlated through z).
  for (int i = 0; i < 100; ++i) {
    (void)kf.step(0.0, true);
  }
  for (int i = 0; i < 1200000; ++i) {  // 1.2e6 x 1e-2 = 1.2e4 > cap 1e4 (GM prior 5e-4)
    (void)kf.step(0.0, false);
  }
  const auto& p = kf.covariance();
  EXPECT_GT(kf.stats().covariance_capped, 0U);
  EXPECT_LE(p(1, 1), 1e4 * (1.0 + 1e-12));  // the cap, up to the rounding of the scaling
  EXPECT_GE(p(0, 0), 0.0);
  EXPECT_GE(p(0, 0) * p(1, 1) - p(0, 1) * p(1, 0), -1e-12 * p(0, 0) * p(1, 1));
}

}  // namespace

namespace {

// GM (2 s) + GM (16 s) + RRW + white, seen through the averaging sampler (4 states: three
// diagonal ones and the sample mean, whose row of Phi is dense).
imu::DiscreteModel<6> steady_test_model() {
  imu::ContinuousModel<6> c;
  EXPECT_EQ(c.add_white(3.3e-3), imu::ModelStatus::kOk);
  EXPECT_EQ(c.add_gauss_markov(1e-6, 2.0), imu::ModelStatus::kOk);
  EXPECT_EQ(c.add_gauss_markov(1e-7, 16.0), imu::ModelStatus::kOk);
  EXPECT_EQ(c.add_rrw(1.3e-4, 1e-6), imu::ModelStatus::kOk);
  imu::DiscreteModel<6> d;
  EXPECT_EQ(imu::discretize_averaged(c, 0.01, d), imu::ModelStatus::kOk);
  EXPECT_EQ(d.n_states, 4U);
  return d;
}

// The discrete algebraic Riccati equation's gain and innovation variance, by iterating the
// Riccati recursion in long double (plain arrays, no filter code) until P stops changing.
template <std::size_t kN>
void dare_gain(const imu::DiscreteModel<6>& d, long double (&k)[kN], long double& s) {
  long double p[kN][kN] = {};
  for (std::size_t i = 0; i < kN; ++i) {
    for (std::size_t j = 0; j < kN; ++j) {
      p[i][j] = static_cast<long double>(d.p0(i, j));
    }
  }
  for (int it = 0; it < 2000000; ++it) {
    long double t[kN][kN] = {};
    long double m[kN][kN] = {};
    for (std::size_t i = 0; i < kN; ++i) {
      for (std::size_t j = 0; j < kN; ++j) {
        for (std::size_t q = 0; q < kN; ++q) {
          t[i][j] += static_cast<long double>(d.phi(i, q)) * p[q][j];
        }
      }
    }
    for (std::size_t i = 0; i < kN; ++i) {
      for (std::size_t j = 0; j < kN; ++j) {
        m[i][j] = static_cast<long double>(d.qd(i, j));
        for (std::size_t q = 0; q < kN; ++q) {
          m[i][j] += t[i][q] * static_cast<long double>(d.phi(j, q));
        }
      }
    }
    long double ph[kN] = {};
    s = static_cast<long double>(d.r_filter());
    for (std::size_t i = 0; i < kN; ++i) {
      for (std::size_t j = 0; j < kN; ++j) {
        ph[i] += m[i][j] * static_cast<long double>(d.h(0, j));
      }
      s += static_cast<long double>(d.h(0, i)) * ph[i];
    }
    long double change = 0.0L;
    for (std::size_t i = 0; i < kN; ++i) {
      k[i] = ph[i] / s;
    }
    for (std::size_t i = 0; i < kN; ++i) {
      for (std::size_t j = 0; j < kN; ++j) {
        const long double next = m[i][j] - k[i] * s * k[j];  // (I - K H) M, symmetric form
        change = std::fmax(change, std::fabs(next - p[i][j]) / (std::fabs(next) + 1e-300L));
        p[i][j] = next;
      }
    }
    if (it > 1000 && change < 1e-15L) {
      break;
    }
  }
}

}  // namespace

TEST(KfSteadyState, FrozenGainEqualsTheRiccatiSolution) {
  const imu::DiscreteModel<6> d = steady_test_model();
  imu::KalmanFilter<float, 4> kf;
  ASSERT_EQ(kf.configure(d), imu::KfStatus::kOk);
  kf.set_steady_state(true);
  EXPECT_TRUE(kf.steady_allowed());
  EXPECT_EQ(kf.phi_nonzeros(), 3U + 3U);  // three diagonal states, the mean's row (Phi(J,J) = 0)
  imu::ModelSimulator<6> sim;
  ASSERT_EQ(sim.configure(d, 5), imu::ModelStatus::kOk);
  int frozen_at = -1;
  for (int i = 0; i < 200000 && frozen_at < 0; ++i) {
    (void)kf.step(static_cast<float>(sim.next()), true);
    frozen_at = kf.steady() ? i : -1;
  }
  ASSERT_GE(frozen_at, 0) << "the gain never froze";
  long double k_ref[4];
  long double s_ref = 0.0L;
  dare_gain<4>(d, k_ref, s_ref);
  long double kmax = 0.0L;
  for (const long double v : k_ref) {
    kmax = std::fmax(kmax, std::fabs(v));
  }
  std::printf("steady gain froze after %d updates; K vs DARE:", frozen_at + 1);
  for (std::size_t i = 0; i < 4; ++i) {
    const auto got = static_cast<long double>(kf.steady_gain()(i, 0));
    std::printf(" %.6Le/%.6Le", got, k_ref[i]);
    // Float filter (relative rounding ~1e-6 in P's products) plus the freeze tolerance 1e-5.
    EXPECT_LE(std::fabs(got - k_ref[i]), 1e-4L * kmax) << "state " << i;
  }
  std::printf("; S %.6e/%.6Le\n", static_cast<double>(kf.steady_innovation_var()), s_ref);
  EXPECT_LE(std::fabs(static_cast<long double>(kf.steady_innovation_var()) - s_ref),
            1e-4L * s_ref);
}

TEST(KfSteadyState, EstimatesMatchTheTimeVaryingFilterAndNisStaysConsistent) {
  const imu::DiscreteModel<6> d = steady_test_model();
  imu::KalmanFilter<float, 4> ss;
  imu::KalmanFilter<float, 4> tv;
  ASSERT_EQ(ss.configure(d), imu::KfStatus::kOk);
  ASSERT_EQ(tv.configure(d), imu::KfStatus::kOk);
  ss.set_steady_state(true);
  imu::ModelSimulator<6> sim;
  ASSERT_EQ(sim.configure(d, 17), imu::ModelStatus::kOk);
  double max_db_sigma = 0.0;
  double nis_sum = 0.0;
  long steady_steps = 0;
  for (int i = 0; i < 300000; ++i) {
    const auto z = static_cast<float>(sim.next());
    const auto a = ss.step(z, true);
    const auto b = tv.step(z, true);
    ASSERT_TRUE(a.updated);
    if (ss.steady()) {
      ++steady_steps;
      ASSERT_EQ(a.innovation_var, ss.steady_innovation_var());  // S frozen with the gain
      nis_sum += static_cast<double>(a.nis());
      // The time-varying filter's S has converged too: same value within the freeze tolerance.
      ASSERT_NEAR(a.innovation_var, b.innovation_var, 1e-4F * b.innovation_var);
      const double db = std::fabs(static_cast<double>(ss.bias()) - static_cast<double>(tv.bias()));
      max_db_sigma = std::fmax(max_db_sigma, db / std::sqrt(static_cast<double>(tv.bias_variance())));
    }
  }
  EXPECT_FALSE(tv.steady());  // off by default
  ASSERT_GT(steady_steps, 250000);
  const double nis_mean = nis_sum / static_cast<double>(steady_steps);
  std::printf("steady vs time-varying: %ld steady steps, max |db| %.3e sigma, mean NIS %.4f\n",
              steady_steps, max_db_sigma, nis_mean);
  EXPECT_LT(max_db_sigma, 0.01);
  EXPECT_NEAR(nis_mean, 1.0, 4.0 * std::sqrt(2.0 / static_cast<double>(steady_steps)) + 0.01);
  EXPECT_EQ(ss.stats().updates, tv.stats().updates);
  EXPECT_EQ(ss.stats().predictions, tv.stats().predictions);
}

TEST(KfSteadyState, AGapOrANonFiniteSampleRevertsToTimeVaryingUntilReconverged) {
  const imu::DiscreteModel<6> d = steady_test_model();
  imu::KalmanFilter<float, 4> kf;
  ASSERT_EQ(kf.configure(d), imu::KfStatus::kOk);
  kf.set_steady_state(true);
  imu::ModelSimulator<6> sim;
  ASSERT_EQ(sim.configure(d, 23), imu::ModelStatus::kOk);
  for (int i = 0; i < 200000 && !kf.steady(); ++i) {
    (void)kf.step(static_cast<float>(sim.next()), true);
  }
  ASSERT_TRUE(kf.steady());
  const float s_frozen = kf.steady_innovation_var();
  for (int gap = 0; gap < 2; ++gap) {
    if (gap == 0) {
      for (int i = 0; i < 500; ++i) {
        (void)kf.step(static_cast<float>(sim.next()), false);  // 5 s not static: no update
        ASSERT_FALSE(kf.steady());
      }
    } else {
      (void)sim.next();
      (void)kf.step(std::nanf(""), true);  // rejected: a prediction only
      ASSERT_FALSE(kf.steady());
    }
    // P grew during the gap: the first update's S exceeds the steady one.
    const auto first = kf.step(static_cast<float>(sim.next()), true);
    EXPECT_GT(first.innovation_var, s_frozen);
    int updates = 1;
    while (!kf.steady() && updates < 200000) {
      (void)kf.step(static_cast<float>(sim.next()), true);
      ++updates;
    }
    ASSERT_TRUE(kf.steady());
    EXPECT_GE(updates, static_cast<int>(imu::KalmanFilter<float, 4>::kSteadyBlock));
    EXPECT_NEAR(kf.steady_innovation_var(), s_frozen, 1e-4F * s_frozen);
  }
  kf.set_steady_state(false);
  EXPECT_FALSE(kf.steady());
}

TEST(KfSteadyState, UndrivenSinusoidStaysTimeVaryingAndInertStatesDoNotPreventIt) {
  imu::ContinuousModel<6> c;
  ASSERT_EQ(c.add_white(3.3e-3), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(1e-6, 2.0), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_sinusoid(1e-3, 0.5), imu::ModelStatus::kOk);
  imu::DiscreteModel<6> d;
  ASSERT_EQ(imu::discretize(c, 0.01, d), imu::ModelStatus::kOk);
  ASSERT_EQ(d.n_states, 3U);
  imu::KalmanFilter<float, 3> kf;
  ASSERT_EQ(kf.configure(d), imu::KfStatus::kOk);
  kf.set_steady_state(true);
  EXPECT_FALSE(kf.steady_allowed());
  imu::ModelSimulator<6> sim;
  ASSERT_EQ(sim.configure(d, 29), imu::ModelStatus::kOk);
  for (int i = 0; i < 100000; ++i) {
    (void)kf.step(static_cast<float>(sim.next()), true);
    ASSERT_FALSE(kf.steady());
  }
  // The GM alone padded with an inert state (Phi = Qd = P0 = H = 0, as the node pads models).
  imu::ContinuousModel<6> g;
  ASSERT_EQ(g.add_white(3.3e-3), imu::ModelStatus::kOk);
  ASSERT_EQ(g.add_gauss_markov(1e-6, 2.0), imu::ModelStatus::kOk);
  imu::DiscreteModel<6> gd;
  ASSERT_EQ(imu::discretize(g, 0.01, gd), imu::ModelStatus::kOk);
  gd.n_states = 2;
  imu::KalmanFilter<float, 2> kg;
  ASSERT_EQ(kg.configure(gd), imu::KfStatus::kOk);
  kg.set_steady_state(true);
  EXPECT_TRUE(kg.steady_allowed());
  EXPECT_EQ(kg.phi_nonzeros(), 1U);
  imu::ModelSimulator<6> gs;
  ASSERT_EQ(gs.configure(gd, 31), imu::ModelStatus::kOk);
  for (int i = 0; i < 100000 && !kg.steady(); ++i) {
    (void)kg.step(static_cast<float>(gs.next()), true);
  }
  EXPECT_TRUE(kg.steady());
  EXPECT_EQ(kg.steady_gain()(1, 0), 0.0F);
}

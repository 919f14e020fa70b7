// Tests of imu/residual_monitor.hpp: false-alarm rates on white N(0,1) input against their
// stated confidence, detection of correlated innovations, wrong variance and a step, and the
// monitors fed by the bias filter on simulated data with an injected bias step.
#include "imu/residual_monitor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "imu/bias_kf.hpp"
#include "imu/error_model.hpp"
#include "imu/noise_sim.hpp"

namespace {

TEST(ResidualMonitor, RejectsBadConfig) {
  imu::NisMonitor nis;
  EXPECT_EQ(nis.configure(1), imu::MonitorStatus::kBadConfig);
  EXPECT_EQ(nis.configure(100, 1.0), imu::MonitorStatus::kBadConfig);
  imu::WhitenessMonitor<4> w;
  EXPECT_EQ(w.configure(8), imu::MonitorStatus::kBadConfig);  // < 4 kLags
  imu::Cusum c;
  EXPECT_EQ(c.configure(0.5F, 0.0F), imu::MonitorStatus::kBadConfig);
}

TEST(ResidualMonitor, NisBoundsAreTheChiSquareQuantiles) {
  imu::NisMonitor nis;
  ASSERT_EQ(nis.configure(1000, 0.99), imu::MonitorStatus::kOk);
  // chi2 quantiles for 1000 dof at 0.005 and 0.995 by Wilson-Hilferty, computed by hand:
  // k (1 - 2/(9k) -+ 2.5758 sqrt(2/(9k)))^3 / k = 0.96138^3, 1.038176^3 = 0.88856, 1.11893
  // (the approximation is good to ~1e-4 at 1000 dof); 5e-4 covers it and the float rounding.
  EXPECT_NEAR(nis.bound_lo(), 0.88856F, 5e-4F);
  EXPECT_NEAR(nis.bound_hi(), 1.11893F, 5e-4F);
}

TEST(ResidualMonitor, WhiteInputRaisesFewAlarmsAndScaledInputIsFlagged) {
  imu::GaussianRng rng(17);
  imu::ResidualMonitors<4> mon;
  ASSERT_EQ(mon.configure(1000), imu::MonitorStatus::kOk);
  ASSERT_EQ(mon.cusum.configure(0.5F, 5.0F), imu::MonitorStatus::kOk);  // short ARL: countable
  constexpr int kBlocks = 400;
  std::uint32_t cusum_alarms = 0;
  for (int i = 0; i < kBlocks * 1000; ++i) {
    mon.push(static_cast<float>(rng.normal()), 1.0F);
    if (mon.cusum.alarm()) {
      ++cusum_alarms;
      mon.cusum.reset();
    }
  }
  ASSERT_EQ(mon.nis.blocks(), static_cast<std::uint32_t>(kBlocks));
  std::printf("white input, %d blocks: NIS flagged %u, Box-Pierce flagged %u, CUSUM alarms %u "
              "in 4e5 updates\n", kBlocks, mon.nis.flagged_blocks(),
              mon.whiteness.flagged_blocks(), cusum_alarms);
  // NIS at 99 %: expected 4 of 400 flagged; binomial 99.9 % upper bound 12.
  EXPECT_LE(mon.nis.flagged_blocks(), 12U);
  // Box-Pierce at 95 %: expected 20 of 400; 99.9 % upper bound 35.
  EXPECT_LE(mon.whiteness.flagged_blocks(), 35U);
  // CUSUM k = 0.5, h = 5: two-sided in-control average run length ~470 updates (Siegmund's
  // approximation, 938 per side), so about 850 alarms in 4e5 updates; a broken recursion gives
  // 0 or ~4e5. Band 500..1300 (the approximation is good to ~10 %, the count's sd is ~30).
  EXPECT_GT(cusum_alarms, 500U);
  EXPECT_LT(cusum_alarms, 1300U);

  // Innovation variance 1.2x what the filter claims: every NIS block mean ~1.2 > 1.121.
  imu::NisMonitor nis;
  ASSERT_EQ(nis.configure(1000, 0.99), imu::MonitorStatus::kOk);
  for (int i = 0; i < 10000; ++i) {
    nis.push(static_cast<float>(std::sqrt(1.2) * rng.normal()));
  }
  EXPECT_GE(nis.flagged_blocks(), 9U);  // P(mean < 1.121 | 1.2) ~ 5e-2 per block
  EXPECT_NEAR(nis.last_block_mean(), 1.2F, 0.15F);  // 4 sigma of the block mean (0.054)
}

TEST(ResidualMonitor, CorrelatedInnovationsAreFlagged) {
  // AR(1) with rho = 0.2, unit variance: r_1 ~ 0.2 >> 2/sqrt(1000) = 0.063.
  imu::GaussianRng rng(3);
  imu::WhitenessMonitor<4> w;
  ASSERT_EQ(w.configure(1000), imu::MonitorStatus::kOk);
  double prev = 0.0;
  const double rho = 0.2;
  for (int i = 0; i < 5000; ++i) {
    const double x = rho * prev + std::sqrt(1.0 - rho * rho) * rng.normal();
    prev = x;
    w.push(static_cast<float>(x));
  }
  EXPECT_EQ(w.blocks(), 5U);
  EXPECT_EQ(w.flagged_blocks(), 5U);  // Q ~ 1000 * 0.042 = 42 vs bound 9.49
  EXPECT_TRUE(w.lag_flag(1));
  // Sampling sd of r_1 is ~1/sqrt(1000) = 0.032: 3 sd.
  EXPECT_NEAR(w.autocorrelation(1), 0.2F, 0.1F);
  EXPECT_NEAR(w.autocorrelation(2), 0.04F, 0.1F);
}

TEST(ResidualMonitor, CusumFindsAStepAndItsTime) {
  imu::GaussianRng rng(8);
  imu::Cusum c;
  ASSERT_EQ(c.configure(0.5F, 5.0F), imu::MonitorStatus::kOk);
  std::uint64_t alarm_at = 0;
  for (int i = 1; i <= 3000; ++i) {
    const double step = i > 2000 ? -1.5 : 0.0;  // downward 1.5-sigma step after update 2000
    const bool alarm = c.push(static_cast<float>(rng.normal() + step));
    if (i <= 1990) {
      if (alarm) {
        c.reset();  // in-control false alarms (ARL ~470 with h = 5): re-arm
      }
      continue;
    }
    if (alarm && alarm_at == 0) {
      alarm_at = c.updates();
    }
  }
  ASSERT_TRUE(c.alarm());
  EXPECT_EQ(c.direction(), -1);
  // Detection delay for a 1.5-sigma shift with k = 0.5, h = 5: ~5 updates on average; 30 max.
  EXPECT_GT(alarm_at, 2000U);
  EXPECT_LT(alarm_at, 2030U);
  // Step time estimate (last zero of the alarming sum): before the step g- makes excursions
  // from zero lasting up to a few tens of updates (measured here: starts 11 early), so the
  // estimate is within 20 updates of 2000.
  EXPECT_NEAR(static_cast<double>(c.step_index()), 2000.0, 20.0);
}

TEST(ResidualMonitor, CusumReconfiguredCountsFromZero) {
  // A step right at the start of a reconfigured monitor: its time is update 0 of the new
  // configuration, not a count left over from before.
  imu::Cusum c;
  ASSERT_EQ(c.configure(), imu::MonitorStatus::kOk);
  for (int i = 0; i < 100; ++i) {
    c.push(0.0F);
  }
  ASSERT_EQ(c.configure(), imu::MonitorStatus::kOk);
  for (int i = 0; i < 20 && !c.alarm(); ++i) {
    c.push(3.0F);
  }
  ASSERT_TRUE(c.alarm());
  EXPECT_EQ(c.direction(), 1);
  EXPECT_EQ(c.step_index(), 0U);
  EXPECT_EQ(c.updates(), 5U);  // g+ grows by 3 - 0.5 per update and passes h = 10 at the 5th
}

TEST(ResidualMonitor, FilterOnSeedDataWithABiasStepRaisesTheCusum) {
  // The seed model simulated, a 0.02 m/s^2 step added at sample 300000 (static all along):
  // the monitors stay quiet before (mostly) and the CUSUM fires soon after.
  imu::FirstOrderGm m{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, m), imu::ModelStatus::kOk);
  imu::ContinuousModel<1> c;
  ASSERT_EQ(c.add_white(m.n), imu::ModelStatus::kOk);
  ASSERT_EQ(c.add_gauss_markov(m.sb, m.tb_s), imu::ModelStatus::kOk);
  imu::DiscreteModel<1> d;
  ASSERT_EQ(imu::discretize(c, m.ts_s, d), imu::ModelStatus::kOk);
  imu::ModelSimulator<1> sim;
  ASSERT_EQ(sim.configure(d, 5), imu::ModelStatus::kOk);
  imu::ScalarBiasKf<float> kf;
  ASSERT_EQ(kf.configure(m), imu::KfStatus::kOk);
  imu::ResidualMonitors<4> mon;
  ASSERT_EQ(mon.configure(1000), imu::MonitorStatus::kOk);
  std::uint32_t false_alarms = 0;
  int detected_at = -1;
  for (int i = 0; i < 400000; ++i) {
    const double z = sim.next() + (i >= 300000 ? 0.02 : 0.0);
    const imu::KfStep<float> s = kf.step(static_cast<float>(z), true);
    mon.push(s.innovation, s.innovation_var);
    if (mon.cusum.alarm()) {
      if (i < 300000) {
        ++false_alarms;
        mon.cusum.reset();
      } else if (detected_at < 0) {
        detected_at = i;
      }
    }
  }
  std::printf("bias step 0.02 m/s^2 (0.6 sigma of the innovation) at sample 300000: CUSUM alarm "
              "at %d, %u false alarms before\n", detected_at, false_alarms);
  ASSERT_GE(detected_at, 300000);
  // 0.6-sigma step, k = 0.5, h = 10: drift 0.1/update (the filter absorbs the step only over
  // ~1/K = 2500 updates), so the alarm comes after ~110 updates; 1000 is the stated limit.
  EXPECT_LT(detected_at, 301000);
  EXPECT_LT(false_alarms, 20U);  // default h = 10: ARL ~7e4, ~4 expected in 3e5 updates
}

}  // namespace

// The covariance check on recorded data (label golden: reads ../shared/data, skipped if absent):
// ADIS16405 acc_z, model fitted automatically to the data's online ADEV (white + GM over
// [Ts, 100 s], the example's "before" model), 1000 windows of T_avg = 10 s + T_int = 20 s, exact
// prediction from the fitted model. Reports the ratio of empirical (robust) to predicted
// standard deviation at the end of the window.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/covariance_check.hpp"
#include "imu/error_model.hpp"
#include "imu/mat/mat_reader.hpp"
#include "imu/model_fit.hpp"
#include "imu/online_adev.hpp"

namespace {

struct Recorded {
  std::vector<double> z;
  double lsb = 0.0;
};

bool load(const std::string& file, const char* var, Recorded& out) {
  const std::string path = std::string(IMU_SHARED_DIR) + "/data/" + file;
  auto col = imu::mat::read_column(path, var);
  auto lsb = imu::mat::read_scalar(path, "acc_lsb");
  if (!col.ok() || !lsb.ok()) {
    return false;
  }
  out.z = std::move(col).value();
  out.lsb = lsb.value();
  return true;
}

// Returns false (and skips) when the data are absent; ratio_end/mid: empirical / exact.
void check_channel(const char* file, const char* var, const imu::FitOptions& o, const char* label,
                   double tolerance) {
  Recorded rec;
  if (!load(file, var, rec)) {
    GTEST_SKIP() << "shared data not readable at " << IMU_SHARED_DIR;
  }
  ASSERT_EQ(rec.z.size(), 1000000U);
  constexpr double kTs = 0.01;
  imu::OnlineAdev<8, 22> adev(kTs, rec.lsb);
  for (const double v : rec.z) {
    const imu::QuantizeResult q = imu::quantize(v, rec.lsb);
    ASSERT_FALSE(q.saturated);
    adev.push(q.counts);
  }
  imu::AdevPoint pts[imu::OnlineAdev<8, 22>::kMaxPoints];
  const std::size_t n = adev.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  const imu::FitResult fr = imu::fit(pts, n, o);
  ASSERT_EQ(fr.status, imu::FitStatus::kOk);
  imu::ContinuousModel<6> c;
  ASSERT_EQ(imu::build_model(fr.params, c), imu::ModelStatus::kOk);
  imu::DiscreteModel<6> d;
  ASSERT_EQ(imu::discretize(c, kTs, d), imu::ModelStatus::kOk);

  constexpr std::size_t kNa = 1000;
  constexpr std::size_t kNi = 2000;
  constexpr std::size_t kWindows = 1000;
  std::vector<double> exact(kNi);
  std::vector<double> ignored(kNi);
  ASSERT_EQ(imu::predict_integral_std(d, kNa, kNi, exact.data()), imu::ModelStatus::kOk);
  ASSERT_EQ(imu::predict_integral_std(d, kNa, kNi, ignored.data(),
                                      imu::CovPrediction::kCorrelationIgnored),
            imu::ModelStatus::kOk);
  // 1000 windows of 3000 samples over 1e6 samples: overlapping starts 998 samples apart.
  const std::size_t span = kNa + kNi;
  const std::size_t stride = (rec.z.size() - span) / (kWindows - 1);
  std::vector<double> traj(kNi);
  std::vector<double> ends(kWindows);
  std::vector<double> mids(kWindows);
  for (std::size_t w = 0; w < kWindows; ++w) {
    imu::integrate_window(rec.z.data() + w * stride, kNa, kNi, kTs, traj.data());
    ends[w] = traj[kNi - 1];
    mids[w] = traj[kNi / 2 - 1];
  }
  const double emp_end = imu::robust_std(ends.data(), kWindows);
  const double emp_mid = imu::robust_std(mids.data(), kWindows);
  const double ratio_end = emp_end / exact[kNi - 1];
  const double ratio_mid = emp_mid / exact[kNi / 2 - 1];
  std::printf("%s %s [%s]: fit N = %.4e, GM1 Sb = %.4e Tb = %.2f s, GM2 Sb = %.4e Tb = %.2f s%s, RMS rel %.2f %%; predicted std at "
              "20 s %.4e (exact) %.4e (correlation ignored); robust empirical %.4e; ratio "
              "empirical/exact %.3f at 20 s, %.3f at 10 s; empirical/ignored %.3f\n",
              file, var, label, fr.params.n, fr.params.n_gm > 0 ? fr.params.gm[0].sb : 0.0,
              fr.params.n_gm > 0 ? fr.params.gm[0].tb_s : 0.0,
              fr.params.n_gm > 1 ? fr.params.gm[1].sb : 0.0,
              fr.params.n_gm > 1 ? fr.params.gm[1].tb_s : 0.0,
              fr.tb_at_bound ? " (at bound)" : "", 100.0 * fr.rms_rel, exact[kNi - 1],
              ignored[kNi - 1], emp_end, ratio_end, ratio_mid, emp_end / ignored[kNi - 1]);
  EXPECT_NEAR(ratio_end, 1.0, tolerance);
  EXPECT_NEAR(ratio_mid, 1.0, tolerance);
}

// The example's "before" model fitted with the pure 1/var weights: reported, loosely bounded. The
// ADIS16405 has a bump near 0.6 s (a ~0.6 Hz periodic component) and a flicker plateau from
// 10 s that white + one GM cannot both follow; the EDF ~1e6 points at tau < 0.1 s then decide
// the fit, the plateau is underestimated and the model underpredicts the 20 s integral by ~20 %.
// Measured: 1.21 (imu1), 1.18 (imu2). Bound 35 %: a regression bound on a reported figure.
imu::FitOptions first_order_before_model() { return imu::FitOptions{}; }

// White + two GMs with the EDF capped at 1000 in the weights: follows the plateau (RMS ~5 %).
// Measured: ratio 0.87 at 20 s on both IMUs (the model over-predicts by 13 %: a GM with
// Tb ~ 40-100 s stands in for a flicker plateau, which it is not). With 1000 overlapping
// windows the robust std itself has ~5 % sampling error (MAD of 1000 values, windows
// overlapping 3x). Bound 15 %: a regression bound on this figure, not a proof of the model.
imu::FitOptions two_gm_capped() {
  imu::FitOptions o;
  o.terms = imu::kFitWhite | imu::kFitGm1 | imu::kFitGm2;
  o.edf_cap = 1000.0;
  return o;
}

TEST(CovarianceCheckRecorded, Imu1AccZ) {
  check_channel("adis16405_imu1.mat", "acc_z", first_order_before_model(), "white+GM", 0.35);
  check_channel("adis16405_imu1.mat", "acc_z", two_gm_capped(), "white+2GM, edf cap", 0.15);
}
TEST(CovarianceCheckRecorded, Imu2AccZ) {
  check_channel("adis16405_imu2.mat", "acc_z", first_order_before_model(), "white+GM", 0.35);
  check_channel("adis16405_imu2.mat", "acc_z", two_gm_capped(), "white+2GM, edf cap", 0.15);
}

}  // namespace

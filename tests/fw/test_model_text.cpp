// Test of host_sim/model_text: the example's report, compared with the text typed from Farrell's
// "ASD to State-Space Example" (its printed output), not with this code's own output.
#include "imu/model_text.hpp"

#include <gtest/gtest.h>

#include <string>

#include "imu/error_model.hpp"

namespace {

TEST(ModelText, SeedModelInTheSeedLayout) {
  imu::FirstOrderGm m{};
  ASSERT_EQ(imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, m), imu::ModelStatus::kOk);
  const std::string want =
      "Continuous-time model is (units depend on context):\n"
      "    z(t) = b(t) + n(t),\n"
      "    db(t)/dt = -6.3000e-03 * b(t) + w(t),\n"
      "where n(t) is white noise with PSD S_n = 1.0890e-05 and w(t) is the bias process noise "
      "with PSD S_w = 2.6783e-08.\n"
      "The steady-state covariance of the bias process is P_b_ss_c = 2.1256e-06.\n"
      "\n"
      "Discrete-time model is (units depend on context):\n"
      "    z[k] = b[k] + n[k],\n"
      "    b[k+1] = 0.9999 * b[k] + w[k],\n"
      "where n[k] is white noise with covariance Q_n = 1.0890e-03 (std 3.3000e-02) and w[k] is "
      "the bias process with covariance Q_w = 2.6781e-10 (std 1.6365e-05).\n"
      "The steady-state covariance of the bias process is P_b_ss_d = 2.1256e-06.\n";
  EXPECT_EQ(imu::format_first_order_model(m), want);
}

TEST(ModelText, ParamsListOnlyThePresentTerms) {
  imu::ModelParams p;
  p.n = 3.3e-3;
  p.n_gm = 1;
  p.gm[0] = {2.6783e-8, 300.0 / 1.89};
  const std::string s = imu::format_model_params(p);
  EXPECT_NE(s.find("white noise N = 3.3000e-03 u/sqrt(Hz)\n"), std::string::npos) << s;
  // B = 0.4365 sqrt(2.6783e-8 * 158.73) = 9.0000e-04 and the peak at 1.89 Tb = 300 s (the
  // example's Tp).
  EXPECT_NE(s.find("(B = 9.0000e-04 u, peak at tau = 3.0000e+02 s)"), std::string::npos) << s;
  EXPECT_EQ(s.find("quantization"), std::string::npos);
  EXPECT_EQ(s.find("ramp"), std::string::npos);
}

}  // namespace

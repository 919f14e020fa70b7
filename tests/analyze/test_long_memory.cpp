// The block-mean likelihood of long_memory.hpp against an independent reference: the Gaussian
// density of the block means from their covariance matrix, built from the double integrals of
// each term's autocovariance (closed forms below, derived separately from the filter's), and
// the RRW likelihood-ratio test on simulated records with a known answer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "imu/analyze/long_memory.hpp"
#include "imu/analyze/synth.hpp"
#include "imu/error_model.hpp"

namespace {

namespace ia = imu::analyze;

// Covariance of block means (length h) of white + GMs + a walk with w(0) ~ N(0, w0_var).
std::vector<std::vector<double>> block_cov(const ia::BlockModel& m, double h, std::size_t n,
                                           double w0_var) {
  std::vector<std::vector<double>> c(n, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      double v = w0_var;
      const double lo = static_cast<double>(std::min(i, j));
      // (1/h^2) int int min(t, s): h (i + 1/3) on the diagonal, h (min + 1/2) off it.
      v += m.k * m.k * h * (lo + (i == j ? 1.0 / 3.0 : 0.5));
      for (std::size_t g = 0; g < m.n_gm; ++g) {
        const double tb = m.gm[g].tb_s;
        const double var = 0.5 * m.gm[g].sb * tb;
        const double x = h / tb;
        if (i == j) {
          v += 2.0 * var * tb * tb * (x - 1.0 + std::exp(-x)) / (h * h);
        } else {
          const double d = std::fabs(static_cast<double>(i) - static_cast<double>(j));
          const double om = 1.0 - std::exp(-x);
          v += var * tb * tb * om * om * std::exp(-x * (d - 1.0)) / (h * h);
        }
      }
      c[i][j] = v + (i == j ? m.white_var : 0.0);
    }
  }
  return c;
}

// -0.5 (ln det C + y' C^-1 y) by Cholesky.
double gaussian_loglik(std::vector<std::vector<double>> c, const std::vector<double>& y) {
  const std::size_t n = y.size();
  for (std::size_t j = 0; j < n; ++j) {
    for (std::size_t k = 0; k < j; ++k) {
      c[j][j] -= c[j][k] * c[j][k];
    }
    c[j][j] = std::sqrt(c[j][j]);
    for (std::size_t i = j + 1; i < n; ++i) {
      for (std::size_t k = 0; k < j; ++k) {
        c[i][j] -= c[i][k] * c[j][k];
      }
      c[i][j] /= c[j][j];
    }
  }
  std::vector<double> z(y);
  double logdet = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      z[i] -= c[i][k] * z[k];
    }
    z[i] /= c[i][i];
    logdet += 2.0 * std::log(c[i][i]);
  }
  double q = 0.0;
  for (double v : z) {
    q += v * v;
  }
  return -0.5 * (logdet + q);
}

// remove_polynomial against the least-squares conditions: a cubic in the index with an offset
// far above its curvature leaves rounding only, and of any sequence each degree (1 by the closed
// form of remove_mean_and_line, 2 and 3 by Gram-Schmidt) leaves a residual orthogonal to every
// power of the index up to it.
TEST(LongMemory, RemovePolynomialLeavesTheLeastSquaresResidual) {
  const std::size_t n = 2048;
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k);
    v[k] = 9.81 + 2e-3 * t - 4e-6 * t * t + 1.5e-9 * t * t * t;
  }
  ia::remove_polynomial(v, 3);
  for (const double x : v) {
    ASSERT_LT(std::abs(x), 1e-9);
  }
  std::vector<double> w0(n);
  for (std::size_t k = 0; k < n; ++k) {
    w0[k] = std::sin(0.37 * static_cast<double>(k)) + 1e-3 * static_cast<double>(k % 17) +
            1e-6 * static_cast<double>(k * k);
  }
  for (const std::size_t degree : {1U, 2U, 3U}) {
    std::vector<double> w = w0;
    ia::remove_polynomial(w, degree);
    for (std::size_t d = 0; d <= degree; ++d) {
      double dot = 0.0;
      double scale = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        const double t = (static_cast<double>(k) - 1023.5) / 1023.5;
        dot += w[k] * std::pow(t, static_cast<double>(d));
        scale += std::abs(std::pow(t, static_cast<double>(d)));
      }
      EXPECT_LT(std::abs(dot), 1e-10 * scale) << "degree " << degree << ", power " << d;
    }
  }
}

TEST(LongMemory, BlockLikelihoodEqualsGaussianDensity) {
  ia::BlockModel m;
  m.white_var = 0.7;
  m.n_gm = 2;
  m.gm[0] = imu::GmParam{0.4, 3.0};   // tb comparable to the block
  m.gm[1] = imu::GmParam{0.05, 40.0};  // tb of many blocks
  m.k = 0.3;
  const double h = 2.5;
  const std::vector<double> y = {0.3, -1.2, 0.8, 2.1, 1.7, -0.4, 0.9, 3.0, 2.2};
  for (const double w0 : {0.0, 1.5}) {
    const double ref = gaussian_loglik(block_cov(m, h, y.size(), w0), y);
    EXPECT_NEAR(ia::block_loglik(y, h, m, w0), ref, 1e-9 * std::fabs(ref) + 1e-12) << w0;
  }
  // Without a walk and with one GM only.
  m.k = 0.0;
  m.n_gm = 1;
  const double ref = gaussian_loglik(block_cov(m, h, y.size(), 0.0), y);
  EXPECT_NEAR(ia::block_loglik(y, h, m, 0.0), ref, 1e-9 * std::fabs(ref));
}

TEST(LongMemory, ResetForgetsTheLevel) {
  // After a reset the walk's level is unknown: a constant added from there on changes nothing
  // (up to the diffuse limit), while without the reset it is a large, improbable jump.
  ia::BlockModel m;
  m.white_var = 0.5;
  m.n_gm = 1;
  m.gm[0] = imu::GmParam{0.2, 4.0};
  const std::vector<double> y = {0.3, -0.2, 0.8, 0.1, 0.7, -0.4, 0.2, 0.5, 0.0, -0.3};
  std::vector<double> jumped(y);
  for (std::size_t i = 5; i < jumped.size(); ++i) {
    jumped[i] += 40.0;
  }
  const std::vector<std::size_t> resets = {5, 6};
  const double with_reset = ia::block_loglik(jumped, 1.0, m, -1.0, resets);
  EXPECT_NEAR(with_reset, ia::block_loglik(y, 1.0, m, -1.0, resets), 1e-5);
  EXPECT_LT(ia::block_loglik(jumped, 1.0, m), with_reset - 100.0);
}

TEST(LongMemory, InvalidModelIsMinusInfinity) {
  ia::BlockModel m;
  m.white_var = 0.0;
  EXPECT_TRUE(std::isinf(ia::block_loglik({1.0, 2.0}, 1.0, m)));
  m.white_var = 1.0;
  m.n_gm = 1;
  m.gm[0] = imu::GmParam{1.0, 0.0};
  EXPECT_TRUE(std::isinf(ia::block_loglik({1.0, 2.0}, 1.0, m)));
}

}  // namespace

namespace {

// The test on simulated records with a known answer: another first-order model (gyro-like,
// N = 5e-4, B = 2e-4, Tp = 60 s, 3000 s at 100 Hz), with and without a rate random walk.
// tb_max as analyze() sets it: GM peak and one octave of its falling side inside [Ts, T/10].
ia::RrwLikelihoodTest run_lrt(double k, std::uint64_t seed) {
  ia::SynthSpec s;
  s.n = 5e-4;
  s.b = 2e-4;
  s.tp_s = 60.0;
  s.samples = 300000;
  s.k = k;
  s.offset = 0.2;
  s.seed = seed;
  const std::vector<double> y = ia::synthesize(s);
  imu::FirstOrderGm gm{};
  EXPECT_EQ(imu::first_order_gm_from_asd(s.n, s.b, s.tp_s, s.fs_hz, gm), imu::ModelStatus::kOk);
  imu::ModelParams start;  // what an ADEV fit would give: the first-order model's terms
  start.n = s.n;
  start.n_gm = 1;
  start.gm[0] = imu::GmParam{gm.sb, gm.tb_s};
  const double tb_max = 0.1 * 3000.0 / (2.0 * imu::kGmPeakTauFactor);
  return ia::test_rrw(y, 0.01, start, tb_max, false);
}

const double kLrThreshold = 6.635;  // chi2(1) at 0.99

TEST(LongMemory, NoWalkNoEvidence) {
  int false_alarms = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const ia::RrwLikelihoodTest c = run_lrt(0.0, seed);
    ASSERT_TRUE(c.ok);
    false_alarms += c.lr > kLrThreshold ? 1 : 0;
    EXPECT_GE(c.h1.loglik, c.h0.loglik - 1e-9);  // H1 contains H0
    // The white part of a block mean: N^2 / h.
    const double wv = 5e-4 * 5e-4 / c.block_s;
    EXPECT_NEAR(c.h0.model.white_var, wv, 0.1 * wv) << "seed " << seed;
  }
  EXPECT_LE(false_alarms, 1);  // 1 % level: 0.1 expected in 10
}

TEST(LongMemory, WalkFoundAndSized) {
  // K = 4e-5: its ADEV at T/10 (K sqrt(300 s / 3) = 4e-4) is twice the GM's ADEV peak (B).
  const double k_true = 4e-5;
  int found = 0;
  std::vector<double> k;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const ia::RrwLikelihoodTest c = run_lrt(k_true, seed);
    ASSERT_TRUE(c.ok);
    found += c.lr > kLrThreshold ? 1 : 0;
    k.push_back(c.h1.model.k);
  }
  EXPECT_GE(found, 9);
  std::sort(k.begin(), k.end());
  const double median = 0.5 * (k[4] + k[5]);
  EXPECT_NEAR(median, k_true, 0.25 * k_true);
}

}  // namespace

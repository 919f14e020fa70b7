// The analysis's FFTs against the DFT's definition summed directly (O(n^2), small n), and the
// real-input power spectrum against the complex FFT of the same zero-padded record (large n).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <random>
#include <vector>

#include "imu/analyze/fft.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<double> gaussian(std::size_t size, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.3, 1.0);
  std::vector<double> v(size);
  for (double& x : v) {
    x = n(rng);
  }
  return v;
}

// |X[k]|^2 of x zero-padded to n, from the definition X[k] = sum x[j] e^{-2 pi i j k / n}.
double direct_power(const std::vector<double>& x, std::size_t n, std::size_t k) {
  double re = 0.0;
  double im = 0.0;
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double ang = -2.0 * kPi * static_cast<double>((j * k) % n) / static_cast<double>(n);
    re += x[j] * std::cos(ang);
    im += x[j] * std::sin(ang);
  }
  return re * re + im * im;
}

TEST(Fft, RealPowerIsTheDftsDefinitionOnSmallRecords) {
  for (const std::size_t size : {1U, 2U, 3U, 7U, 8U, 33U, 100U, 256U}) {
    const std::vector<double> x = gaussian(size, 7301U + static_cast<unsigned>(size));
    std::size_t n = 2;
    while (n < size) {
      n <<= 1;
    }
    for (const std::size_t pad : {n, 2 * n}) {
      const std::vector<double> p = imu::analyze::real_fft_power(x, pad);
      ASSERT_EQ(p.size(), pad / 2 + 1);
      for (std::size_t k = 0; k <= pad / 2; ++k) {
        const double ref = direct_power(x, pad, k);
        EXPECT_NEAR(p[k], ref, 1e-9 * (1.0 + ref)) << "size " << size << " n " << pad << " k " << k;
      }
    }
  }
}

TEST(Fft, ComplexFftIsTheDftsDefinition) {
  const std::vector<double> x = gaussian(64, 7311U);
  std::vector<std::complex<double>> a(x.begin(), x.end());
  imu::analyze::fft(a);
  for (std::size_t k = 0; k < a.size(); ++k) {
    const double ref = direct_power(x, a.size(), k);
    EXPECT_NEAR(std::norm(a[k]), ref, 1e-9 * (1.0 + ref)) << "k " << k;
  }
}

TEST(Fft, RealPowerMatchesTheComplexFftOnALongZeroPaddedRecord) {
  const std::vector<double> x = gaussian(1000003, 7321U);
  const std::size_t n = std::size_t{1} << 21;
  std::vector<std::complex<double>> a(n, std::complex<double>(0.0, 0.0));
  for (std::size_t j = 0; j < x.size(); ++j) {
    a[j] = x[j];
  }
  imu::analyze::fft(a);
  const std::vector<double> p = imu::analyze::real_fft_power(x, n);
  ASSERT_EQ(p.size(), n / 2 + 1);
  double worst = 0.0;
  for (std::size_t k = 0; k <= n / 2; ++k) {
    const double ref = std::norm(a[k]);
    worst = std::max(worst, std::abs(p[k] - ref) / (ref + 1.0));
  }
  EXPECT_LT(worst, 1e-9);
}

}  // namespace

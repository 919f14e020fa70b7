// In-place radix-2 FFT for the analysis and the synthetic generator (host only).
#ifndef IMU_ANALYZE_FFT_HPP
#define IMU_ANALYZE_FFT_HPP

#include <cmath>
#include <complex>
#include <cstddef>
#include <utility>
#include <vector>

namespace imu::analyze {

/// Forward DFT (e^{-2 pi i k n / N}) of a, in place; a.size() must be a power of two. O(N log N).
inline void fft(std::vector<std::complex<double>>& a) {
  const std::size_t n = a.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {
    std::size_t bit = n >> 1;
    for (; (j & bit) != 0; bit >>= 1) {
      j ^= bit;
    }
    j ^= bit;
    if (i < j) {
      std::swap(a[i], a[j]);
    }
  }
  // Twiddles e^{-2 pi i k / n}, k < n/2, once (stage len reads every (n/len)-th); the products
  // are written out in real arithmetic: std::complex's operator* goes through the C99 Annex G
  // NaN/Inf recovery (__muldc3), several times slower.
  std::vector<double> wr(n / 2);
  std::vector<double> wi(n / 2);
  for (std::size_t k = 0; k < n / 2; ++k) {
    const double ang = -2.0 * 3.14159265358979323846 * static_cast<double>(k) /
                       static_cast<double>(n);
    wr[k] = std::cos(ang);
    wi[k] = std::sin(ang);
  }
  auto* d = reinterpret_cast<double*>(a.data());  // std::complex<T> is array-of-2 compatible
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const std::size_t half = len / 2;
    const std::size_t stride = n / len;
    for (std::size_t i = 0; i < n; i += len) {
      for (std::size_t j = 0; j < half; ++j) {
        const double c = wr[j * stride];
        const double s = wi[j * stride];
        double* u = d + 2 * (i + j);
        double* v = d + 2 * (i + j + half);
        const double vr = v[0] * c - v[1] * s;
        const double vi = v[0] * s + v[1] * c;
        v[0] = u[0] - vr;
        v[1] = u[1] - vi;
        u[0] += vr;
        u[1] += vi;
      }
    }
  }
}

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_FFT_HPP

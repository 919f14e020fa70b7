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
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const double ang = -2.0 * 3.14159265358979323846 / static_cast<double>(len);
    const std::complex<double> wl(std::cos(ang), std::sin(ang));
    for (std::size_t i = 0; i < n; i += len) {
      std::complex<double> w(1.0, 0.0);
      for (std::size_t j = 0; j < len / 2; ++j) {
        const std::complex<double> u = a[i + j];
        const std::complex<double> v = a[i + j + len / 2] * w;
        a[i + j] = u + v;
        a[i + j + len / 2] = u - v;
        w *= wl;
      }
    }
  }
}

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_FFT_HPP

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

/// |X[k]|^2 for k = 0 .. n/2 of the DFT of the real sequence x zero-padded to n (a power of two,
/// at least 2 and x.size()): one complex FFT of n/2 points over the even and odd samples, then
/// X[k] = E[k] + e^{-2 pi i k / n} O[k]. Half the memory of the complex FFT of n points (the
/// sinusoid search's full-rate spectrum is the analysis's largest buffer), the same values to
/// rounding.
inline std::vector<double> real_fft_power(const std::vector<double>& x, std::size_t n) {
  const std::size_t m = n / 2;
  std::vector<std::complex<double>> z(m, std::complex<double>(0.0, 0.0));
  for (std::size_t j = 0; j < m; ++j) {
    const double re = 2 * j < x.size() ? x[2 * j] : 0.0;
    const double im = 2 * j + 1 < x.size() ? x[2 * j + 1] : 0.0;
    z[j] = std::complex<double>(re, im);
  }
  fft(z);
  std::vector<double> p(m + 1);
  for (std::size_t k = 0; k <= m; ++k) {
    const std::complex<double> zk = z[k % m];
    const std::complex<double> zc = std::conj(z[(m - k) % m]);
    const double er = 0.5 * (zk.real() + zc.real());  // E[k] = (Z[k] + conj Z[m-k]) / 2
    const double ei = 0.5 * (zk.imag() + zc.imag());
    const double dr = 0.5 * (zk.imag() - zc.imag());  // O[k] = (Z[k] - conj Z[m-k]) / 2i
    const double di = -0.5 * (zk.real() - zc.real());
    const double ang = -2.0 * 3.14159265358979323846 * static_cast<double>(k) /
                       static_cast<double>(n);
    const double c = std::cos(ang);
    const double s = std::sin(ang);
    const double xr = er + (dr * c - di * s);
    const double xi = ei + (dr * s + di * c);
    p[k] = xr * xr + xi * xi;
  }
  return p;
}

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_FFT_HPP

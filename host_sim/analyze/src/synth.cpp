// Synthetic channel generator (see synth.hpp).
#include "imu/analyze/synth.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "imu/error_model.hpp"
#include "imu/noise_sim.hpp"
#include "imu/analyze/fft.hpp"

namespace imu::analyze {
namespace {
constexpr double kPi = 3.14159265358979323846;

// Kasdin's 1/f (alpha = 1) sequence of m values, white variance b^2 (see SynthSpec::flicker_b):
// the causal convolution of the white sequence with h by FFT (zero-padded to 2m: no wrap).
std::vector<double> flicker_sequence(std::size_t m, double b, GaussianRng& rng) {
  std::size_t n = 1;
  while (n < 2 * m) {
    n <<= 1;
  }
  std::vector<std::complex<double>> hf(n);
  std::vector<std::complex<double>> wf(n);
  double h = 1.0;
  for (std::size_t k = 0; k < m; ++k) {
    hf[k] = h;
    h *= (static_cast<double>(k) + 0.5) / static_cast<double>(k + 1);
    wf[k] = b * rng.normal();
  }
  fft(hf);
  fft(wf);
  for (std::size_t k = 0; k < n; ++k) {
    wf[k] = std::conj(wf[k] * hf[k]);  // inverse by the conjugate trick
  }
  fft(wf);
  std::vector<double> x(m);
  for (std::size_t k = 0; k < m; ++k) {
    x[k] = wf[k].real() / static_cast<double>(n);
  }
  return x;
}
}  // namespace

std::vector<double> synthesize(const SynthSpec& s) {
  FirstOrderGm gm{};
  if (first_order_gm_from_asd(s.n, s.b, s.tp_s, s.fs_hz, gm) != ModelStatus::kOk ||
      s.samples == 0) {
    return {};
  }
  ModelParams p{};
  p.n = s.n;
  p.q = s.q;
  p.n_gm = 1;
  p.gm[0] = GmParam{gm.sb, gm.tb_s};
  p.k = s.k;
  ContinuousModel<6> c;
  DiscreteModel<6> d;
  const double ts = 1.0 / s.fs_hz;
  if (build_model(p, c) != ModelStatus::kOk || discretize(c, ts, d) != ModelStatus::kOk) {
    return {};
  }
  ModelSimulator<6> sim;
  if (sim.configure(d, s.seed) != ModelStatus::kOk) {
    return {};
  }
  std::vector<double> y(s.samples);
  const double t_mid = 0.5 * static_cast<double>(s.samples) * ts;
  Xoshiro256ss u(s.seed ^ 0x9E3779B97F4A7C15ULL);
  const double phase = 2.0 * kPi * u.uniform_open();
  for (std::size_t i = 0; i < s.samples; ++i) {
    const double t = static_cast<double>(i) * ts;
    double v = sim.next() + s.offset + s.ramp_r * (t - t_mid);
    if (s.sin_a > 0.0) {
      v += s.sin_a * std::sin(2.0 * kPi * s.sin_f_hz * t + phase);
    }
    if (std::fabs(s.step_size) > 0.0 && t >= s.step_time_s) {
      v += s.step_size;
    }
    y[i] = v;
  }
  if (s.flicker_b > 0.0) {
    const auto hold = static_cast<std::size_t>(std::max(1L, std::lround(s.flicker_dt_s / ts)));
    GaussianRng rf(s.seed ^ 0xF11C4E5ULL);
    const std::vector<double> f = flicker_sequence(s.samples / hold + 1, s.flicker_b, rf);
    for (std::size_t i = 0; i < s.samples; ++i) {
      y[i] += f[i / hold];
    }
  }
  if (s.osc_sigma > 0.0 && s.osc_beta_per_s > 0.0) {
    GaussianRng ro(s.seed ^ 0x05C111ULL);
    const double rho = std::exp(-s.osc_beta_per_s * ts);
    const double th = 2.0 * kPi * s.osc_f0_hz * ts;
    const double rc = rho * std::cos(th);
    const double sn = rho * std::sin(th);
    const double sd = s.osc_sigma * std::sqrt(1.0 - rho * rho);
    double a = s.osc_sigma * ro.normal();  // stationary start
    double b = s.osc_sigma * ro.normal();
    for (std::size_t i = 0; i < s.samples; ++i) {
      y[i] += a;
      const double a1 = rc * a - sn * b + sd * ro.normal();
      const double b1 = sn * a + rc * b + sd * ro.normal();
      a = a1;
      b = b1;
    }
  }
  if (s.drift_walk > 0.0) {
    GaussianRng rd(s.seed ^ 0xD21F7ULL);
    double rate = 0.0;
    double bias = 0.0;
    const double sd = s.drift_walk * std::sqrt(ts);
    for (std::size_t i = 0; i < s.samples; ++i) {
      rate += sd * rd.normal();
      bias += rate * ts;
      y[i] += bias;
    }
  }
  // Outliers: positions on a jittered grid, so they are isolated (>= 100 samples apart).
  if (s.n_outliers > 0 && s.samples >= 200 * s.n_outliers) {
    const std::size_t cell = s.samples / s.n_outliers;
    for (std::size_t j = 0; j < s.n_outliers; ++j) {
      const auto off = static_cast<std::size_t>(u.uniform_open() * static_cast<double>(cell - 100));
      const double sign = u.uniform_open() < 0.5 ? -1.0 : 1.0;
      y[j * cell + 50 + off] += sign * s.outlier_size;
    }
  }
  if (s.nan_gaps > 0 && s.nan_gap_len > 0 && s.samples > 2 * s.nan_gaps * s.nan_gap_len) {
    Xoshiro256ss rg(s.seed ^ 0x6A95ULL);
    const std::size_t cell = s.samples / s.nan_gaps;
    for (std::size_t j = 0; j < s.nan_gaps; ++j) {
      const auto off = static_cast<std::size_t>(rg.uniform_open() *
                                                static_cast<double>(cell - s.nan_gap_len));
      for (std::size_t i = 0; i < s.nan_gap_len; ++i) {
        y[j * cell + off + i] = std::numeric_limits<double>::quiet_NaN();
      }
    }
  }
  return y;
}

}  // namespace imu::analyze

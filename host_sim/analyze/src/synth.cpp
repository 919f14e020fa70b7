// Synthetic channel generator (see synth.hpp).
#include "imu/analyze/synth.hpp"

#include <cmath>

#include "imu/error_model.hpp"
#include "imu/noise_sim.hpp"

namespace imu::analyze {
namespace {
constexpr double kPi = 3.14159265358979323846;
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
  // Outliers: positions on a jittered grid, so they are isolated (>= 100 samples apart).
  if (s.n_outliers > 0 && s.samples >= 200 * s.n_outliers) {
    const std::size_t cell = s.samples / s.n_outliers;
    for (std::size_t j = 0; j < s.n_outliers; ++j) {
      const auto off = static_cast<std::size_t>(u.uniform_open() * static_cast<double>(cell - 100));
      const double sign = u.uniform_open() < 0.5 ? -1.0 : 1.0;
      y[j * cell + 50 + off] += sign * s.outlier_size;
    }
  }
  return y;
}

}  // namespace imu::analyze

// Benchmark (not a test): host cost per sample of the bias filters and the residual monitors,
// and the state size in bytes. Run: build-<dir>/tests/fw/bench_bias_kf [samples]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "imu/averaged_kf.hpp"
#include "imu/bias_kf.hpp"
#include "imu/error_model.hpp"
#include "imu/model_fit.hpp"
#include "imu/online_adev.hpp"
#include "imu/noise_sim.hpp"
#include "imu/residual_monitor.hpp"

namespace {

template <typename Fn>
double ns_per_sample(std::size_t n, Fn fn) {
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < n; ++i) {
    fn(i);
  }
  const auto t1 = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::nano>(t1 - t0).count() / static_cast<double>(n);
}

// The fit's host cost (it runs rarely, e.g. after a calibration run): the ADEV of 1e6 samples
// of the first-order model m, fitted white + GM and white + 2 GM + RRW.
void print_fit_cost(const imu::FirstOrderGm& m) {
  imu::ContinuousModel<1> c1;
  (void)c1.add_white(m.n);
  (void)c1.add_gauss_markov(m.sb, m.tb_s);
  imu::DiscreteModel<1> d1;
  (void)imu::discretize(c1, m.ts_s, d1);
  imu::ModelSimulator<1> sim1;
  (void)sim1.configure(d1, 20251121);
  imu::OnlineAdev<8, 22> adev(m.ts_s, 1e-5);
  for (int i = 0; i < 1000000; ++i) {
    adev.push(imu::quantize(sim1.next(), 1e-5).counts);
  }
  imu::AdevPoint pts[imu::OnlineAdev<8, 22>::kMaxPoints];
  const std::size_t np = adev.snapshot(pts, imu::OnlineAdev<8, 22>::kMaxPoints);
  constexpr int kFits = 20;
  imu::FitResult fr{};
  const auto f0 = std::chrono::steady_clock::now();
  for (int i = 0; i < kFits; ++i) {
    fr = imu::fit(pts, np, imu::FitOptions{});
  }
  const double fit_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - f0).count() /
      kFits;
  imu::FitOptions o2;
  o2.terms = imu::kFitWhite | imu::kFitGm1 | imu::kFitGm2 | imu::kFitRrw;
  const auto f1 = std::chrono::steady_clock::now();
  const imu::FitResult fr2 = imu::fit(pts, np, o2);
  const double fit2_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - f1).count();
  std::printf("fit (host): white+GM %.2f ms (%u NNLS solves, %zu points); white+2GM+RRW %.2f ms "
              "(%u solves)\n", fit_ms, fr.evaluations, fr.n_points, fit2_ms, fr2.evaluations);
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 10000000U;
  imu::FirstOrderGm m{};
  if (imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, 100.0, m) != imu::ModelStatus::kOk) {
    return 1;
  }
  imu::ContinuousModel<6> c;
  (void)c.add_white(3.3e-3);
  (void)c.add_gauss_markov(m.sb, m.tb_s);
  (void)c.add_gauss_markov(1e-6, 2.0);
  (void)c.add_rrw(1.3e-4, 1e-6);
  imu::DiscreteModel<6> d6;
  if (imu::discretize(c, 0.01, d6) != imu::ModelStatus::kOk) {
    return 1;
  }
  // Pre-generated input so the generator is not timed (a 4096-sample ring).
  imu::ModelSimulator<6> sim;
  if (sim.configure(d6, 1) != imu::ModelStatus::kOk) {
    return 1;
  }
  std::vector<float> zf(4096);
  std::vector<double> zd(4096);
  for (std::size_t i = 0; i < zf.size(); ++i) {
    zd[i] = sim.next();
    zf[i] = static_cast<float>(zd[i]);
  }
  volatile float sink_f = 0.0F;
  volatile double sink_d = 0.0;

  imu::ScalarBiasKf<float> kf;
  (void)kf.configure(m);
  const double t_scalar_f = ns_per_sample(n, [&](std::size_t i) {
    sink_f = kf.step(zf[i & 4095U], (i & 1023U) < 900U).innovation;
  });
  imu::ScalarBiasKf<double> kd;
  (void)kd.configure(m);
  const double t_scalar_d = ns_per_sample(n, [&](std::size_t i) {
    sink_d = kd.step(zd[i & 4095U], (i & 1023U) < 900U).innovation;
  });
  imu::KalmanFilter<float, 3> k3;
  (void)k3.configure(d6);
  const double t_3f = ns_per_sample(n / 10, [&](std::size_t i) {
    sink_f = k3.step(zf[i & 4095U], (i & 1023U) < 900U).innovation;
  });
  // The node's largest pushed model: 2 GM + RRW + a flicker bank, 8 states.
  imu::ContinuousModel<9> c8;
  (void)c8.add_white(3.3e-3);
  (void)c8.add_gauss_markov(m.sb, m.tb_s);
  (void)c8.add_gauss_markov(1e-6, 0.2);
  (void)c8.add_rrw(1.3e-4, 1e-6);
  (void)c8.add_flicker(1e-4, 1.0, 1e3);
  imu::DiscreteModel<9> d8;  // the node's: 8 model states and the averaging sampler's
  imu::KalmanFilter<float, 9> k8;
  double t_8f = -1.0;
  if (imu::discretize_averaged(c8, 0.01, d8) == imu::ModelStatus::kOk && d8.n_states == 9 &&
      k8.configure(d8) == imu::KfStatus::kOk) {
    t_8f = ns_per_sample(n / 10, [&](std::size_t i) {
      sink_f = k8.step(zf[i & 4095U], (i & 1023U) < 900U).innovation;
    });
  }
  // The same model in the structured filter the node runs (time-varying, then frozen).
  imu::AveragedKf<float, 8> a8;
  double t_a8 = -1.0;
  double t_a8_steady = -1.0;
  if (d8.n_states == 9 && a8.configure(d8) == imu::KfStatus::kOk) {
    t_a8 = ns_per_sample(n / 10, [&](std::size_t i) {
      sink_f = a8.step(zf[i & 4095U], (i & 1023U) < 900U).innovation;
    });
    a8.set_steady_state(true);
    for (std::size_t i = 0; i < 2000000 && !a8.steady(); ++i) {
      (void)a8.step(zf[i & 4095U], true);
    }
    if (a8.steady()) {
      t_a8_steady = ns_per_sample(n / 10, [&](std::size_t i) {
        sink_f = a8.step(zf[i & 4095U], true).innovation;
      });
    }
  }
  imu::ResidualMonitors<4> mon;
  (void)mon.configure(1000);
  imu::ScalarBiasKf<float> kf2;
  (void)kf2.configure(m);
  const double t_scalar_mon = ns_per_sample(n, [&](std::size_t i) {
    const imu::KfStep<float> s = kf2.step(zf[i & 4095U], true);
    mon.push(s.innovation, s.innovation_var);
    sink_f = mon.any_alarm() ? 1.0F : 0.0F;
  });
  (void)sink_f;
  (void)sink_d;
  std::printf("bias filter cost per sample (host, %zu samples, static 88 %% of the time):\n", n);
  std::printf("  ScalarBiasKf<float>            %6.2f ns  state %3zu bytes\n", t_scalar_f,
              sizeof(imu::ScalarBiasKf<float>));
  std::printf("  ScalarBiasKf<double>           %6.2f ns  state %3zu bytes\n", t_scalar_d,
              sizeof(imu::ScalarBiasKf<double>));
  std::printf("  KalmanFilter<float, 3>         %6.2f ns  state %3zu bytes\n", t_3f,
              sizeof(imu::KalmanFilter<float, 3>));
  std::printf("  KalmanFilter<float, 9>         %6.2f ns  state %3zu bytes (the node's pushed "
              "model; %zu states built, -1: not 9)\n",
              t_8f, sizeof(imu::KalmanFilter<float, 9>), d8.n_states);
  std::printf("  AveragedKf<float, 8>           %6.2f ns  state %3zu bytes (the same model, "
              "structured); frozen gain %.2f ns (-1: did not freeze)\n",
              t_a8, sizeof(imu::AveragedKf<float, 8>), t_a8_steady);
  std::printf("  ScalarBiasKf<float> + monitors %6.2f ns  state %3zu + %zu bytes "
              "(NIS + whiteness lags 1..4 + CUSUM)\n",
              t_scalar_mon, sizeof(imu::ScalarBiasKf<float>), sizeof(imu::ResidualMonitors<4>));

  print_fit_cost(m);
  return 0;
}

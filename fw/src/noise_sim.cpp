// PRNG, Gaussian draws and the model simulator (instantiated for kMaxStates = 1, 2, 4, 6).
#include "imu/noise_sim.hpp"

#include <cmath>

namespace imu {
namespace {

constexpr std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

std::uint64_t splitmix64(std::uint64_t& state) {
  state += 0x9E3779B97F4A7C15ULL;
  std::uint64_t z = state;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

constexpr double kTwoPi = 6.28318530717958647692;

}  // namespace

void Xoshiro256ss::seed_with(std::uint64_t seed) {
  std::uint64_t st = seed;
  for (auto& s : s_) {
    s = splitmix64(st);
  }
}

std::uint64_t Xoshiro256ss::next() {
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

double Xoshiro256ss::uniform_open() {
  // (k + 0.5) / 2^53 with k uniform in [0, 2^53): never 0, never 1.
  const std::uint64_t k = next() >> 11;
  return (static_cast<double>(k) + 0.5) * 0x1.0p-53;
}

double GaussianRng::normal() {
  if (have_spare_) {
    have_spare_ = false;
    return spare_;
  }
  const double u1 = u_.uniform_open();
  const double u2 = u_.uniform_open();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = kTwoPi * u2;
  spare_ = r * std::sin(a);
  have_spare_ = true;
  return r * std::cos(a);
}

template <std::size_t kMaxStates>
ModelStatus ModelSimulator<kMaxStates>::configure(const DiscreteModel<kMaxStates>& model,
                                                  std::uint64_t seed) {
  configured_ = false;
  if (!(model.ts_s > 0.0) || model.n_states > kMaxStates || !(model.r_white >= 0.0) ||
      !(model.q >= 0.0)) {
    return ModelStatus::kBadParameter;
  }
  Mat<double, kMaxStates, kMaxStates> lq{};
  Mat<double, kMaxStates, kMaxStates> lp{};
  if (model.n_states > 0) {
    if (!cholesky_psd(model.qd, lq, model.n_states) ||
        !cholesky_psd(model.p0, lp, model.n_states)) {
      return ModelStatus::kNumerical;
    }
  }
  model_ = model;
  lq_ = lq;
  lp_ = lp;
  white_sd_ = std::sqrt(model.r_white);
  rng_.seed_with(seed);
  configured_ = true;
  restart();
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
void ModelSimulator<kMaxStates>::restart() {
  const std::size_t n = model_.n_states;
  double e[kMaxStates] = {};
  for (std::size_t i = 0; i < n; ++i) {
    e[i] = rng_.normal();
  }
  for (std::size_t i = 0; i < n; ++i) {
    double s = 0.0;
    for (std::size_t j = 0; j <= i; ++j) {
      s += lp_(i, j) * e[j];
    }
    x_[i] = s;
  }
  u_prev_ = model_.q > 0.0 ? rng_.normal() : 0.0;
}

template <std::size_t kMaxStates>
double ModelSimulator<kMaxStates>::next() {
  if (!configured_) {
    return 0.0;
  }
  const std::size_t n = model_.n_states;
  double z = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    z += model_.h(0, i) * x_[i];
  }
  z += white_sd_ * rng_.normal();
  if (model_.q > 0.0) {
    const double u = rng_.normal();
    z += model_.q * (u - u_prev_) / model_.ts_s;
    u_prev_ = u;
  }
  double e[kMaxStates] = {};
  for (std::size_t i = 0; i < n; ++i) {
    e[i] = rng_.normal();
  }
  double xn[kMaxStates] = {};
  for (std::size_t i = 0; i < n; ++i) {
    double s = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      s += model_.phi(i, j) * x_[j];
    }
    for (std::size_t j = 0; j <= i; ++j) {
      s += lq_(i, j) * e[j];
    }
    xn[i] = s;
  }
  for (std::size_t i = 0; i < n; ++i) {
    x_[i] = xn[i];
  }
  return z;
}

template class ModelSimulator<1>;
template class ModelSimulator<2>;
template class ModelSimulator<4>;
template class ModelSimulator<6>;
template class ModelSimulator<8>;  // synth --model: the node's largest filter
template class ModelSimulator<16>;  // the largest model the host tools build (kModelMaxStates)
template SimAdevResult simulate_adev<1, 8, 22>(const DiscreteModel<1>&, std::uint64_t,
                                              std::uint64_t, double, OnlineAdev<8, 22>&);
template SimAdevResult simulate_adev<6, 8, 22>(const DiscreteModel<6>&, std::uint64_t,
                                              std::uint64_t, double, OnlineAdev<8, 22>&);

}  // namespace imu

// Deterministic noise generation and fixed-memory simulation of a DiscreteModel.
//
// Xoshiro256ss: xoshiro256** 1.0 (Blackman & Vigna), seeded through splitmix64; the integer
// stream is identical on every compiler and target. GaussianRng: Box-Muller on 53-bit uniforms
// in (0, 1); the normal values depend only on the libm's log/sqrt/cos/sin (the same libm gives
// bit-identical streams; different libms may differ in the last ulp). std::normal_distribution
// is not used because its algorithm is implementation-defined.
//
// ModelSimulator<kMaxStates>: z_k = H x_k + sqrt(r_white) v_k + Q (u_k - u_{k-1}) / Ts,
// x_{k+1} = Phi x_k + L_Q e_k (L_Q L_Q^T = Qd), x_0 ~ N(0, P0). Quantization is simulated
// exactly as the first difference of white phase noise. Cost per sample: O(n^2) multiply-adds
// and n + 2 normal draws. No heap; not re-entrant on one instance.
//
// simulate_adev(): the model's ADEV by simulation, through the online estimator.
#ifndef IMU_NOISE_SIM_HPP
#define IMU_NOISE_SIM_HPP

#include <cstddef>
#include <cstdint>

#include "imu/error_model.hpp"
#include "imu/linalg.hpp"
#include "imu/online_adev.hpp"

namespace imu {

class Xoshiro256ss {
 public:
  explicit Xoshiro256ss(std::uint64_t seed = 1) { seed_with(seed); }
  void seed_with(std::uint64_t seed);
  /// Next 64-bit output. Constant time.
  std::uint64_t next();
  /// Uniform in the open interval (0, 1), 53-bit resolution.
  double uniform_open();

 private:
  std::uint64_t s_[4] = {};
};

class GaussianRng {
 public:
  explicit GaussianRng(std::uint64_t seed = 1) : u_(seed) {}
  void seed_with(std::uint64_t seed) {
    u_.seed_with(seed);
    have_spare_ = false;
  }
  /// Standard normal draw (Box-Muller, pairs cached).
  double normal();

 private:
  Xoshiro256ss u_;
  double spare_ = 0.0;
  bool have_spare_ = false;
};

template <std::size_t kMaxStates = 6>
class ModelSimulator {
 public:
  /// Factorises Qd and P0 (PSD Cholesky) and draws x_0. kNumerical if either is not PSD,
  /// kBadParameter for an invalid model (ts_s <= 0). The simulator is unusable until kOk.
  [[nodiscard]] ModelStatus configure(const DiscreteModel<kMaxStates>& model, std::uint64_t seed);
  /// Draw a new x_0 ~ N(0, P0) and restart the quantization phase noise (a new realisation).
  void restart();
  /// Set the current state x_k (n_states entries), e.g. a sinusoid of a chosen amplitude and
  /// phase or a ramp of a chosen slope instead of a draw from P0. Ignored if not configured.
  void set_state(const double* x, std::size_t n) {
    for (std::size_t i = 0; configured_ && i < n && i < model_.n_states; ++i) {
      x_[i] = x[i];
    }
  }
  /// Next output sample z_k (then advances the state). Returns 0 if not configured.
  double next();
  /// Current state x_k (the one the next call of next() observes), n_states entries.
  [[nodiscard]] const double* state() const { return x_; }

 private:
  DiscreteModel<kMaxStates> model_{};
  Mat<double, kMaxStates, kMaxStates> lq_{};
  Mat<double, kMaxStates, kMaxStates> lp_{};
  GaussianRng rng_{};
  double x_[kMaxStates] = {};
  double u_prev_ = 0.0;
  double white_sd_ = 0.0;
  bool configured_ = false;
};

/// Result of simulate_adev().
struct SimAdevResult {
  ModelStatus status = ModelStatus::kOk;
  std::uint64_t samples = 0;    ///< pushed into the estimator
  std::uint64_t saturated = 0;  ///< samples that did not fit in int32 counts (clamped)
};

/// The model's ADEV by simulation: the next n_samples of a configured simulator, quantized
/// with `lsb` (imu::quantize) and pushed into `adev` (configured by the caller with the model's
/// Ts and the same lsb; read it with adev.snapshot()) in batches of OnlineAdev::kBatch. The
/// simulator keeps its state, so a caller can go on drawing from it. Cost O(n_samples n^2);
/// stack: one batch of counts (1 kB). No heap.
template <std::size_t kMaxStates, std::size_t M, std::size_t L>
[[nodiscard]] SimAdevResult simulate_adev(ModelSimulator<kMaxStates>& sim,
                                          std::uint64_t n_samples, double lsb,
                                          OnlineAdev<M, L>& adev) {
  SimAdevResult r;
  if (!(lsb > 0.0)) {
    r.status = ModelStatus::kBadParameter;
    return r;
  }
  constexpr std::size_t kBatch = OnlineAdev<M, L>::kBatch;
  std::int32_t buf[kBatch];
  for (std::uint64_t done = 0; done < n_samples;) {
    const std::uint64_t left = n_samples - done;
    const std::size_t b = left < kBatch ? static_cast<std::size_t>(left) : kBatch;
    for (std::size_t i = 0; i < b; ++i) {
      const QuantizeResult q = quantize(sim.next(), lsb);
      r.saturated += q.saturated ? 1U : 0U;
      buf[i] = q.counts;
    }
    adev.push_block(buf, b);
    done += b;
  }
  r.samples = n_samples;
  return r;
}

/// The same from a model and a seed (a new simulator).
template <std::size_t kMaxStates, std::size_t M, std::size_t L>
[[nodiscard]] SimAdevResult simulate_adev(const DiscreteModel<kMaxStates>& model,
                                          std::uint64_t seed, std::uint64_t n_samples,
                                          double lsb, OnlineAdev<M, L>& adev) {
  ModelSimulator<kMaxStates> sim;
  const ModelStatus st = sim.configure(model, seed);
  if (st != ModelStatus::kOk) {
    SimAdevResult r;
    r.status = st;
    return r;
  }
  return simulate_adev(sim, n_samples, lsb, adev);
}

}  // namespace imu

#endif  // IMU_NOISE_SIM_HPP

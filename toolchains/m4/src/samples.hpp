// Deterministic IMU-like samples for the bare-metal program and its host twin: integer-only
// (an LCG), so the Cortex-M4 and the host generate bit-identical input without any table in
// flash. Per channel: constant bias + approximately Gaussian white noise (sum of four uniforms,
// sigma about 18900 counts) + a random walk (steps uniform in +-32 counts, sigma about 18.5).
// Cost: O(1) per sample, a few integer operations. No heap, re-entrant per instance.
#ifndef IMU_M4_SAMPLES_HPP
#define IMU_M4_SAMPLES_HPP

#include <cstdint>

namespace imu::m4 {

/// Numerical Recipes' 32-bit LCG: x' = 1664525 x + 1013904223 (mod 2^32).
class Lcg {
 public:
  explicit constexpr Lcg(std::uint32_t seed) : x_(seed) {}
  constexpr std::uint32_t next() {
    x_ = x_ * 1664525u + 1013904223u;
    return x_;
  }
  /// Uniform integer in [-32768, 32767] from the high bits (the low bits of an LCG are poor).
  constexpr std::int32_t uniform16() { return static_cast<std::int32_t>(next() >> 16) - 32768; }

 private:
  std::uint32_t x_;
};

/// One channel's sample source.
class SampleSource {
 public:
  constexpr SampleSource() : SampleSource(0) {}
  explicit constexpr SampleSource(std::uint32_t channel)
      : rng_(0x9E3779B9u * (channel + 1u)),
        bias_counts_(1000 * (static_cast<std::int32_t>(channel) - 2)) {}

  /// Constant part of the bias and the random walk so far, in counts (the truth a filter tracks).
  constexpr std::int32_t bias_counts() const { return bias_counts_ + walk_counts_; }

  /// Next sample in counts. Stays far inside int32 for any practical length: the walk grows
  /// like 18.5 sqrt(n) counts.
  constexpr std::int32_t next() {
    const std::int32_t white = (rng_.uniform16() + rng_.uniform16() + rng_.uniform16() +
                                rng_.uniform16()) / 2;
    walk_counts_ += rng_.uniform16() / 1024;
    return bias_counts_ + white + walk_counts_;
  }

 private:
  Lcg rng_;
  std::int32_t bias_counts_;
  std::int32_t walk_counts_ = 0;
};

}  // namespace imu::m4

#endif  // IMU_M4_SAMPLES_HPP

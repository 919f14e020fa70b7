// The Cortex-M4 demonstration workload, compiled for the target and for the host with the same
// source: kChannels channels of deterministic samples (samples.hpp) through imu::MultiAdev,
// then one text line per estimated tau. Line format (all fields exact, doubles as IEEE hex):
//   IMU-M4 BEGIN channels=<C> samples=<N> M=<M> L=<L> ts_bits=<hex> lsb_bits=<hex>
//   P c=<ch> af=<m> st=<stride> n=<terms> avar=<hex> adev=<hex> edf=<hex> lo=<hex> hi=<hex>
//   C c=<ch> samples=<n> points=<k>
//   K c=<ch> bias=<f32 hex> var=<f32 hex> truth=<f64 hex> predictions=<n> updates=<n>
//   IMU-M4 END status=ok lines=<count>
// The target appends "IMU-M4 STACK used=<bytes> of=<bytes>" after END (host has no such line).
// Cost: N * C pushes (amortised O(1.5 M) each) + one snapshot per channel. State is static
// (about 5.5 KiB per channel for M = 8, L = 22, plus one snapshot buffer of 96 points).
#ifndef IMU_M4_DEMO_HPP
#define IMU_M4_DEMO_HPP

#include <cstddef>
#include <cstdint>

#ifndef IMU_M4_CHANNELS
#define IMU_M4_CHANNELS 6
#endif

namespace imu::m4 {

inline constexpr std::size_t kChannels = IMU_M4_CHANNELS;
inline constexpr std::size_t kAdevM = 8;
inline constexpr std::size_t kAdevL = 22;
inline constexpr std::uint32_t kSamples = 65536;  ///< per channel (655 s at 100 Hz)
inline constexpr double kSamplePeriodS = 0.01;
inline constexpr double kLsb = 1.0 / 1024.0;      ///< exact in binary: no rounding in the scale

// Bias filter: first-order Gauss-Markov model matched to samples.hpp (units = counts * kLsb):
// white noise sigma 18900 counts -> R = (18900 / 1024)^2; random-walk step sigma 18.5 counts ->
// Qw = (18.5 / 1024)^2; correlation time 1000 s (longer than the run: the walk is nearly
// unbounded), phi = exp(-Ts / 1000 s); initial sigma 4 units (the biases are within +-3).
inline constexpr double kKfPhi = 0.99999000005;   ///< exp(-1e-5)
inline constexpr double kKfQw = 3.2639e-4;
inline constexpr double kKfR = 340.66;
inline constexpr double kKfP0 = 16.0;
/// The sensor is "static" (filter updates) except in the 2nd of every 4 blocks of 8192 samples
/// (the run ends static, so the final estimate is a tracking one).
constexpr bool is_static_sample(std::uint32_t i) { return ((i >> 13) & 3u) != 1u; }

/// Receives one NUL-terminated line (ending in '\n').
using WriteFn = void (*)(const char* line, void* ctx);

enum class DemoStatus : std::uint8_t {
  kOk = 0,
  kLineTruncated,  ///< a line did not fit its buffer (a bug in the format, not in the data)
  kBadFilterModel, ///< ScalarBiasKf::configure rejected the constants above
};

/// Runs the whole workload and writes every line through `write`. Not re-entrant (static state).
[[nodiscard]] DemoStatus run_demo(WriteFn write, void* ctx);

}  // namespace imu::m4

#endif  // IMU_M4_DEMO_HPP

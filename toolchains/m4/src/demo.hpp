// The Cortex-M4 demonstration workload, compiled for the target and for the host with the same
// source: kChannels channels of deterministic samples (samples.hpp) through imu::MultiAdev,
// then one text line per estimated tau. Line format (all fields exact, doubles as IEEE hex):
//   IMU-M4 BEGIN channels=<C> samples=<N> M=<M> L=<L> ts_bits=<hex> lsb_bits=<hex>
//   P c=<ch> af=<m> st=<stride> n=<terms> avar=<hex> adev=<hex> edf=<hex> lo=<hex> hi=<hex>
//   C c=<ch> samples=<n> points=<k>
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

/// Receives one NUL-terminated line (ending in '\n').
using WriteFn = void (*)(const char* line, void* ctx);

enum class DemoStatus : std::uint8_t {
  kOk = 0,
  kLineTruncated,  ///< a line did not fit its buffer (a bug in the format, not in the data)
};

/// Runs the whole workload and writes every line through `write`. Not re-entrant (static state).
[[nodiscard]] DemoStatus run_demo(WriteFn write, void* ctx);

}  // namespace imu::m4

#endif  // IMU_M4_DEMO_HPP

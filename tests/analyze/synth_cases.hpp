// The synthetic cases of the analysis tests: the seed's model (N = 3.3e-3, B = 9e-4, Tp = 300 s,
// 100 Hz, 1e6 samples) plus one effect each, at a size where an expert sees it on the ADEV plot
// or in the time series. Shared by test_analyze_synthetic and the tuning tool.
#ifndef IMU_TESTS_ANALYZE_SYNTH_CASES_HPP
#define IMU_TESTS_ANALYZE_SYNTH_CASES_HPP

#include <cstdint>
#include <string>

#include "imu/analyze/synth.hpp"

namespace imu::analyze::test {

// Effect sizes (true values the tests compare with).
inline constexpr double kQ = 3.8e-4;         // quantization: 3 Q^2/Ts^2 = 4 x the white AVAR at Ts
inline constexpr double kK = 1e-3;           // RRW: crosses the white noise ADEV near 3 s
inline constexpr double kR = 1.3e-5;         // ramp: R tau / sqrt 2 = B at tau = 100 s
inline constexpr double kSinA = 3e-3;        // sinusoid: bump 2.2e-3 over a model ADEV of 1.3e-3
inline constexpr double kSinF = 0.05;        //   at tau = 0.371 / f = 7.4 s
inline constexpr double kStepTime = 6000.0;  // bias step: 20 x the GM std (1.46e-3)
inline constexpr double kStepSize = 0.03;
inline constexpr std::size_t kOutliers = 50;  // outliers: 10 x the white std per sample (0.033)
inline constexpr double kOutlierSize = 0.33;

inline SynthSpec make_case(const std::string& name, std::uint64_t seed) {
  SynthSpec s;
  s.seed = seed;
  s.offset = 0.1;
  if (name == "quantization") {
    s.q = kQ;
  } else if (name == "rate_random_walk") {
    s.k = kK;
  } else if (name == "ramp") {
    s.ramp_r = kR;
  } else if (name == "sinusoid") {
    s.sin_a = kSinA;
    s.sin_f_hz = kSinF;
  } else if (name == "bias_step") {
    s.step_time_s = kStepTime;
    s.step_size = kStepSize;
  } else if (name == "outliers") {
    s.n_outliers = kOutliers;
    s.outlier_size = kOutlierSize;
  }
  return s;  // "control": the seed's model alone
}

}  // namespace imu::analyze::test

#endif  // IMU_TESTS_ANALYZE_SYNTH_CASES_HPP

// The synthetic cases of the analysis tests: the first-order model (N = 3.3e-3, B = 9e-4, Tp = 300 s,
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

// Cases (the first-order model plus one effect; sizes of our own, not the shared data's):
inline constexpr double kBi = 2e-3;  // bias instability B: flicker floor 0.664 B = 1.33e-3, flat
                                     // from ~20 s (where white N/sqrt(tau) meets it) to T/10
inline constexpr double kGmSigma = 1.46e-3;      // the example GM's std sqrt(Pss)
inline constexpr double kStep3Size = 3.0 * kGmSigma;  // a step of 3 GM sigmas,
inline constexpr double kStep3Time = 16000.0;          // late in a 20,000 s record
inline constexpr std::size_t kStep3Samples = 2000000;
// Narrowband oscillation (a vibration mode): sigma 0.6 x the white noise's per-sample std
// (0.033), at 6 Hz, half-power width 0.5 Hz; the ADEV bump it makes near tau = 0.06 s is 1.9 x
// the white noise's AVAR there.
inline constexpr double kOscSigma = 0.02;
inline constexpr double kOscF0 = 6.0;
inline constexpr double kOscBeta = 3.14159265358979323846 * 0.5;
inline constexpr double kDriftWalk = 2e-6;  // "unknown": AVAR q^2 tau^3 / 20 meets the model near 200 s

// "_alt" cases: another first-order model (N = 5e-4, B = 2e-4, Tp = 60 s, 3e5 samples), so the
// thresholds are not tied to the first-order model.
inline constexpr double kAltSinA = 2e-3;
inline constexpr double kAltSinF = 2.0;
inline constexpr double kAltStepTime = 1000.0;
inline constexpr double kAltStepSize = 3e-3;
inline constexpr std::size_t kAltOutliers = 30;
inline constexpr double kAltR = 1e-5;

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
  } else if (name == "bias_instability") {
    s.flicker_b = kBi;
  } else if (name == "bias_step_3sigma") {
    s.samples = kStep3Samples;
    s.step_time_s = kStep3Time;
    s.step_size = kStep3Size;
  } else if (name == "control_nan") {
    s.nan_gaps = 5;  // five logger dropouts of 10 s
    s.nan_gap_len = 1000;
  } else if (name == "drift_walk") {
    s.drift_walk = kDriftWalk;
  } else if (name == "oscillation") {
    s.osc_sigma = kOscSigma;
    s.osc_f0_hz = kOscF0;
    s.osc_beta_per_s = kOscBeta;
  }
  if (name.size() > 4 && name.compare(name.size() - 4, 4, "_alt") == 0) {
    // Another first-order model: gyro-like, short GM, shorter record (generalisation checks).
    s.n = 5e-4;
    s.b = 2e-4;
    s.tp_s = 60.0;
    s.samples = 300000;
    if (name == "sinusoid_alt") {
      s.sin_a = kAltSinA;
      s.sin_f_hz = kAltSinF;
    } else if (name == "bias_step_alt") {
      s.step_time_s = kAltStepTime;
      s.step_size = kAltStepSize;
    } else if (name == "outliers_alt") {
      s.n_outliers = kAltOutliers;
      s.outlier_size = 0.05;  // 10 x the white std per sample (5e-3)
    } else if (name == "ramp_alt") {
      s.ramp_r = kAltR;
    }
  }
  return s;  // "control": the first-order model alone
}

}  // namespace imu::analyze::test

#endif  // IMU_TESTS_ANALYZE_SYNTH_CASES_HPP

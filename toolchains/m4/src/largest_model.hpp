// The largest model the node runs, for the M4 node images (the test workload and the production
// image's smoke board) and their host twin.
#ifndef IMU_M4_LARGEST_MODEL_HPP
#define IMU_M4_LARGEST_MODEL_HPP

#include <cstdint>

#include "imu/hal/codec.hpp"

namespace imu::m4 {

/// The largest model the node runs (8 model states): white, 2 GM, RRW and a flicker bank over 3
/// decades (5 GMs; 1 s .. 1e3 s: a wider bank is refused as more than 8 states), in the units of
/// samples.hpp's channels (white sigma 18.5 units per sample at 100 Hz: N = 1.85 units/sqrt(Hz)).
inline hal::ModelRecord largest_model(std::uint8_t channel) {
  hal::ModelRecord m{};
  m.version = hal::kModelVersion1;
  m.channel = channel;
  m.n = 1.85F;
  m.gm_sb[0] = 1e-4F;
  m.gm_tb_s[0] = 50.0F;
  m.gm_sb[1] = 1e-3F;
  m.gm_tb_s[1] = 2.0F;
  m.k = 0.18F;
  m.bi = 0.05F;
  m.bi_tau_lo_s = 1.0F;
  m.bi_tau_hi_s = 1e3F;
  return m;
}

}  // namespace imu::m4

#endif  // IMU_M4_LARGEST_MODEL_HPP

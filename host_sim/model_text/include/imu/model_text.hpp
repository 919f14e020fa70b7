// Text reports of error models for the host CLI (imu-sim model). Host only: allocates.
#ifndef IMU_MODEL_TEXT_HPP
#define IMU_MODEL_TEXT_HPP

#include <string>

#include "imu/error_model.hpp"

namespace imu {

/// The continuous and discrete first-order model in the layout of Farrell's ASD-to-state-space
/// example (its printed output): same sentences, same order, %.4e numbers, phi as %.4f. Lines
/// end with '\n'; a blank line separates the two models.
[[nodiscard]] std::string format_first_order_model(const FirstOrderGm& m);

/// One line per term present in p (e.g. a fit result): N, Q, each GM (Sb, Tb and its ADEV peak
/// B = 0.4365 sqrt(Sb Tb)), K, R, sinusoid; %.4e numbers; "u" stands for the channel's
/// unit (m/s^2 or rad/s).
[[nodiscard]] std::string format_model_params(const ModelParams& p);

}  // namespace imu

#endif  // IMU_MODEL_TEXT_HPP

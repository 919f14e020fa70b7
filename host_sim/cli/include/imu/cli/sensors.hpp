// Which sensor a channel belongs to and the unit its numbers are in: declared on the command
// line (--acc/--gyro, --acc-unit/--gyro-unit), else guessed from the channel's name and, for an
// accelerometer, checked by the norm of a static triad's means (about 1 in g, about 9.81 in
// m/s^2). Every analysis runs in SI units (m/s^2, rad/s); a declared or detected other unit is
// a scale factor applied on reading, said in a note. Host code.
#ifndef IMU_CLI_SENSORS_HPP
#define IMU_CLI_SENSORS_HPP

#include <string>
#include <vector>

namespace imu::cli {

enum class Sensor { kUnknown, kAcc, kGyro };

/// "accelerometer", "gyroscope" or "" (unknown).
[[nodiscard]] const char* sensor_name(Sensor s);
/// The SI unit the analysis reports a sensor in: m/s^2, rad/s; "unit" for an unknown one.
[[nodiscard]] const char* si_unit(Sensor s);

/// The sensor a channel's name suggests (its last field for a struct's, the column's matrix
/// name without :K): acc*, accel*, a_* (EuRoC a_RS_S_x), ax/ay/az, linear_acceleration* are
/// accelerometers; gyro*, gyr*, w_* (EuRoC w_RS_S_x), omega*, gx/gy/gz, wx/wy/wz,
/// angular_velocity* are gyroscopes (case ignored); anything else unknown.
[[nodiscard]] Sensor guess_sensor(const std::string& channel);

/// The factor from a unit to SI for a sensor: g (9.80665 m/s^2 per g, the standard gravity),
/// m/s^2 (also m/s2) for an accelerometer; rad/s, deg/s (also dps), deg/h for a gyroscope.
/// False (err lists the accepted units) for another.
[[nodiscard]] bool unit_to_si(Sensor s, const std::string& unit, double& factor, std::string& err);

/// Standard gravity [m/s^2] (CGPM 1901): 1 g.
inline constexpr double kStandardGravity = 9.80665;

/// The unit a static accelerometer triad's mean norm points to: "g" for a norm in
/// [0.85, 1.15], "m/s^2" for one in [8.3, 11.3], "" for neither (not static, or another unit).
[[nodiscard]] std::string unit_from_gravity(double mean_norm);

}  // namespace imu::cli

#endif  // IMU_CLI_SENSORS_HPP

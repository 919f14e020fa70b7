// Sensors and units of a channel (see sensors.hpp).
#include "imu/cli/sensors.hpp"

#include <cctype>
#include <cmath>
#include <string>

namespace imu::cli {
namespace {

std::string lower(std::string s) {
  for (char& c : s) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return s;
}

bool starts(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

const char* sensor_name(Sensor s) {
  switch (s) {
    case Sensor::kAcc: return "accelerometer";
    case Sensor::kGyro: return "gyroscope";
    case Sensor::kUnknown: break;
  }
  return "";
}

const char* si_unit(Sensor s) {
  switch (s) {
    case Sensor::kAcc: return "m/s^2";
    case Sensor::kGyro: return "rad/s";
    case Sensor::kUnknown: break;
  }
  return "unit";
}

Sensor guess_sensor(const std::string& channel) {
  std::string name = channel.substr(0, channel.find(':'));
  name = lower(name.substr(name.rfind('.') + 1));
  if (starts(name, "acc") || starts(name, "a_") || starts(name, "linear_acceleration") ||
      name == "ax" || name == "ay" || name == "az") {
    return Sensor::kAcc;
  }
  if (starts(name, "gyr") || starts(name, "w_") || starts(name, "omega") ||
      starts(name, "angular_velocity") || name == "gx" || name == "gy" || name == "gz" ||
      name == "wx" || name == "wy" || name == "wz") {
    return Sensor::kGyro;
  }
  return Sensor::kUnknown;
}

bool unit_to_si(Sensor s, const std::string& unit, double& factor, std::string& err) {
  constexpr double kPi = 3.14159265358979323846;
  const std::string u = lower(unit);
  if (s == Sensor::kAcc) {
    if (u == "g") {
      factor = kStandardGravity;
      return true;
    }
    if (u == "m/s^2" || u == "m/s2") {
      factor = 1.0;
      return true;
    }
    err = "accelerometer unit '" + unit + "': g or m/s^2";
    return false;
  }
  if (s == Sensor::kGyro) {
    if (u == "rad/s") {
      factor = 1.0;
      return true;
    }
    if (u == "deg/s" || u == "dps") {
      factor = kPi / 180.0;
      return true;
    }
    if (u == "deg/h") {
      factor = kPi / 180.0 / 3600.0;
      return true;
    }
    err = "gyroscope unit '" + unit + "': rad/s, deg/s or deg/h";
    return false;
  }
  err = "a unit needs a sensor (accelerometer or gyroscope)";
  return false;
}

std::string unit_from_gravity(double mean_norm) {
  if (!std::isfinite(mean_norm)) {
    return "";
  }
  if (mean_norm >= 0.85 && mean_norm <= 1.15) {
    return "g";
  }
  if (mean_norm >= 8.3 && mean_norm <= 11.3) {
    return "m/s^2";
  }
  return "";
}

}  // namespace imu::cli

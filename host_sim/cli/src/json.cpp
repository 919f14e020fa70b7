// The shared JSON scalars (see imu/cli/json.hpp).
#include "imu/cli/json.hpp"

#include <cmath>
#include <cstdio>

namespace imu::cli {

std::string json_num(double v) {
  if (!std::isfinite(v)) {
    return "null";
  }
  char buf[40];
  (void)std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string json_str(const std::string& s) {
  std::string o = "\"";
  for (const char ch : s) {
    switch (ch) {
      case '"': o += "\\\""; break;
      case '\\': o += "\\\\"; break;
      case '\n': o += "\\n"; break;
      case '\t': o += "\\t"; break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20) {
          char buf[8];
          (void)std::snprintf(buf, sizeof buf, "\\u%04x",
                              static_cast<unsigned>(static_cast<unsigned char>(ch)));
          o += buf;
        } else {
          o += ch;
        }
    }
  }
  return o + "\"";
}

std::string json_units(const std::string& unit) {
  const std::string u = json_str(unit).substr(1, std::string::npos);  // escaped, no quotes
  const std::string base = u.substr(0, u.size() - 1);
  return "{\"n\": \"" + base + "/sqrt(Hz)\", \"q\": \"" + base + "*s\", \"b\": \"" + base +
         "\", \"k\": \"" + base + "*sqrt(Hz)\", \"r\": \"" + base + "/s\", \"sb\": \"" + base +
         "\", \"tb_s\": \"s\", \"sigma\": \"" + base + "\", \"amplitude\": \"" + base +
         "\", \"size\": \"" + base + "\", \"adev\": \"" + base + "\"}";
}

}  // namespace imu::cli

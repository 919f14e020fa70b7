// The shared JSON scalars (see imu/cli/json.hpp).
#include "imu/cli/json.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

namespace imu::cli {

std::string json_num(double v) {
  if (!std::isfinite(v)) {
    return "null";
  }
  char buf[40];
  (void)std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::size_t utf8_sequence(const std::string& s, std::size_t i) {
  const std::size_t n = s.size();
  const auto u = static_cast<unsigned char>(s[i]);
  if (u < 0x80U) {
    return 1;
  }
  const std::size_t len = u >= 0xf0U && u <= 0xf4U ? 4 : u >= 0xe0U && u < 0xf0U ? 3 : u >= 0xc2U && u < 0xe0U ? 2 : 0;
  if (len == 0 || i + len > n) {
    return 0;
  }
  std::uint32_t cp = len == 2 ? (u & 0x1fU) : len == 3 ? (u & 0x0fU) : (u & 0x07U);
  for (std::size_t k = 1; k < len; ++k) {
    const auto c = static_cast<unsigned char>(s[i + k]);
    if ((c & 0xc0U) != 0x80U) {
      return 0;
    }
    cp = (cp << 6U) | (c & 0x3fU);
  }
  const bool overlong = (len == 3 && cp < 0x800U) || (len == 4 && cp < 0x10000U);
  const bool surrogate = cp >= 0xd800U && cp <= 0xdfffU;
  return overlong || surrogate || cp > 0x10ffffU ? 0 : len;
}

std::string json_str(const std::string& s) {
  std::string o = "\"";
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char ch = s[i];
    if (static_cast<unsigned char>(ch) >= 0x80U) {
      // Valid UTF-8 is copied; a byte that is not (a Latin-1 name, a cut sequence) becomes
      // U+FFFD, so the JSON is always valid UTF-8.
      const std::size_t len = utf8_sequence(s, i);
      if (len == 0) {
        o += "\\ufffd";
      } else {
        o.append(s, i, len);
        i += len - 1;
      }
      continue;
    }
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
         "\", \"k\": \"" + base + "*sqrt(Hz)\", \"r\": \"" + base + "/s\", \"sb\": \"(" + base +
         ")^2/s\", \"tb_s\": \"s\", \"sigma\": \"" + base + "\", \"amplitude\": \"" + base +
         "\", \"size\": \"" + base + "\", \"adev\": \"" + base + "\"}";
}

std::string json_head(const std::string& command, const std::string& source,
                      const std::string& indent) {
  return indent + "\"schema_version\": " + std::to_string(kJsonSchemaVersion) + ",\n" + indent +
         "\"command\": " + json_str(command) + ",\n" + indent + "\"source\": " + json_str(source) +
         ",\n";
}

std::string num_text(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

}  // namespace imu::cli

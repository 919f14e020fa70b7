// Test helpers shared by the analysis tests on synthetic records: an analysis that must succeed
// and tell one story (report_consistent), and whether a report names an effect.
#ifndef IMU_TESTS_ANALYZE_ANALYSE_CHECKED_HPP
#define IMU_TESTS_ANALYZE_ANALYSE_CHECKED_HPP

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "imu/analyze/analyze.hpp"

namespace imu::analyze::test {

inline Report analyse_checked(const std::vector<double>& y, const std::string& name,
                              std::uint64_t seed, double fs_hz = 0.0) {
  Report r;
  std::string err;
  Options o;
  if (fs_hz > 0.0) {
    o.fs_hz = fs_hz;
  }
  EXPECT_TRUE(analyze(y, name, o, r, err)) << err;
  std::string why;
  EXPECT_TRUE(report_consistent(r, why)) << name << " seed " << seed << ": " << why;
  return r;
}

inline bool named(const Report& r, const std::string& type) {
  for (const auto& e : r.effects) {
    if (e.type == type) {
      return true;
    }
  }
  return false;
}

}  // namespace imu::analyze::test

#endif  // IMU_TESTS_ANALYZE_ANALYSE_CHECKED_HPP

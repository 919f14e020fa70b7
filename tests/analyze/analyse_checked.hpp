// Test helpers shared by the analysis tests on synthetic records: an analysis that must succeed
// and tell one story (report_consistent), whether a report names an effect, and whether a slow
// GM stands in for a walk.
#ifndef IMU_TESTS_ANALYZE_ANALYSE_CHECKED_HPP
#define IMU_TESTS_ANALYZE_ANALYSE_CHECKED_HPP

#include <gtest/gtest.h>

#include <cmath>
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

// No walk named and the model after one GM (no K) whose Tb's 95 % interval is open above: the
// first-order model's own GM slower than the record resolves, which took the place of a walk the
// record does not tell from it (analyze.cpp slow_gm_for_walk).
inline bool slow_gm_stands_in(const Report& r) {
  if (r.model_after.n_gm != 1 || r.model_after.k > 0.0 || named(r, "rate_random_walk")) {
    return false;
  }
  for (const auto& iv : r.model_after_ci95) {
    if (iv.name == "gm_tb_s") {
      return std::isinf(iv.hi);
    }
  }
  return false;
}

}  // namespace imu::analyze::test

#endif  // IMU_TESTS_ANALYZE_ANALYSE_CHECKED_HPP

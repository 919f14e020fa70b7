// The analysis's in-place radix sort against std::sort: the same sequence on values of both
// signs, zeros, repeated lattice levels, magnitudes far apart, and sizes around the point where
// it hands a bucket to std::sort.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "radix_sort.hpp"

namespace {

void expect_sorted_like_std(std::vector<double> v) {
  std::vector<double> ref(v);
  std::sort(ref.begin(), ref.end());
  imu::analyze::sort_finite(v);
  ASSERT_EQ(v.size(), ref.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    ASSERT_EQ(v[i], ref[i]) << "at " << i << " of " << v.size();
  }
}

TEST(RadixSort, MatchesStdSortOnGaussianValuesOfBothSigns) {
  std::mt19937_64 rng(920417);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const std::size_t size : {0U, 1U, 2U, 63U, 64U, 65U, 1000U, 100000U}) {
    std::vector<double> v(size);
    for (double& x : v) {
      x = n(rng);
    }
    expect_sorted_like_std(v);
  }
}

TEST(RadixSort, MatchesStdSortOnLatticeLevelsZerosAndWideMagnitudes) {
  std::mt19937_64 rng(920418);
  std::normal_distribution<double> n(0.0, 3.0);
  std::vector<double> v(200000);
  for (std::size_t i = 0; i < v.size(); ++i) {
    switch (i % 4) {
      case 0:  // an accelerometer's lattice: gravity plus whole steps, with residue
        v[i] = 9.80665 + 0.0025 * std::round(n(rng));
        break;
      case 1:
        v[i] = (i % 8 == 1) ? 0.0 : -0.0;
        break;
      case 2:
        v[i] = std::ldexp(n(rng), static_cast<int>(i % 600) - 300);
        break;
      default:
        v[i] = -std::fabs(n(rng)) * 1e-6;
    }
  }
  expect_sorted_like_std(v);
}

}  // namespace

// 2^32 samples through the online ADEV must lose no more than 1e-9 relative accuracy against an
// exact reference. The input is periodic with period P = 2^16 and large values, so the
// exact sum of squared second differences over the whole record is computable in 128-bit
// integers from one period: every term's value depends only on its start index modulo P.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "imu/online_adev.hpp"

namespace {

__extension__ using Int128 = __int128;

constexpr std::uint64_t kPeriod = 1ULL << 16U;
constexpr std::uint64_t kSamples = 1ULL << 32U;

std::vector<std::int32_t> make_period() {
  std::vector<std::int32_t> y(kPeriod);
  std::uint64_t s = 0x9E3779B97F4A7C15ULL;
  for (auto& v : y) {
    s ^= s << 13U;
    s ^= s >> 7U;
    s ^= s << 17U;
    // Values up to +-2^30 with a mean offset of 2^29: squares up to ~2^70, phase wraps int64.
    v = static_cast<std::int32_t>(static_cast<std::int64_t>(s >> 34U) - (1LL << 29U));
  }
  return y;
}

// Exact sum over terms starting at i = 0, stride, 2 stride, ... while i + 2 af <= n.
Int128 exact_sum(const std::vector<std::int32_t>& y, std::uint64_t af, std::uint64_t stride,
                 std::uint64_t n, std::uint64_t& terms) {
  // Phase over two periods plus 2 af, relative to x_0 (x is periodic up to a linear drift, and
  // second differences cancel the drift).
  std::vector<Int128> x(2 * kPeriod + 2 * af + 1, 0);
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    x[i + 1] = x[i] + y[i % kPeriod];
  }
  const std::uint64_t last = n - 2 * af;  // last valid start index
  terms = last / stride + 1;
  const std::uint64_t per_period = kPeriod / stride;
  Int128 one_period = 0;
  for (std::uint64_t i = 0; i < kPeriod; i += stride) {
    const Int128 d = x[i + 2 * af] - 2 * x[i + af] + x[i];
    one_period += d * d;
  }
  const std::uint64_t full = terms / per_period;
  Int128 sum = one_period * static_cast<Int128>(full);
  for (std::uint64_t t = full * per_period; t < terms; ++t) {
    const std::uint64_t i = (t * stride) % kPeriod;
    const Int128 d = x[i + 2 * af] - 2 * x[i + af] + x[i];
    sum += d * d;
  }
  return sum;
}

TEST(AdevNumerics, TwoToThe32SamplesWithinOneInABillion) {
  const auto y = make_period();
  imu::OnlineAdev<8, 24> adev(1.0, 1.0);
  for (std::uint64_t done = 0; done < kSamples; done += kPeriod) {
    adev.push_block(y.data(), y.size());
  }
  ASSERT_EQ(adev.samples(), kSamples);
  std::vector<imu::AdevPoint> pts(adev.kMaxPoints);
  pts.resize(adev.snapshot(pts.data(), pts.size()));
  double worst = 0.0;
  int checked = 0;
  for (const auto& p : pts) {
    if (p.af > 4096) {
      continue;  // the exact reference needs the phase over 2 periods + 2 af
    }
    std::uint64_t terms = 0;
    const Int128 s = exact_sum(y, p.af, p.stride, kSamples, terms);
    ASSERT_EQ(p.n_terms, terms) << "af " << p.af;
    const long double exact = static_cast<long double>(s) /
                              (2.0L * static_cast<long double>(p.af) * p.af * terms);
    const double rel = static_cast<double>(std::fabs(static_cast<long double>(p.avar) / exact - 1));
    worst = std::max(worst, rel);
    EXPECT_LE(rel, 1e-9) << "af " << p.af;
    ++checked;
  }
  std::printf("2^32 samples: %d taus checked, worst relative error of AVAR %.3g\n", checked, worst);
  EXPECT_GE(checked, 30);
}

}  // namespace

// Tests of the online ADEV (fw/include/imu/online_adev.hpp) through its public API, against an
// independent brute-force reference written here from MODELS.md's formula.
#include "imu/online_adev.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

__extension__ using Int128 = __int128;  // exact phase for the reference
using Adev = imu::OnlineAdev<8, 22>;

// Brute-force AVAR at averaging factor af with a stride of `stride` samples, from the phase
// points of gap-free segments. Sample i is missing when missing[i] is true. Terms start at phase
// indices that are multiples of the stride (the online estimator's decimation grid).
// Accumulates in long double from exact int64 second differences.
struct RefPoint {
  double avar;
  std::uint64_t terms;
};
RefPoint brute_avar(const std::vector<std::int32_t>& y, const std::vector<bool>& missing,
                    std::uint64_t af, std::uint64_t stride, double lsb) {
  const std::size_t n = y.size();
  // phase[i] valid flag: x_i is in the same segment as x_j iff no missing sample in [i, j).
  std::vector<Int128> x(n + 1, 0);
  std::vector<std::uint64_t> seg(n + 1, 0);  // segment id of each phase point
  std::uint64_t id = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (missing[i]) {
      ++id;
      x[i + 1] = x[i];
    } else {
      x[i + 1] = x[i] + y[i];
    }
    seg[i + 1] = id;
  }
  long double sum = 0;
  std::uint64_t terms = 0;
  for (std::size_t k = 0; k + 2 * af <= n; k += stride) {
    if (seg[k] != seg[k + 2 * af]) {
      continue;
    }
    // x_k belongs to the segment that starts after the gap: the segment of x_k is seg[k], and a
    // missing sample i (between x_i and x_{i+1}) gives x_{i+1} a new id, so equal ids at both
    // ends mean no gap inside.
    const Int128 d = x[k + 2 * af] - 2 * x[k + af] + x[k];
    const auto dl = static_cast<long double>(d);
    sum += dl * dl;
    ++terms;
  }
  if (terms == 0) {
    return {0.0, 0};
  }
  const auto afl = static_cast<long double>(af);
  const auto lsbl = static_cast<long double>(lsb);
  const auto terms_l = static_cast<long double>(terms);
  return {static_cast<double>(lsbl * lsbl * sum / (2 * afl * afl * terms_l)), terms};
}

template <typename Estimator>
std::vector<imu::AdevPoint> snap(const Estimator& a) {
  std::vector<imu::AdevPoint> pts(Estimator::kMaxPoints);
  pts.resize(a.snapshot(pts.data(), pts.size()));
  return pts;
}

std::vector<std::int32_t> white_plus_walk(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 30.0);
  std::vector<std::int32_t> y(n);
  double walk = 0.0;
  for (auto& v : y) {
    walk += 0.05 * g(rng) / 30.0;
    v = static_cast<std::int32_t>(std::lround(g(rng) + walk));
  }
  return y;
}

// The estimator is exactly the partially overlapping estimator on the decimation grid.
TEST(OnlineAdev, MatchesBruteForceOnTheSameGrid) {
  const auto y = white_plus_walk(50000, 1);
  const std::vector<bool> missing(y.size(), false);
  Adev a(0.01, 0.5);
  a.push_block(y.data(), y.size());
  const auto pts = snap(a);
  ASSERT_GT(pts.size(), 30U);
  for (const auto& p : pts) {
    const RefPoint r = brute_avar(y, missing, p.af, p.stride, 0.5);
    ASSERT_EQ(p.n_terms, r.terms) << "af " << p.af;
    // Reason for 1e-12: double accumulation of up to 5e4 exact squares vs long double.
    EXPECT_NEAR(p.avar, r.avar, 1e-12 * r.avar) << "af " << p.af;
    EXPECT_NEAR(p.tau_s, 0.01 * p.af, 1e-12);
  }
}

// Against the fully overlapping estimator (stride 1), the criterion: within 1 % or a
// quarter of the 68 % interval's relative half-width, for taus up to a tenth of the record.
// The two estimators legitimately differ: the partial one uses a subset of the full one's terms,
// so their relative difference has a standard deviation of about
// 0.5 sqrt(2/edf_partial - 2/edf_full), which is 0.14 to 0.22 of the relative half-width (EDF
// ratio 0.95..0.98, see test_edf). The criterion is therefore a ~1.5 sigma bound at long tau; the
// test requires it at >= 85 % of the taus and a 3-sigma bound at every tau, and prints the worst.
TEST(OnlineAdev, AgreesWithFullyOverlappingReference) {
  const auto y = white_plus_walk(200000, 2);
  const std::vector<bool> missing(y.size(), false);
  Adev a(0.01, 1.0);
  a.push_block(y.data(), y.size());
  int total = 0;
  int strict_ok = 0;
  double worst_ratio = 0.0;
  for (const auto& p : snap(a)) {
    if (p.af > y.size() / 10) {
      continue;
    }
    const RefPoint full = brute_avar(y, missing, p.af, 1, 1.0);
    const double ref = std::sqrt(full.avar);
    const double rel = std::fabs(p.adev / ref - 1.0);
    const double half = 0.5 * (p.ci_hi - p.ci_lo) / p.adev;
    const double bound = std::max(0.01, 0.25 * half);
    const double edf_full = imu::edf_greenhall(0, 2, p.af, p.af, static_cast<double>(full.terms));
    const double sigma = 0.5 * std::sqrt(std::max(0.0, 2.0 / p.edf - 2.0 / edf_full));
    ++total;
    strict_ok += rel <= bound ? 1 : 0;
    worst_ratio = std::max(worst_ratio, rel / bound);
    EXPECT_LE(rel, std::max(bound, 3.0 * sigma)) << "af " << p.af;
  }
  std::printf("within 1%%/quarter-half-width: %d of %d taus; worst rel/bound %.3f\n", strict_ok,
              total, worst_ratio);
  EXPECT_GE(strict_ok, (85 * total) / 100);
}

TEST(OnlineAdev, TauGridHasFourPerOctave) {
  Adev a;
  std::vector<std::int32_t> y(5000, 0);
  std::mt19937 rng(3);
  for (auto& v : y) {
    v = static_cast<std::int32_t>(rng() % 100);
  }
  a.push_block(y.data(), y.size());
  const auto pts = snap(a);
  const std::uint32_t expect[] = {1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40};
  ASSERT_GE(pts.size(), std::size(expect));
  for (std::size_t i = 0; i < std::size(expect); ++i) {
    EXPECT_EQ(pts[i].af, expect[i]);
  }
  for (std::size_t i = 1; i < pts.size(); ++i) {
    EXPECT_GT(pts[i].tau_s, pts[i - 1].tau_s);
    EXPECT_GE(pts[i].stride * 8, pts[i].af);  // stride >= tau / M
    if (pts[i].af > 4) {                      // level 0 keeps stride 1 for m <= M/2 too
      EXPECT_LE(pts[i].stride * 8, 2 * pts[i].af);  // stride <= 2 tau / M
    }
  }
}

TEST(OnlineAdev, DefaultReachesFortyEightHoursAtHundredHertz) {
  constexpr double kMaxTau = (1ULL << 22) * 8 * 0.01;
  EXPECT_GE(kMaxTau, 48.0 * 3600.0);
  EXPECT_EQ(Adev::kMaxPoints, 8U + 22U * 4U);
}

TEST(OnlineAdev, GapsAreNotSpanned) {
  auto y = white_plus_walk(60000, 4);
  std::vector<bool> missing(y.size(), false);
  // A gap at the very start, single drops, a long gap, and a gap at the very end.
  for (std::size_t i : {0UL, 1UL, 777UL, 12345UL, 59999UL}) {
    missing[i] = true;
  }
  for (std::size_t i = 30000; i < 30500; ++i) {
    missing[i] = true;
  }
  Adev a(0.01, 1.0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (missing[i]) {
      a.mark_missing(1);
    } else {
      a.push(y[i]);
    }
  }
  EXPECT_EQ(a.samples(), y.size());
  EXPECT_EQ(a.missing_samples(), 505U);
  for (const auto& p : snap(a)) {
    const RefPoint r = brute_avar(y, missing, p.af, p.stride, 1.0);
    ASSERT_EQ(p.n_terms, r.terms) << "af " << p.af;
    EXPECT_NEAR(p.avar, r.avar, 1e-12 * r.avar) << "af " << p.af;
  }
}

// A gap must not bias: a big step hidden inside a gap leaves the white-noise ADEV untouched,
// whereas pushing it as data would not.
TEST(OnlineAdev, GapHidesOffsetJump) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 10.0);
  Adev gapped;
  Adev clean;
  for (int i = 0; i < 100000; ++i) {
    const double offset = i < 50000 ? 0.0 : 100000.0;
    const auto c = static_cast<std::int32_t>(std::lround(g(rng)));
    clean.push(c);
    if (i == 50000) {
      gapped.mark_missing(3);
    }
    gapped.push(static_cast<std::int32_t>(c + offset));
  }
  const auto pg = snap(gapped);
  const auto pc = snap(clean);
  // Taus longer than half of each segment have no term in the gapped run (they would span it).
  ASSERT_LT(pg.size(), pc.size());
  ASSERT_GT(pg.size(), 40U);
  for (std::size_t i = 0; i < pg.size(); ++i) {
    ASSERT_EQ(pg[i].af, pc[i].af);
    // A leaked jump would add (1e5)^2 to a term and multiply the short-tau ADEV by ~20.
    // Reason for the tolerance: both are estimates of the same noise from nearly the same terms.
    EXPECT_NEAR(pg[i].adev, pc[i].adev, 0.05 * pc[i].adev + 1.5 * (pg[i].ci_hi - pg[i].ci_lo))
        << "af " << pc[i].af;
  }
}

TEST(OnlineAdev, FewerSamplesThanOneTau) {
  Adev a;
  EXPECT_EQ(snap(a).size(), 0U);
  a.push(5);
  EXPECT_EQ(snap(a).size(), 0U);  // 2 phase points: no second difference yet
  a.push(7);
  const auto pts = snap(a);
  ASSERT_EQ(pts.size(), 1U);
  EXPECT_EQ(pts[0].af, 1U);
  EXPECT_EQ(pts[0].n_terms, 1U);
  EXPECT_DOUBLE_EQ(pts[0].avar, 4.0 / 2.0);  // (7 - 5)^2 / 2
}

TEST(OnlineAdev, ConstantInputGivesExactlyZero) {
  Adev a(0.01, 0.033);
  for (int i = 0; i < 300000; ++i) {
    a.push(123456);
  }
  const auto pts = snap(a);
  ASSERT_FALSE(pts.empty());
  for (const auto& p : pts) {
    EXPECT_EQ(p.adev, 0.0) << "af " << p.af;
    EXPECT_EQ(p.ci_hi, 0.0);
  }
}

TEST(OnlineAdev, FullScaleInt32IsExact) {
  // Constant full scale: the phase wraps many times, second differences stay exactly zero.
  Adev c;
  for (int i = 0; i < 100000; ++i) {
    c.push(std::numeric_limits<std::int32_t>::max());
  }
  for (const auto& p : snap(c)) {
    EXPECT_EQ(p.adev, 0.0);
  }
  // Alternating extremes and random full-scale values against the exact reference.
  std::mt19937 rng(6);
  std::vector<std::int32_t> y(40000);
  for (std::size_t i = 0; i < y.size(); ++i) {
    y[i] = (i % 3 == 0) ? std::numeric_limits<std::int32_t>::min()
                        : static_cast<std::int32_t>(rng());
  }
  const std::vector<bool> missing(y.size(), false);
  Adev a;
  a.push_block(y.data(), y.size());
  for (const auto& p : snap(a)) {
    const RefPoint r = brute_avar(y, missing, p.af, p.stride, 1.0);
    EXPECT_NEAR(p.avar, r.avar, 1e-12 * r.avar) << "af " << p.af;
  }
}

TEST(OnlineAdev, ResetForgetsEverything) {
  const auto y = white_plus_walk(20000, 7);
  Adev a;
  a.push_block(y.data(), 5000);
  a.mark_missing(10);
  a.reset();
  EXPECT_EQ(a.samples(), 0U);
  EXPECT_EQ(a.gaps(), 0U);
  EXPECT_EQ(snap(a).size(), 0U);
  a.push_block(y.data(), y.size());
  Adev fresh;
  fresh.push_block(y.data(), y.size());
  const auto pa = snap(a);
  const auto pf = snap(fresh);
  ASSERT_EQ(pa.size(), pf.size());
  for (std::size_t i = 0; i < pa.size(); ++i) {
    EXPECT_EQ(pa[i].avar, pf[i].avar);
    EXPECT_EQ(pa[i].n_terms, pf[i].n_terms);
  }
}

TEST(OnlineAdev, GapAtTheEndChangesNothing) {
  const auto y = white_plus_walk(30000, 8);
  Adev a;
  a.push_block(y.data(), y.size());
  const auto before = snap(a);
  a.mark_missing(1000);
  const auto after = snap(a);
  ASSERT_EQ(before.size(), after.size());
  for (std::size_t i = 0; i < before.size(); ++i) {
    EXPECT_EQ(before[i].avar, after[i].avar);
    EXPECT_EQ(before[i].n_terms, after[i].n_terms);
  }
}

TEST(OnlineAdev, SnapshotDoesNotDisturbIngestion) {
  const auto y = white_plus_walk(40000, 9);
  Adev a;
  Adev b;
  for (std::size_t i = 0; i < y.size(); ++i) {
    a.push(y[i]);
    b.push(y[i]);
    if (i % 997 == 0) {
      (void)snap(a);
    }
  }
  const auto pa = snap(a);
  const auto pb = snap(b);
  ASSERT_EQ(pa.size(), pb.size());
  for (std::size_t i = 0; i < pa.size(); ++i) {
    EXPECT_EQ(pa[i].avar, pb[i].avar);
  }
}

TEST(OnlineAdev, SnapshotRespectsCapacity) {
  const auto y = white_plus_walk(10000, 10);
  Adev a;
  a.push_block(y.data(), y.size());
  imu::AdevPoint pts[3];
  EXPECT_EQ(a.snapshot(pts, 3), 3U);
  EXPECT_EQ(pts[2].af, 3U);
  EXPECT_EQ(a.snapshot(pts, 0), 0U);
}

TEST(OnlineAdev, StateIsSmallAndFixed) {
  // Budget: at most 6 KiB per channel for L = 24, M = 8.
  EXPECT_LE(sizeof(imu::OnlineAdev<8, 24>), 6U * 1024U);
  // Six channels plus push_frame's buffer of kAdevFrameBufferDefault frames and its count.
  constexpr std::size_t kBuffer = imu::kAdevFrameBufferDefault * 6 * 4 + 8;
  EXPECT_EQ(sizeof(imu::MultiAdev<6, 8, 22>), 6 * sizeof(imu::OnlineAdev<8, 22>) + kBuffer);
}

std::uint64_t bits_of(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// Every field of every tau, bit for bit.
template <typename Estimator>
void expect_identical(const Estimator& a, const Estimator& b) {
  EXPECT_EQ(a.samples(), b.samples());
  EXPECT_EQ(a.missing_samples(), b.missing_samples());
  EXPECT_EQ(a.gaps(), b.gaps());
  const auto pa = snap(a);
  const auto pb = snap(b);
  ASSERT_EQ(pa.size(), pb.size());
  for (std::size_t i = 0; i < pa.size(); ++i) {
    SCOPED_TRACE(pa[i].af);
    EXPECT_EQ(pa[i].af, pb[i].af);
    EXPECT_EQ(pa[i].n_terms, pb[i].n_terms);
    EXPECT_EQ(bits_of(pa[i].avar), bits_of(pb[i].avar));
    EXPECT_EQ(bits_of(pa[i].edf), bits_of(pb[i].edf));
    EXPECT_EQ(bits_of(pa[i].ci_lo), bits_of(pb[i].ci_lo));
    EXPECT_EQ(bits_of(pa[i].ci_hi), bits_of(pb[i].ci_hi));
  }
}

// MultiAdev::push_frame (buffered, channels summed together) against six independent channels
// fed one sample at a time with push(): bit-identical, with gaps of random lengths at random
// places, snapshots in between (which flush a partial buffer), more than 2^16 samples (block
// sums closed inside a batch), small and full-scale samples, and one channel pushed on its own
// (the fallback for channels out of step). kBuf: the push_frame buffer (frames per batch); kCh
// channels (their number mod 4 picks how push_frames lays them in vectors); M taus per level.
template <std::size_t kBuf, std::size_t kCh = 6, std::size_t M = 8>
void check_push_frame_against_push(std::size_t n_frames) {
  imu::MultiAdev<kCh, M, 22, kBuf> multi;
  imu::OnlineAdev<M, 22> ref[kCh];
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<std::int32_t> small(-3000, 3000);
  std::uniform_int_distribution<std::int32_t> full(std::numeric_limits<std::int32_t>::min(),
                                                   std::numeric_limits<std::int32_t>::max());
  std::uniform_int_distribution<int> event(0, 19999);
  std::int32_t frame[kCh];
  for (std::size_t f = 0; f < n_frames; ++f) {
    const bool big = f >= n_frames / 2U && f < n_frames / 2U + 10000U;
    for (std::size_t c = 0; c < kCh; ++c) {
      frame[c] = big ? full(rng) : small(rng) + static_cast<std::int32_t>(100 * c);
      ref[c].push(frame[c]);
    }
    multi.push_frame(frame);
    const int e = event(rng);
    if (e < 3) {  // a gap of 1 .. ~5000 samples
      const std::uint64_t n = 1U + rng() % (e == 0 ? 5000U : 7U);
      multi.mark_missing(n);
      for (auto& r : ref) {
        r.mark_missing(n);
      }
    } else if (e == 3) {
      expect_identical(multi.channel(f % kCh), ref[f % kCh]);  // flushes a partial buffer
    }
    if (f == n_frames * 2U / 3U) {  // one channel alone gets an extra sample: out of step
      multi.channel(kCh / 2).push(17);
      ref[kCh / 2].push(17);
    }
  }
  for (std::size_t c = 0; c < kCh; ++c) {
    SCOPED_TRACE(c);
    expect_identical(multi.channel(c), ref[c]);
  }
}

TEST(MultiAdev, PushFrameIsBitIdenticalToPerChannelPush) {
  check_push_frame_against_push<imu::OnlineAdev<8, 22>::kFrames>(300000U);
}

TEST(MultiAdev, PushFrameWithSmallBuffersIsBitIdenticalToo) {
  check_push_frame_against_push<7>(80000U);  // batches of 7: levels 0 and 1 batched
  check_push_frame_against_push<1>(20000U);  // no batching: every frame by push_point
  check_push_frame_against_push<64>(80000U);  // the 32-bit targets' default
}

// Every channel count mod 4 (2 and 6 share a vector between two taus' last two channels; 1, 3,
// 5, 7 and 9 read past the row; 4 and 8 fill their vectors), and M = 6, whose upper levels have
// an odd number of taus (3: the last one shares a vector with itself).
TEST(MultiAdev, PushFrameIsBitIdenticalForAnyChannelCountAndM) {
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 1>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 2>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 3>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 4>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 5>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 7>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 8>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 9>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 10>(40000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 6, 6>(80000U);
  check_push_frame_against_push<imu::kAdevFrameBufferDefault, 2, 6>(40000U);
}

// The CPU-selected kernel (AVX2 + FMA on most x86-64 machines) against the baseline-ISA one: the
// same doubles, bit for bit, for push_block (single channel) and push_frames, with full-scale
// samples and gaps. On a CPU without AVX2 + FMA both calls take the portable path (printed).
TEST(OnlineAdev, DispatchedKernelIsBitIdenticalToPortable) {
  std::printf("kernel path on this CPU: %s\n", Adev::kernel_isa());
  std::mt19937_64 rng(77);
  std::uniform_int_distribution<std::int32_t> full(std::numeric_limits<std::int32_t>::min(),
                                                   std::numeric_limits<std::int32_t>::max());
  std::uniform_int_distribution<std::int32_t> small(-5000, 5000);
  std::vector<std::int32_t> y(400000);
  for (std::size_t i = 0; i < y.size(); ++i) {
    y[i] = (i / 50000) % 3 == 1 ? full(rng) : small(rng);
  }
  Adev fast;
  Adev portable;
  for (std::size_t i = 0; i < y.size();) {
    const std::size_t n = std::min<std::size_t>(1 + rng() % 3000, y.size() - i);
    fast.push_block(y.data() + i, n);
    portable.push_block_portable(y.data() + i, n);
    i += n;
    if (rng() % 8 == 0) {
      const std::uint64_t gap = 1 + rng() % 40;
      fast.mark_missing(gap);
      portable.mark_missing(gap);
    }
  }
  expect_identical(fast, portable);

  constexpr std::size_t kCh = 6;
  constexpr std::size_t kF = Adev::kFrames;
  Adev ch_fast[kCh];
  Adev ch_portable[kCh];
  std::int32_t frames[kF][kCh];
  for (std::size_t done = 0; done < 200000;) {
    const std::size_t n = 1 + rng() % kF;
    for (std::size_t f = 0; f < n; ++f) {
      for (auto& v : frames[f]) {
        v = done > 100000 && done < 120000 ? full(rng) : small(rng);
      }
    }
    Adev::push_frames(ch_fast, frames, n);
    Adev::push_frames_portable(ch_portable, frames, n);
    done += n;
  }
  for (std::size_t c = 0; c < kCh; ++c) {
    SCOPED_TRACE(c);
    expect_identical(ch_fast[c], ch_portable[c]);
  }
}

TEST(Quantize, RoundsAndSaturates) {
  EXPECT_EQ(imu::quantize(0.0333, 0.0333).counts, 1);
  EXPECT_EQ(imu::quantize(-2.5, 1.0).counts, -3);
  EXPECT_EQ(imu::quantize(2.49, 1.0).counts, 2);
  EXPECT_FALSE(imu::quantize(2.49, 1.0).saturated);
  EXPECT_TRUE(imu::quantize(1e12, 1.0).saturated);
  EXPECT_EQ(imu::quantize(1e12, 1.0).counts, std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(imu::quantize(-1e12, 1.0).counts, std::numeric_limits<std::int32_t>::min());
  EXPECT_TRUE(imu::quantize(std::nan(""), 1.0).saturated);
}

}  // namespace

namespace {

__extension__ using UInt128 = unsigned __int128;

UInt128 as_u128(std::uint64_t lo, std::uint64_t hi) { return (UInt128{hi} << 64U) | lo; }

// Exact sum of squared second differences at averaging factor af, stride `stride`, no gaps:
// phases in __int128, squares and sum in unsigned __int128 (the reference for the estimator's
// 128-bit accumulator, computed independently of it).
UInt128 exact_sum(const std::vector<std::int32_t>& y, std::uint64_t af, std::uint64_t stride,
                  std::uint64_t& terms) {
  std::vector<Int128> x(y.size() + 1, 0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    x[i + 1] = x[i] + y[i];
  }
  UInt128 sum = 0;
  terms = 0;
  for (std::size_t k = 0; k + 2 * af <= y.size(); k += stride) {
    const Int128 d = x[k + 2 * af] - 2 * x[k + af] + x[k];
    const UInt128 u = d < 0 ? static_cast<UInt128>(-d) : static_cast<UInt128>(d);
    sum += u * u;
    ++terms;
  }
  return sum;
}

}  // namespace

TEST(ExactSquareSum, AddSquareMatchesInt128ArithmeticOverTheWholeInt64Range) {
  std::mt19937_64 rng(41);
  std::uint64_t lo = 0;
  std::uint64_t hi = 0;
  UInt128 ref = 0;
  int restarts = 0;
  const std::int64_t edges[] = {0,
                                1,
                                -1,
                                0xFFFFFFFFLL,
                                -0xFFFFFFFFLL,
                                0x100000000LL,
                                -0x100000000LL,
                                std::numeric_limits<std::int64_t>::max(),
                                std::numeric_limits<std::int64_t>::min()};
  for (int i = 0; i < 200000; ++i) {
    std::int64_t d = 0;
    if (i < 9) {
      d = edges[i];
    } else {
      // Magnitudes from 2^0 to 2^63: both multiply paths, carries into the high word.
      const auto bits = static_cast<unsigned>(rng() % 64U);
      d = static_cast<std::int64_t>(rng() >> (63U - bits)) * ((rng() & 1U) != 0U ? -1 : 1);
    }
    const UInt128 u = d < 0 ? UInt128{0} - static_cast<UInt128>(static_cast<Int128>(d))
                            : static_cast<UInt128>(d);
    const UInt128 sq = u * u;
    if (ref + sq < ref) {  // would pass 2^128 (tested below): start again from 0
      ref = 0;
      lo = 0;
      hi = 0;
      ++restarts;
    }
    ref += sq;
    ASSERT_TRUE(imu::add_square_u128(lo, hi, d)) << "i " << i;
    ASSERT_TRUE(as_u128(lo, hi) == ref) << "i " << i << " d " << d;
  }
  EXPECT_GT(restarts, 100);  // sums up to near 2^128 many times over
}

// The 32-bit multiply form the Cortex-M4 runs (the host build uses unsigned __int128).
TEST(ExactSquareSum, PortableSquareMatchesInt128) {
  std::mt19937_64 rng(53);
  for (int i = 0; i < 300000; ++i) {
    const auto bits = static_cast<unsigned>(rng() % 64U);
    std::uint64_t u = rng() >> (63U - bits);  // 0 .. 2^(bits+1) - 1, up to 2^64 - 1
    u = u > (1ULL << 63U) ? (1ULL << 63U) : u;  // |d| <= 2^63
    if (i < 4) {
      const std::uint64_t edges[] = {0xFFFFFFFFULL, 0x100000000ULL, 1ULL << 63U, 0};
      u = edges[i];
    }
    std::uint64_t lo = 0;
    std::uint64_t hi = 0;
    imu::square_u64_portable(u, lo, hi);
    const UInt128 ref = static_cast<UInt128>(u) * u;
    ASSERT_TRUE(as_u128(lo, hi) == ref) << "u " << u;
  }
}

// The 32-bit-core form of the 128-bit accumulation (the host build uses unsigned __int128):
// the same sums and return values, around the 2^31 boundary of its fast path, with carries into
// the high word and at the saturation limit.
TEST(ExactSquareSum, PortableAddMatchesInt128Add) {
  std::mt19937_64 rng(59);
  const std::int64_t two31 = std::int64_t{1} << 31U;
  const std::int64_t edges[] = {two31 - 1, two31, -two31, -two31 - 1, 0, -1,
                                std::numeric_limits<std::int64_t>::min(),
                                std::numeric_limits<std::int64_t>::max()};
  for (int i = 0; i < 300000; ++i) {
    std::int64_t d = 0;
    if (i < 64) {
      d = edges[static_cast<std::size_t>(i) % 8U];
    } else {
      const auto bits = static_cast<unsigned>(rng() % 64U);
      d = static_cast<std::int64_t>(rng() >> (63U - bits)) * ((rng() & 1U) != 0U ? -1 : 1);
    }
    // Start below a carry into hi, or below the limit, or anywhere.
    const std::uint64_t starts_lo[] = {~0ULL - (rng() % 1000U), rng(), ~0ULL - (rng() % 1000U)};
    const std::uint64_t starts_hi[] = {rng() % 4U, rng(), ~0ULL};
    const std::size_t s = static_cast<std::size_t>(i) % 3U;
    std::uint64_t lo_a = starts_lo[s];
    std::uint64_t hi_a = starts_hi[s];
    std::uint64_t lo_b = lo_a;
    std::uint64_t hi_b = hi_a;
    const bool ok_a = imu::add_square_u128(lo_a, hi_a, d);
    const bool ok_b = imu::add_square_u128_portable(lo_b, hi_b, d);
    ASSERT_EQ(ok_a, ok_b) << "i " << i << " d " << d;
    ASSERT_EQ(lo_a, lo_b) << "i " << i << " d " << d;
    ASSERT_EQ(hi_a, hi_b) << "i " << i << " d " << d;
  }
  // A carry that fits, and one that does not.
  std::uint64_t lo = ~0ULL;
  std::uint64_t hi = 5;
  ASSERT_TRUE(imu::add_square_u128_portable(lo, hi, 1));
  EXPECT_EQ(lo, 0U);
  EXPECT_EQ(hi, 6U);
  lo = ~0ULL - 4U;
  hi = ~0ULL;
  ASSERT_TRUE(imu::add_square_u128_portable(lo, hi, 2));  // 2^128 - 1
  EXPECT_FALSE(imu::add_square_u128_portable(lo, hi, 1));
  EXPECT_EQ(lo, ~0ULL);
  EXPECT_EQ(hi, ~0ULL);
}

TEST(ExactSquareSum, SaturatesAt2To128) {
  std::uint64_t lo = 0;
  std::uint64_t hi = 0;
  const std::int64_t min = std::numeric_limits<std::int64_t>::min();  // |d| = 2^63, d^2 = 2^126
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(imu::add_square_u128(lo, hi, min));
  }
  EXPECT_EQ(hi, 3ULL << 62U);  // 3 x 2^126, exact
  EXPECT_EQ(lo, 0U);
  EXPECT_EQ(imu::u128_to_double(lo, hi), std::ldexp(3.0, 126));
  ASSERT_TRUE(imu::add_square_u128(lo, hi, -3));  // 3 x 2^126 + 9
  EXPECT_EQ(lo, 9U);
  EXPECT_FALSE(imu::add_square_u128(lo, hi, min));  // 2^128 + 9: saturated
  EXPECT_EQ(hi, ~0ULL);
  EXPECT_EQ(lo, ~0ULL);
  // One below the limit, then one more.
  lo = ~0ULL - 4U;
  hi = ~0ULL;
  ASSERT_TRUE(imu::add_square_u128(lo, hi, 2));  // 2^128 - 1
  EXPECT_EQ(lo, ~0ULL);
  EXPECT_FALSE(imu::add_square_u128(lo, hi, 1));
}

TEST(ExactSquareSum, ConversionToDoubleIsCorrectlyRounded) {
  std::mt19937_64 rng(43);
  std::vector<UInt128> values;
  // Ties between two doubles (54 significant bits ending in 1, nothing below): to even; the
  // same with one more bit far below (the sticky bit): up.
  for (unsigned s = 0; s <= 74; s += 2) {
    const UInt128 tie = ((UInt128{1} << 53U) + 1U) << s;
    values.push_back(tie);
    values.push_back(((UInt128{1} << 53U) + 3U) << s);
    if (s > 0) {
      values.push_back(tie + 1U);
    }
  }
  for (int i = 0; i < 100000; ++i) {
    const auto bits = static_cast<unsigned>(rng() % 128U);
    const UInt128 v = as_u128(rng(), rng()) >> (127U - bits);
    values.push_back(v);
  }
  for (const UInt128 v : values) {
    const auto lo = static_cast<std::uint64_t>(v);
    const auto hi = static_cast<std::uint64_t>(v >> 64U);
    // GCC's and clang's unsigned __int128 -> double conversion rounds to nearest even.
    ASSERT_EQ(imu::u128_to_double(lo, hi), static_cast<double>(v))
        << "hi " << hi << " lo " << lo;
  }
}

// The estimator's sums are the exact integer sums: its AVAR equals the formula evaluated on
// the exact sum (converted once), bit for bit, on full-scale input whose level-0 sums exceed
// 2^64 (|d| up to 2^33, 2^20 terms) and whose upper-level terms exceed 2^32 (the three-multiply
// path), fed through push_block and push.
TEST(ExactSquareSum, EstimatorSumsAreExactOnFullScaleLongRecords) {
  std::mt19937 rng(47);
  std::vector<std::int32_t> y(1U << 20U);
  for (std::size_t i = 0; i < y.size(); ++i) {
    // Full-scale random values with a slow square wave of +-2^30 (large upper-level terms).
    const std::int32_t wave = ((i >> 12U) & 1U) != 0U ? (1 << 30) : -(1 << 30);
    y[i] = static_cast<std::int32_t>(rng()) / 2 + wave;
  }
  Adev a(0.01, 0.25);
  a.push_block(y.data(), y.size());
  Adev b(0.01, 0.25);
  for (const std::int32_t v : y) {
    b.push(v);
  }
  const auto pa = snap(a);
  const auto pb = snap(b);
  ASSERT_EQ(pa.size(), pb.size());
  ASSERT_GT(pa.size(), 60U);
  bool above_2_64 = false;
  for (std::size_t i = 0; i < pa.size(); ++i) {
    const auto& p = pa[i];
    std::uint64_t terms = 0;
    const UInt128 sum = exact_sum(y, p.af, p.stride, terms);
    above_2_64 = above_2_64 || (sum >> 64U) != 0;
    ASSERT_EQ(p.n_terms, terms) << "af " << p.af;
    const auto af = static_cast<double>(p.af);
    const double expect = 0.25 * 0.25 * static_cast<double>(sum) /
                          (2.0 * af * af * static_cast<double>(terms));
    EXPECT_EQ(p.avar, expect) << "af " << p.af;
    std::uint64_t bits_a = 0;
    std::uint64_t bits_b = 0;
    std::memcpy(&bits_a, &p.avar, sizeof bits_a);
    std::memcpy(&bits_b, &pb[i].avar, sizeof bits_b);
    EXPECT_EQ(bits_a, bits_b) << "af " << p.af;  // push_block and push: the same bits
  }
  EXPECT_TRUE(above_2_64);
  EXPECT_FALSE(a.overflowed());
}

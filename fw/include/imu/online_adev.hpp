// Streaming, fixed-memory, decimated overlapping Allan deviation.
//
// Input: one integer sample (int32 counts) at a time, or a block, or "missing" marks. The
// physical value of a count is `lsb` (e.g. m/s^2 per count); a floating-point source is
// converted by the caller with imu::quantize() and a stated LSB.
//
// Method (fw/README.md has the details and the proofs of the bounds):
//  * phase x_n = sum of counts, kept as a wrapping uint64: second differences
//    x_p - 2 x_{p-m} + x_{p-2m} are exact whenever their true value fits in int64, so the
//    phase never overflows in a way that matters, even at full-scale int32 input;
//  * level k (k = 0..L) holds the phase decimated by 2^k, i.e. the points x_{j 2^k}, in a ring
//    of the last 2M points (the incoming point is the (2M+1)-th);
//  * level 0 estimates tau = m Ts for m = 1..M, level k >= 1 estimates tau = m 2^k Ts for
//    M/2 < m <= M, from overlapping terms at a stride of 2^k samples (between tau/M and 2tau/M),
//    which gives M/2 taus per octave from Ts to 2^L M Ts;
//  * squared second differences are summed exactly, in integers: each term d (int64) is squared
//    into 128 bits (32 x 32 -> 64-bit multiplies, one when |d| < 2^32) and added to a 128-bit
//    unsigned accumulator per tau (two uint64 words; unsigned __int128 products where the
//    compiler has them, the same values). No rounding at all until a snapshot
//    converts the sum to double (correctly rounded). The sum is exact while it is below 2^128:
//    a level-k term is below 2^(2 (k + 35)) (|counts| <= 2^31, m <= 8; M = 64 adds 6 bits) and
//    the level has n / 2^k terms, so at full-scale input level k holds n < 2^(58 - k) samples
//    (2^36 on every level for L = 22; 2^68 at |counts| <= 2^15); beyond that the sum saturates
//    at 2^128 - 1 (overflowed() says so).
//    Every way of feeding the samples (push, push_block, push_frames, MultiAdev) and every
//    target (host, Cortex-M4 without double-precision hardware) gives the same sums, bit for bit;
//  * term counts are not incremented per sample: they are derived from the number of points in
//    the current gap-free segment plus the terms of closed segments;
//  * a missing sample breaks the phase: every level closes its segment, and terms that would
//    span the gap are never formed. A level-k tau m recovers after 2m new level-k points, i.e.
//    2 tau of clean data. Nothing already accumulated is lost or biased.
//
// Cost: push() is O(M) at level 0 plus O(M/2) at level k with probability 2^-k: amortised
// O(1.5 M) integer multiply-adds per sample, constant in the record length, no floating point.
// snapshot() is O(number of taus * M) (double, EDF) and does not disturb ingestion. No heap, no
// exceptions, not re-entrant on one instance (one instance per channel; different instances are
// independent).
#ifndef IMU_ONLINE_ADEV_HPP
#define IMU_ONLINE_ADEV_HPP

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "imu/edf.hpp"

namespace imu {

/// One estimated tau. Units: `adev`, `ci_lo`, `ci_hi` in the channel's physical units
/// (lsb units), `avar` in their square.
struct AdevPoint {
  double tau_s;
  std::uint32_t af;      ///< averaging factor: tau / Ts
  std::uint32_t stride;  ///< samples between successive terms (2^level)
  std::uint64_t n_terms; ///< number of squared second differences in the sum
  double avar;
  double adev;
  double edf;    ///< Greenhall-Riley EDF for the partially overlapping estimate
  double ci_lo;  ///< 68.3 % interval (chi-square with `edf` degrees of freedom)
  double ci_hi;
};

/// Result of converting a floating-point sample to counts.
struct QuantizeResult {
  std::int32_t counts;
  bool saturated;  ///< the value did not fit in int32 (or was NaN): counts is clamped (NaN -> 0)
};

/// Round value / lsb_units to the nearest integer count (ties away from zero), saturating.
[[nodiscard]] inline QuantizeResult quantize(double value, double lsb_units) {
  const double c = value / lsb_units;
  if (std::isnan(c)) {
    return QuantizeResult{0, true};
  }
  constexpr double kMax = 2147483647.0;
  constexpr double kMin = -2147483648.0;
  const double r = c < 0.0 ? -std::floor(-c + 0.5) : std::floor(c + 0.5);
  if (r > kMax) {
    return QuantizeResult{2147483647, true};
  }
  if (r < kMin) {
    return QuantizeResult{-2147483647 - 1, true};
  }
  return QuantizeResult{static_cast<std::int32_t>(r), false};
}

/// u^2 as 128 bits (sq_hi, sq_lo) in 32 x 32 -> 64-bit multiplies: one when u < 2^32, three
/// otherwise. u <= 2^63.
inline void square_u64_portable(std::uint64_t u, std::uint64_t& sq_lo, std::uint64_t& sq_hi) {
  if ((u >> 32U) == 0) {
    sq_lo = u * u;
    sq_hi = 0;
    return;
  }
  // u = a 2^32 + b: u^2 = a^2 2^64 + 2 a b 2^32 + b^2, with a <= 2^31 (so 2ab < 2^64).
  const std::uint64_t a = u >> 32U;
  const std::uint64_t b = u & 0xFFFFFFFFU;
  const std::uint64_t ab2 = 2U * (a * b);
  const std::uint64_t bb = b * b;
  sq_lo = bb + (ab2 << 32U);
  sq_hi = a * a + (ab2 >> 32U) + (sq_lo < bb ? 1U : 0U);
}

/// u^2 as 128 bits: square_u64_portable, or one 64 x 64 -> 128-bit multiply where the compiler
/// has unsigned __int128 (64-bit hosts). The same value either way.
inline void square_u64(std::uint64_t u, std::uint64_t& sq_lo, std::uint64_t& sq_hi) {
#if defined(__SIZEOF_INT128__)
  __extension__ using U128 = unsigned __int128;
  const U128 sq = static_cast<U128>(u) * u;
  sq_lo = static_cast<std::uint64_t>(sq);
  sq_hi = static_cast<std::uint64_t>(sq >> 64U);
#else
  square_u64_portable(u, sq_lo, sq_hi);
#endif
}

/// |d| as unsigned, exact for every d (2^63 for INT64_MIN).
inline std::uint64_t magnitude_u64(std::int64_t d) {
  return d < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(d) : static_cast<std::uint64_t>(d);
}

/// (hi, lo) += u^2, u <= 2^63, the general case of add_square_u128 (any u; saturating).
inline bool add_square_u128_wide(std::uint64_t& lo, std::uint64_t& hi, std::uint64_t u) {
  std::uint64_t sq_lo = 0;
  std::uint64_t sq_hi = 0;
  square_u64(u, sq_lo, sq_hi);
  lo += sq_lo;
  const std::uint64_t add = sq_hi + (lo < sq_lo ? 1U : 0U);  // sq_hi <= 2^62: no wrap
  if (add == 0) {
    return true;
  }
  hi += add;
  if (hi < add) {
    hi = ~std::uint64_t{0};
    lo = ~std::uint64_t{0};
    return false;
  }
  return true;
}

/// add_square_u128 in the form for cores without a 64 x 64 -> 128-bit multiply (the
/// Cortex-M4): the usual term, |d| < 2^31, is one signed 32 x 32 -> 64-bit multiply(-accumulate)
/// and a 64-bit add, the high word touched only on a carry; larger terms take the wide path.
/// The same sums and return value as the other form (test_online_adev compares them).
[[gnu::always_inline]] inline bool add_square_u128_portable(std::uint64_t& lo, std::uint64_t& hi,
                                                            std::int64_t d) {
  const auto d32 = static_cast<std::int32_t>(d);
  if (d32 != d) {
    return add_square_u128_wide(lo, hi, magnitude_u64(d));
  }
  const auto sq = static_cast<std::uint64_t>(static_cast<std::int64_t>(d32) * d32);  // < 2^62
  lo += sq;
  if (lo >= sq || ++hi != 0) {  // no carry, or the carry fits in the high word
    return true;
  }
  hi = ~std::uint64_t{0};  // hi wrapped: the sum passed 2^128 - 1
  lo = ~std::uint64_t{0};
  return false;
}

/// (hi, lo) += d^2 as one 128-bit unsigned integer, exactly: no floating point, the same bits
/// on every target. Saturates at 2^128 - 1 and returns false when the sum would exceed it.
/// Where the compiler has unsigned __int128 (64-bit hosts) one branch-free 128-bit multiply;
/// elsewhere add_square_u128_portable (a branch on the term's size, cheaper on a 32-bit core,
/// dearer on a host fed terms of random size).
[[gnu::always_inline]] inline bool add_square_u128(std::uint64_t& lo, std::uint64_t& hi,
                                                   std::int64_t d) {
#if defined(__SIZEOF_INT128__)
  return add_square_u128_wide(lo, hi, magnitude_u64(d));
#else
  return add_square_u128_portable(lo, hi, d);
#endif
}

/// The 128-bit unsigned (hi, lo) as the nearest double (ties to even): the top 64 significant
/// bits with a sticky bit for the rest, converted once, then scaled by a power of two (exact).
inline double u128_to_double(std::uint64_t lo, std::uint64_t hi) {
  if (hi == 0) {
    return static_cast<double>(lo);
  }
  const int shift = 64 - __builtin_clzll(hi);  // significant bits of hi: 1..64
  const std::uint64_t top = shift == 64 ? hi : (hi << (64 - shift)) | (lo >> shift);
  const std::uint64_t rest = shift == 64 ? lo : lo << (64 - shift);
  return std::ldexp(static_cast<double>(top | (rest != 0 ? 1U : 0U)), shift);
}

/// Online overlapping ADEV of one channel. M (taus per level, even) and L (decimation levels
/// above level 0) fix the memory: sizeof() is the whole state, nothing else is allocated.
template <std::size_t M = 8, std::size_t L = 22>
class OnlineAdev {
  static_assert(M >= 2 && M % 2 == 0 && M <= 64, "M must be even, 2..64");
  static_assert(L >= 1 && L <= 40, "L must be 1..40 (tau up to 2^L M Ts)");

 public:
  static constexpr std::size_t kLevels = L + 1;
  static constexpr std::size_t kRing = 2 * M;
  static constexpr std::size_t kUpperTaus = M / 2;
  /// Number of distinct taus this estimator can report.
  static constexpr std::size_t kMaxPoints = M + L * kUpperTaus;
  static constexpr std::size_t kBatch = 256;   // samples per push_block call that callers use
  static constexpr std::size_t kFrames = 256;  // frames per push_frames call, at most

  /// sample_period_s: Ts (> 0); lsb: physical value of one count (> 0).
  explicit OnlineAdev(double sample_period_s = 0.01, double lsb = 1.0)
      : sample_period_s_(sample_period_s), lsb_(lsb) {
    reset();
  }

  /// Forget every sample; keeps Ts and LSB. O(L M).
  void reset() {
    n_ = 0;
    x_ = 0;
    missing_ = 0;
    gaps_ = 0;
    overflowed_ = false;
    level0_ = Level<M, 0>{};
    for (auto& lv : upper_) {
      lv = Level<kUpperTaus, M / 2>{};
    }
    // x_0 = 0 is the first point of every level.
    level0_.seg_points = 1;
    for (auto& lv : upper_) {
      lv.seg_points = 1;
    }
  }

  /// Push one sample (counts). Amortised O(1), constant time apart from the cascade.
  void push(std::int32_t counts) {
    x_ += static_cast<std::uint64_t>(static_cast<std::int64_t>(counts));
    ++n_;
    cascade();
  }

  /// Push n samples: n calls of push() (the sums are exact, so any grouping gives the same).
  void push_block(const std::int32_t* counts, std::size_t n) {
    for (std::size_t j = 0; j < n; ++j) {
      push(counts[j]);
    }
  }
  /// The same as push_block() (one code path on every CPU; kept for callers that name it).
  void push_block_portable(const std::int32_t* counts, std::size_t n) { push_block(counts, n); }

  /// Push the first n <= F frames of `frames` (frames[f][c]: sample f of channel c; F <= kFrames)
  /// into the C channels `ch`, frame after frame: the same sums as push() on each channel.
  template <std::size_t C, std::size_t F>
  static void push_frames(OnlineAdev (&ch)[C], const std::int32_t (&frames)[F][C], std::size_t n) {
    static_assert(C >= 1, "at least one channel");
    static_assert(F >= 1 && F <= kFrames, "F must be 1..kFrames");
    for (std::size_t f = 0; f < n && f < F; ++f) {
      for (std::size_t c = 0; c < C; ++c) {
        ch[c].push(frames[f][c]);
      }
    }
  }
  /// The same as push_frames().
  template <std::size_t C, std::size_t F>
  static void push_frames_portable(OnlineAdev (&ch)[C], const std::int32_t (&frames)[F][C],
                                   std::size_t n) {
    push_frames(ch, frames, n);
  }


  /// Mark n_samples consecutive samples as missing (e.g. dropped frames). Time advances, no term
  /// spans the gap. O(L M).
  void mark_missing(std::uint64_t n_samples) {
    if (n_samples == 0) {
      return;
    }
    close_segment(level0_);
    for (auto& lv : upper_) {
      close_segment(lv);
    }
    n_ += n_samples;
    missing_ += n_samples;
    ++gaps_;
    cascade();  // the current phase starts the new segment on every level it falls on
  }

  /// Write up to `capacity` estimated taus (ascending) to `out`; taus without a term are skipped.
  /// noise_alpha selects the power-law noise assumed for the EDF (0 = white FM). Returns the count.
  std::size_t snapshot(AdevPoint* out, std::size_t capacity, int noise_alpha = 0) const {
    std::size_t k = 0;
    if (capacity == 0) {
      return 0;
    }
    for_each_point(
        [&](const AdevPoint& p) {
          out[k++] = p;
          return k < capacity;
        },
        noise_alpha);
    return k;
  }

  /// The points snapshot() would write, one at a time and without a buffer of them: calls
  /// visit(const AdevPoint&) for each tau with a term, ascending, until visit returns false.
  template <typename Visit>
  void for_each_point(Visit&& visit, int noise_alpha = 0) const {
    AdevPoint p{};
    for_each_tau([&](const auto& lv, std::size_t i, std::size_t m, std::size_t level) {
      return !make_point(lv, i, m, level, noise_alpha, p) || visit(p);
    });
  }

  /// Number of points snapshot() would write with unlimited capacity (no EDF or interval
  /// computed). O(number of taus).
  [[nodiscard]] std::size_t point_count() const {
    std::size_t k = 0;
    for_each_tau([&](const auto& lv, std::size_t i, std::size_t m, std::size_t /*level*/) {
      k += lv_terms(lv, i, m) > 0 ? 1U : 0U;
      return true;
    });
    return k;
  }

  /// Change Ts and LSB (takes effect on the next snapshot; the sums are in counts).
  void configure(double sample_period_s, double lsb) {
    sample_period_s_ = sample_period_s;
    lsb_ = lsb;
  }

  /// The code path push_block() and push_frames() take: "portable" on every CPU (exact integer
  /// sums, no vector or floating-point kernel).
  static const char* kernel_isa() { return "portable"; }
  /// Some tau's sum reached 2^128 and saturated (see the file comment): its ADEV is a lower bound.
  [[nodiscard]] bool overflowed() const { return overflowed_; }

  [[nodiscard]] std::uint64_t samples() const { return n_; }          ///< including missing
  [[nodiscard]] std::uint64_t missing_samples() const { return missing_; }
  [[nodiscard]] std::uint64_t gaps() const { return gaps_; }
  [[nodiscard]] double sample_period_s() const { return sample_period_s_; }
  [[nodiscard]] double lsb() const { return lsb_; }

 private:
  // kMLo: the level's taus are m = kMLo + 1 .. kMLo + kTaus.
  template <std::size_t kTaus, std::size_t kMLo>
  struct Level {
    std::uint64_t ring[kRing] = {};       // wrapping phase points, slot = point index % kRing
    std::uint64_t sum_lo[kTaus] = {};     // exact sum of squared terms, low 64 bits
    std::uint64_t sum_hi[kTaus] = {};     // and high 64 bits
    std::uint64_t terms_done[kTaus] = {}; // terms of closed segments
    std::uint64_t seg_points = 0;         // points in the current gap-free segment
  };

  template <std::size_t kTaus, std::size_t kMLo>
  void push_point(Level<kTaus, kMLo>& lv, std::uint64_t p, std::uint64_t x) {
    // Taus are in increasing m, so the ones with their three points in the current segment
    // (2m <= points before this one, m <= seg_points / 2) are the first `ready`.
    const std::uint64_t half = lv.seg_points / 2;
    const std::size_t ready =
        half <= kMLo ? 0 : (half - kMLo >= kTaus ? kTaus : static_cast<std::size_t>(half - kMLo));
    const auto slot = static_cast<std::size_t>(p % kRing);  // 2m <= kRing: no index wraps below 0
    for (std::size_t i = 0; i < ready; ++i) {
      const std::size_t m = kMLo + 1 + i;
      const std::uint64_t a = lv.ring[(slot + kRing - m) % kRing];
      const std::uint64_t b = lv.ring[(slot + kRing - 2 * m) % kRing];
      if (!add_square_u128(lv.sum_lo[i], lv.sum_hi[i], static_cast<std::int64_t>(x - 2 * a + b))) {
        overflowed_ = true;
      }
    }
    lv.ring[slot] = x;
    ++lv.seg_points;
  }


  template <std::size_t kTaus, std::size_t kMLo>
  static void close_segment(Level<kTaus, kMLo>& lv) {
    for (std::size_t i = 0; i < kTaus; ++i) {
      lv.terms_done[i] += open_terms(lv, kMLo + 1 + i);
    }
    lv.seg_points = 0;
  }

  template <std::size_t kTaus, std::size_t kMLo>
  static std::uint64_t open_terms(const Level<kTaus, kMLo>& lv, std::size_t m) {
    return lv.seg_points > 2 * m ? lv.seg_points - 2 * m : 0;
  }

  // Push the current phase to every level whose grid contains sample index n_.
  void cascade() {
    push_point(level0_, n_, x_);
    const std::uint64_t n = n_;
    if (n == 0) {
      return;
    }
    // Trailing zeros of n in 32-bit halves (a 64-bit count is a library call on 32-bit cores).
    const auto n_lo = static_cast<std::uint32_t>(n);
    const auto tz = static_cast<std::size_t>(
        n_lo != 0 ? __builtin_ctz(n_lo) : 32 + __builtin_ctz(static_cast<std::uint32_t>(n >> 32U)));
    const std::size_t top = tz < L ? tz : L;
    for (std::size_t k = 1; k <= top; ++k) {
      push_point(upper_[k - 1], n >> k, x_);
    }
  }

  // Every tau in ascending order as (level, index in it, m, octave), until fn returns false.
  template <typename Fn>
  void for_each_tau(Fn&& fn) const {
    for (std::size_t i = 0; i < M; ++i) {
      if (!fn(level0_, i, i + 1, std::size_t{0})) {
        return;
      }
    }
    for (std::size_t lv = 0; lv < L; ++lv) {
      for (std::size_t i = 0; i < kUpperTaus; ++i) {
        if (!fn(upper_[lv], i, M / 2 + 1 + i, lv + 1)) {
          return;
        }
      }
    }
  }

  template <std::size_t kTaus, std::size_t kMLo>
  std::uint64_t lv_terms(const Level<kTaus, kMLo>& lv, std::size_t i, std::size_t m) const {
    return lv.terms_done[i] + open_terms(lv, m);
  }

  template <std::size_t kTaus, std::size_t kMLo>
  bool make_point(const Level<kTaus, kMLo>& lv, std::size_t i, std::size_t m, std::size_t level,
                  int noise_alpha, AdevPoint& out) const {
    const std::uint64_t terms = lv_terms(lv, i, m);
    if (terms == 0) {
      return false;
    }
    const std::uint64_t stride = std::uint64_t{1} << level;
    const double af = static_cast<double>(m) * static_cast<double>(stride);
    const double sum = u128_to_double(lv.sum_lo[i], lv.sum_hi[i]);
    const double n_terms = static_cast<double>(terms);
    out.tau_s = af * sample_period_s_;
    out.af = static_cast<std::uint32_t>(m * stride);
    out.stride = static_cast<std::uint32_t>(stride);
    out.n_terms = terms;
    out.avar = lsb_ * lsb_ * sum / (2.0 * af * af * n_terms);
    out.adev = std::sqrt(out.avar);
    out.edf = edf_greenhall(noise_alpha, 2, af, static_cast<double>(m), n_terms);
    const DevInterval ci = deviation_interval(out.adev, out.edf);
    out.ci_lo = ci.lo;
    out.ci_hi = ci.hi;
    return true;
  }

  double sample_period_s_;
  double lsb_;
  std::uint64_t n_ = 0;        // samples so far, missing ones included (= index of newest point)
  std::uint64_t x_ = 0;        // wrapping phase in counts
  std::uint64_t missing_ = 0;
  std::uint64_t gaps_ = 0;
  bool overflowed_ = false;
  Level<M, 0> level0_;
  Level<kUpperTaus, M / 2> upper_[L];
};

/// Frames MultiAdev buffers by default: 1, i.e. none. The sums are exact, so a batch computes
/// the same as frame-by-frame pushes and saves nothing; a buffer would only cost RAM.
inline constexpr std::size_t kAdevFrameBufferDefault = 1;

/// The online ADEV of every channel of an IMU (6 by default), one estimator per channel.
/// push_frame() feeds it one frame at a time: it buffers kFrameBuffer frames (kChannels x 4 x
/// kFrameBuffer bytes; at most Channel::kFrames; default 1, no buffering) and pushes them through
/// OnlineAdev::push_frames, with results bit-identical to push(). Buffered frames are pushed before anything reads or changes the channels: channel()
/// (also the const one: the buffer and channels are `mutable`, the estimate is logically
/// unchanged), push(), mark_missing(), reset(), flush().
template <std::size_t kChannels = 6, std::size_t M = 8, std::size_t L = 22,
          std::size_t kFrameBuffer = kAdevFrameBufferDefault>
class MultiAdev {
 public:
  using Channel = OnlineAdev<M, L>;
  static constexpr std::size_t kNumChannels = kChannels;
  static_assert(kFrameBuffer >= 1 && kFrameBuffer <= Channel::kFrames,
                "kFrameBuffer must be 1..OnlineAdev::kFrames");

  /// Push one sample of every channel, now, channel by channel. Same results as push_frame().
  void push(const std::int32_t (&counts)[kChannels]) {
    flush();
    for (std::size_t c = 0; c < kChannels; ++c) {
      ch_[c].push(counts[c]);
    }
  }
  /// Push one sample of every channel, buffered (see the class comment). O(kChannels) per call,
  /// plus one push_frames() every kFrameBuffer calls.
  void push_frame(const std::int32_t (&counts)[kChannels]) {
    if constexpr (kFrameBuffer == 1) {
      for (std::size_t c = 0; c < kChannels; ++c) {
        ch_[c].push(counts[c]);
      }
      return;
    }
    std::memcpy(pending_[n_pending_], counts, sizeof counts);
    if (++n_pending_ == kFrameBuffer) {
      flush();
    }
  }
  /// Push the buffered frames now. O(frames buffered x kChannels).
  void flush() const {
    if (n_pending_ > 0) {
      Channel::push_frames(ch_, pending_, n_pending_);
      n_pending_ = 0;
    }
  }
  /// Mark n consecutive samples missing on every channel.
  void mark_missing(std::uint64_t n_samples) {
    flush();
    for (auto& c : ch_) {
      c.mark_missing(n_samples);
    }
  }
  void reset() {
    n_pending_ = 0;
    for (auto& c : ch_) {
      c.reset();
    }
  }
  Channel& channel(std::size_t c) {
    flush();
    return ch_[c];
  }
  const Channel& channel(std::size_t c) const {
    flush();
    return ch_[c];
  }

 private:
  mutable Channel ch_[kChannels];
  mutable std::int32_t pending_[kFrameBuffer][kChannels] = {};
  mutable std::size_t n_pending_ = 0;
};

}  // namespace imu

#endif  // IMU_ONLINE_ADEV_HPP

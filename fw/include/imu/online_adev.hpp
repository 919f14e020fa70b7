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
//  * squared second differences are summed in double in blocks of 2^16 terms (plain sum inside
//    a block, block sums added to the total): relative rounding error <= (2^16 + n/2^16) u,
//    1.4e-11 for n = 2^32 terms (u = 1.1e-16);
//  * term counts are not incremented per sample: they are derived from the number of points in
//    the current gap-free segment plus the terms of closed segments;
//  * a missing sample breaks the phase: every level closes its segment, and terms that would
//    span the gap are never formed. A level-k tau m recovers after 2m new level-k points, i.e.
//    2 tau of clean data. Nothing already accumulated is lost or biased.
//
// Cost: push() is O(M) at level 0 plus O(M/2) at level k with probability 2^-k: amortised
// O(1.5 M) multiply-adds per sample, constant in the record length. snapshot() is
// O(number of taus * M) and does not disturb ingestion. No heap, no exceptions, not re-entrant
// on one instance (one instance per channel; different instances are independent).
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
  static constexpr std::uint64_t kBlockMask = 0xFFFF;  // block of 2^16 terms per partial sum
  static constexpr std::size_t kBatch = 256;            // samples per push_block batch
  static constexpr std::size_t kFrames = 64;            // frames per push_frames call, at most

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

  /// Push n samples. Same estimate as n calls of push() (sums may differ in the last bits: they
  /// are added in another order). Faster: phases are formed in batches of kBatch samples and each
  /// level's terms are summed over the batch in registers, from phases taken relative to the
  /// batch's oldest point, which are exact in double (|relative phase| < 2^53, see push_batch).
  /// Stack: kBatch doubles here plus 2M + kBatch doubles in push_batch (4.2 kB for M = 8).
  void push_block(const std::int32_t* counts, std::size_t n) {
    double xd[kBatch];  // phases relative to base; the absolute phase is base + xd (exact)
    while (n > 0) {
      const std::size_t b = n < kBatch ? n : kBatch;
      const std::uint64_t base = x_;  // every level's batch array is relative to this phase
      std::int64_t rel = 0;  // |rel| <= kBatch * 2^31 = 2^39: exact as a double
      for (std::size_t j = 0; j < b; ++j) {
        rel += counts[j];
        xd[j] = static_cast<double>(rel);
      }
      x_ = base + static_cast<std::uint64_t>(rel);
      const std::uint64_t first = n_ + 1;  // sample (= point) index of xd[0]
      n_ += b;
      push_batch(level0_, first, xd, base, 1, b);
      for (std::size_t k = 1; k <= L; ++k) {
        // Level-k points are the phases at indices that are multiples of 2^k.
        const std::uint64_t q0 = (first + (std::uint64_t{1} << k) - 1) >> k;
        const std::uint64_t q1 = (first + b - 1) >> k;
        if (q1 < q0) {
          break;  // no multiple of 2^k in the batch, hence none of 2^(k+1) either
        }
        const std::size_t off = static_cast<std::size_t>((q0 << k) - first);
        push_batch(upper_[k - 1], q0, xd + off, base, std::size_t{1} << k,
                   static_cast<std::size_t>(q1 - q0 + 1));
      }
      counts += b;
      n -= b;
    }
  }

  /// Push the first n <= F frames of `frames` (frames[f][c]: sample f of channel c; F <= kFrames)
  /// into the C channels `ch`.
  /// Bit-identical to pushing frame after frame with push() on each channel: every term is formed
  /// exactly (as in push_block) and added to its tau's partial sum in the same order, flushed
  /// into the block total at the same points. Faster: per level, the taus' terms are summed over
  /// the batch with the channels as the inner loop (contiguous, so the compiler vectorises across
  /// channels), once the level's ring is full and the batch has >= 4 of its points; other levels
  /// take push()'s per-point path. Channels whose sample counts differ (pushed separately) or
  /// n > F fall back to push() frame by frame. Cost: ~1.5 M multiply-adds per sample per
  /// channel, as push(). Stack: (2M + 2F) C doubles (6.9 kB for M = 8, F = 64, C = 6): a host /
  /// application-processor path, not for the M4's 4 KiB stack (where doubles are soft-float and
  /// nothing vectorises anyway: use push(), or F = 1).
  template <std::size_t C, std::size_t F>
  static void push_frames(OnlineAdev (&ch)[C], const std::int32_t (&frames)[F][C], std::size_t n) {
    static_assert(C >= 1, "at least one channel");
    static_assert(F >= 1 && F <= kFrames, "F must be 1..kFrames");
    bool same = n <= F;
    for (std::size_t c = 1; c < C; ++c) {
      same = same && ch[c].n_ == ch[0].n_;
    }
    if (!same) {
      for (std::size_t f = 0; f < n; ++f) {
        for (std::size_t c = 0; c < C; ++c) {
          ch[c].push(frames[f][c]);
        }
      }
      return;
    }
    double xs[F * C];  // phase after frame f of channel c, relative to base[c]: exact
    std::uint64_t base[C];
    std::int64_t rel[C];
    for (std::size_t c = 0; c < C; ++c) {
      base[c] = ch[c].x_;
      rel[c] = 0;
    }
    for (std::size_t f = 0; f < n; ++f) {
      for (std::size_t c = 0; c < C; ++c) {
        rel[c] += frames[f][c];  // |rel| <= kFrames 2^31 = 2^37
        xs[f * C + c] = static_cast<double>(rel[c]);
      }
    }
    const std::uint64_t first = ch[0].n_ + 1;  // sample (= point) index of frame 0
    for (std::size_t c = 0; c < C; ++c) {
      ch[c].x_ = base[c] + static_cast<std::uint64_t>(rel[c]);
      ch[c].n_ += n;
    }
    {
      Level<M, 0>* lv[C];
      for (std::size_t c = 0; c < C; ++c) {
        lv[c] = &ch[c].level0_;
      }
      push_frames_level<F>(lv, first, xs, base, 1, n);
    }
    for (std::size_t k = 1; k <= L; ++k) {
      const std::uint64_t q0 = (first + (std::uint64_t{1} << k) - 1) >> k;
      const std::uint64_t q1 = (first + n - 1) >> k;
      if (q1 < q0) {
        break;  // no multiple of 2^k among the frames, hence none of 2^(k+1) either
      }
      Level<kUpperTaus, M / 2>* lv[C];
      for (std::size_t c = 0; c < C; ++c) {
        lv[c] = &ch[c].upper_[k - 1];
      }
      const auto off = static_cast<std::size_t>((q0 << k) - first);
      push_frames_level<F>(lv, q0, xs + off * C, base, std::size_t{1} << k,
                        static_cast<std::size_t>(q1 - q0 + 1));
    }
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
    for (std::size_t i = 0; i < M && k < capacity; ++i) {
      if (make_point(level0_, i, i + 1, 0, noise_alpha, out[k])) {
        ++k;
      }
    }
    for (std::size_t lv = 0; lv < L; ++lv) {
      for (std::size_t i = 0; i < kUpperTaus && k < capacity; ++i) {
        if (make_point(upper_[lv], i, M / 2 + 1 + i, lv + 1, noise_alpha, out[k])) {
          ++k;
        }
      }
    }
    return k;
  }

  /// Change Ts and LSB (takes effect on the next snapshot; the sums are in counts).
  void configure(double sample_period_s, double lsb) {
    sample_period_s_ = sample_period_s;
    lsb_ = lsb;
  }

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
    double total[kTaus] = {};             // sum of closed blocks
    double partial[kTaus] = {};           // sum of the current block (< 2^16 terms)
    std::uint64_t terms_done[kTaus] = {}; // terms of closed segments
    std::uint64_t seg_points = 0;         // points in the current gap-free segment
  };

  using V2 = double __attribute__((vector_size(16)));  // NOLINT: GNU vector extension
  static V2 load2(const double* p) {
    V2 v;
    std::memcpy(&v, p, sizeof v);
    return v;
  }

  template <std::size_t kTaus, std::size_t kMLo>
  static void push_point(Level<kTaus, kMLo>& lv, std::uint64_t p, std::uint64_t x) {
    // Taus are in increasing m, so the ones with their three points in the current segment
    // (2m <= points before this one) are a prefix: stop at the first that is not.
    for (std::size_t i = 0; i < kTaus; ++i) {
      const std::size_t m = kMLo + 1 + i;
      if (lv.seg_points < 2 * m) {
        break;
      }
      const std::uint64_t a = lv.ring[(p - m) % kRing];
      const std::uint64_t b = lv.ring[(p - 2 * m) % kRing];
      const auto d = static_cast<double>(static_cast<std::int64_t>(x - 2 * a + b));
      lv.partial[i] += d * d;
    }
    lv.ring[p % kRing] = x;
    ++lv.seg_points;
    if ((p & kBlockMask) == 0) {
      for (std::size_t i = 0; i < kTaus; ++i) {
        lv.total[i] += lv.partial[i];
        lv.partial[i] = 0.0;
      }
    }
  }

  // x - base as a double, exact for |x - base| < 2^51: adding the bit pattern of 1.5 * 2^52
  // to the integer gives the double 1.5 * 2^52 + (x - base), from which 1.5 * 2^52 is subtracted
  // exactly. Branch-free integer add and one subtraction, so the loops over it vectorise.
  // Inverse of exact_relative: base + rel, exact (rel is an integer below 2^52 in magnitude).
  static std::uint64_t absolute_phase(double rel, std::uint64_t base) {
    return base + static_cast<std::uint64_t>(static_cast<std::int64_t>(rel));
  }
  static double exact_relative(std::uint64_t x, std::uint64_t base) {
    constexpr std::uint64_t kMagicBits = 0x4338000000000000ULL;  // 1.5 * 2^52
    constexpr double kMagic = 6755399441055744.0;
    const std::uint64_t u = (x - base) + kMagicBits;
    double d = 0.0;
    std::memcpy(&d, &u, sizeof d);
    return d - kMagic;
  }

  // Push cnt consecutive points of one level, the first with point index p0; xd are the points
  // (every `stride`-th entry) relative to `base` as exact doubles (absolute_phase() gives the
  // point itself, for the ring and the start-up path). In steady
  // state (ring full) the terms are summed in registers over a local array of the ring history
  // and the new points, all relative to `base`: they span at most (2M + cnt) 2^k samples of at
  // most 2^31 counts, below 2^51 for the levels that take this path (cnt >= 8 means
  // 2^k <= kBatch / 8), so every double and every second difference formed from them is exact.
  template <std::size_t kTaus, std::size_t kMLo>
  static void push_batch(Level<kTaus, kMLo>& lv, std::uint64_t p0, const double* xd,
                         std::uint64_t base, std::size_t stride, std::size_t cnt) {
    if (lv.seg_points < kRing || cnt < 8) {
      for (std::size_t j = 0; j < cnt; ++j) {
        push_point(lv, p0 + j, absolute_phase(xd[j * stride], base));
      }
      return;
    }
    double arr[kRing + kBatch];
    for (std::size_t i = 0; i < kRing; ++i) {
      arr[i] = exact_relative(lv.ring[(p0 - kRing + i) % kRing], base);
    }
    for (std::size_t j = 0; j < cnt; ++j) {
      arr[kRing + j] = xd[j * stride];
    }
    // Two consecutive points per iteration in a 2-lane vector (GNU vector extension: SSE2 on
    // x86-64, NEON on aarch64, plain scalar code on a Cortex-M4); the taus are the inner loop
    // (unrolled, one register accumulator each), so x_j is loaded once for all taus and the
    // points shared between taus (x_{j-2m} of m equals x_{j-m'} of m' = 2m) are loaded once.
    V2 vacc[kTaus] = {};
    const std::size_t end = kRing + cnt;
    std::size_t j = kRing;
    for (; j + 1 < end; j += 2) {
      const V2 xj = load2(arr + j);
      for (std::size_t i = 0; i < kTaus; ++i) {
        const std::size_t m = kMLo + 1 + i;
        const V2 a = load2(arr + j - m);
        const V2 d = xj - (a + a) + load2(arr + j - 2 * m);
        vacc[i] += d * d;
      }
    }
    double acc[kTaus];
    for (std::size_t i = 0; i < kTaus; ++i) {
      acc[i] = vacc[i][0] + vacc[i][1];
    }
    if (j < end) {  // odd count: the last point alone
      for (std::size_t i = 0; i < kTaus; ++i) {
        const std::size_t m = kMLo + 1 + i;
        const double d = arr[j] - 2.0 * arr[j - m] + arr[j - 2 * m];
        acc[i] += d * d;
      }
    }
    // Flush at the same block boundaries as push_point (a block may hold up to kBatch more terms).
    const bool crosses = ((p0 + cnt - 1) >> 16) != (p0 >> 16) || (p0 & kBlockMask) == 0;
    for (std::size_t i = 0; i < kTaus; ++i) {
      lv.partial[i] += acc[i];
      if (crosses) {
        lv.total[i] += lv.partial[i];
        lv.partial[i] = 0.0;
      }
    }
    const std::size_t keep = cnt < kRing ? cnt : kRing;
    for (std::size_t q = cnt - keep; q < cnt; ++q) {
      lv.ring[(p0 + q) % kRing] = absolute_phase(xd[q * stride], base);
    }
    lv.seg_points += cnt;
  }

  // One level of push_frames: cnt points from p0 on, point j of channel c being
  // xs[j stride C + c] relative to base[c]. Each (tau, channel) partial sum gets its terms in
  // point order, as push_point adds them, so the sums are bit-identical; the terms themselves
  // are exact (relative phases < 2^51, see push_batch), hence equal to push_point's.
  template <std::size_t F, std::size_t kTaus, std::size_t kMLo, std::size_t C>
  static void push_frames_level(Level<kTaus, kMLo>* const (&lv)[C], std::uint64_t p0,
                                const double* xs, const std::uint64_t (&base)[C],
                                std::size_t stride, std::size_t cnt) {
    // Exact in double: the points span at most (2M + cnt) stride samples of at most 2^31
    // counts around base, below 2^51 under this bound. Under 4 points, push_point is as fast.
    // (cnt <= F always; said here so the compiler sees arr's bound, F < 4 compiles it out.)
    bool batched =
        F >= 4 && cnt >= 4 && cnt <= F && (kRing + cnt) * stride <= (std::size_t{1} << 20U);
    for (std::size_t c = 0; c < C; ++c) {
      batched = batched && lv[c]->seg_points >= kRing;
    }
    if (!batched) {
      for (std::size_t c = 0; c < C; ++c) {
        for (std::size_t j = 0; j < cnt; ++j) {
          push_point(*lv[c], p0 + j, absolute_phase(xs[j * stride * C + c], base[c]));
        }
      }
      return;
    }
    double arr[(kRing + F) * C];  // ring history, then the new points; channels inner
    for (std::size_t i = 0; i < kRing; ++i) {
      for (std::size_t c = 0; c < C; ++c) {
        arr[i * C + c] = exact_relative(lv[c]->ring[(p0 - kRing + i) % kRing], base[c]);
      }
    }
    for (std::size_t j = 0; j < cnt; ++j) {
      for (std::size_t c = 0; c < C; ++c) {
        arr[(kRing + j) * C + c] = xs[j * stride * C + c];
      }
    }
    // push_point closes a block after the term of a point p with p % 2^16 == 0: at most one
    // such point among cnt <= F < 2^16.
    const std::uint64_t pb = (p0 + kBlockMask) & ~kBlockMask;  // first multiple of 2^16 >= p0
    const bool closes = pb - p0 < cnt;
    const std::size_t split = closes ? static_cast<std::size_t>(pb - p0) + 1 : cnt;
    sum_frame_terms(lv, arr, kRing, kRing + split);
    if (closes) {
      for (std::size_t c = 0; c < C; ++c) {
        for (std::size_t i = 0; i < kTaus; ++i) {
          lv[c]->total[i] += lv[c]->partial[i];
          lv[c]->partial[i] = 0.0;
        }
      }
    }
    sum_frame_terms(lv, arr, kRing + split, kRing + cnt);
    const std::size_t keep = cnt < kRing ? cnt : kRing;
    for (std::size_t c = 0; c < C; ++c) {
      for (std::size_t q = cnt - keep; q < cnt; ++q) {
        lv[c]->ring[(p0 + q) % kRing] = absolute_phase(xs[q * stride * C + c], base[c]);
      }
      lv[c]->seg_points += cnt;
    }
  }

  // Terms of points arr[j0..j1) (rows of C channels) added in point order to every partial sum.
  template <std::size_t kTaus, std::size_t kMLo, std::size_t C>
  static void sum_frame_terms(Level<kTaus, kMLo>* const (&lv)[C], const double* arr,
                              std::size_t j0, std::size_t j1) {
    for (std::size_t i = 0; i < kTaus; ++i) {
      const std::size_t m = kMLo + 1 + i;
      double acc[C];
      for (std::size_t c = 0; c < C; ++c) {
        acc[c] = lv[c]->partial[i];
      }
      for (std::size_t j = j0; j < j1; ++j) {
        const double* x = arr + j * C;
        const double* a = arr + (j - m) * C;
        const double* b = arr + (j - 2 * m) * C;
        for (std::size_t c = 0; c < C; ++c) {
          const double d = x[c] - (a[c] + a[c]) + b[c];
          acc[c] += d * d;
        }
      }
      for (std::size_t c = 0; c < C; ++c) {
        lv[c]->partial[i] = acc[c];
      }
    }
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
    const auto tz = static_cast<std::size_t>(__builtin_ctzll(n));
    const std::size_t top = tz < L ? tz : L;
    for (std::size_t k = 1; k <= top; ++k) {
      push_point(upper_[k - 1], n >> k, x_);
    }
  }

  template <std::size_t kTaus, std::size_t kMLo>
  bool make_point(const Level<kTaus, kMLo>& lv, std::size_t i, std::size_t m, std::size_t level,
                  int noise_alpha, AdevPoint& out) const {
    const std::uint64_t terms = lv.terms_done[i] + open_terms(lv, m);
    if (terms == 0) {
      return false;
    }
    const std::uint64_t stride = std::uint64_t{1} << level;
    const double af = static_cast<double>(m) * static_cast<double>(stride);
    const double sum = lv.total[i] + lv.partial[i];
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
  Level<M, 0> level0_;
  Level<kUpperTaus, M / 2> upper_[L];
};

/// The online ADEV of every channel of an IMU (6 by default), one estimator per channel.
/// push_frame() is the fast way to feed it one frame at a time: it buffers kFrameBuffer frames
/// (kChannels x 4 x kFrameBuffer bytes; at most Channel::kFrames, 1 for no buffer worth the name,
/// e.g. on the M4) and pushes them through OnlineAdev::push_frames, with results bit-identical to
/// push(). Buffered frames are pushed before anything reads or changes the channels: channel()
/// (also the const one: the buffer and channels are `mutable`, the estimate is logically
/// unchanged), push(), mark_missing(), reset(), flush().
template <std::size_t kChannels = 6, std::size_t M = 8, std::size_t L = 22,
          std::size_t kFrameBuffer = OnlineAdev<M, L>::kFrames>
class MultiAdev {
 public:
  using Channel = OnlineAdev<M, L>;
  static constexpr std::size_t kNumChannels = kChannels;
  static_assert(kFrameBuffer >= 1 && kFrameBuffer <= Channel::kFrames,
                "kFrameBuffer must be 1..OnlineAdev::kFrames");

  /// Push one sample of every channel, now, channel by channel (~13 ns per sample per channel
  /// on the host). Same results as push_frame().
  void push(const std::int32_t (&counts)[kChannels]) {
    flush();
    for (std::size_t c = 0; c < kChannels; ++c) {
      ch_[c].push(counts[c]);
    }
  }
  /// Push one sample of every channel, buffered (see the class comment). O(kChannels) per call,
  /// plus one push_frames() every kFrameBuffer calls.
  void push_frame(const std::int32_t (&counts)[kChannels]) {
    for (std::size_t c = 0; c < kChannels; ++c) {
      pending_[n_pending_][c] = counts[c];
    }
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

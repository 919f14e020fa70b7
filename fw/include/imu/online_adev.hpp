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
#include <type_traits>

#include "imu/edf.hpp"

// The summing loops are written once, always inlined, and instantiated twice on x86-64: the
// portable form (4 lanes as two 2-lane vectors: SSE2) and, inside `target("avx2,fma")` entry
// points chosen at run time from the CPU's feature bits, the wide form (4 lanes in one ymm
// register, 2a subtracted by a fused multiply-add). Both do the same IEEE operations lane by
// lane, in the same order, with every second difference exact and no product fused into a sum,
// so their results are bit-identical (tested). Elsewhere (Cortex-M4, aarch64) there is one path,
// the portable one: NEON pairs, or register pairs on the M4.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define IMU_ADEV_AVX2_DISPATCH 1
#define IMU_ADEV_TARGET_AVX2 __attribute__((target("avx2,fma"), noinline))
#else
#define IMU_ADEV_AVX2_DISPATCH 0
#endif
// Forced inlining is what lets the AVX2 entry points inherit the bodies; without the dispatch
// the compiler chooses (on the M4, forcing it grows the image by ~20 kB for nothing).
#if IMU_ADEV_AVX2_DISPATCH
#define IMU_ADEV_INLINE inline __attribute__((always_inline))
#else
#define IMU_ADEV_INLINE inline
#endif

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
  static constexpr std::size_t kFrames = 256;          // frames per push_frames call, at most

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
  /// level's terms are summed over the batch in registers (4 consecutive points per 4-lane
  /// vector), from phases taken relative to the batch's oldest point, which are exact in double
  /// (|relative phase| < 2^53, see push_batch). On x86-64 with AVX2 + FMA the wide form runs
  /// (bit-identical to push_block_portable()). Stack: about 4 (2M + kBatch) doubles (8.7 kB for
  /// M = 8).
  void push_block(const std::int32_t* counts, std::size_t n) {
#if IMU_ADEV_AVX2_DISPATCH
    if (cpu_has_avx2_fma()) {
      push_block_avx2(counts, n);
      return;
    }
#endif
    push_block_portable(counts, n);
  }
  /// push_block() through the baseline-ISA code whatever the CPU (for tests and comparisons).
  void push_block_portable(const std::int32_t* counts, std::size_t n) {
    push_block_body<false>(counts, n);
  }

  /// Push the first n <= F frames of `frames` (frames[f][c]: sample f of channel c; F <= kFrames)
  /// into the C channels `ch`.
  /// Bit-identical to pushing frame after frame with push() on each channel: every term is formed
  /// exactly (as in push_block) and added to its tau's partial sum in the same order, flushed
  /// into the block total at the same points. Faster: per level, the taus' terms are summed over
  /// the batch in 4-lane vectors of channels (see sum_frame_terms), in registers, once the
  /// level's ring is full and the batch has >= 4 of its points; other levels take push()'s
  /// per-point path. Channels whose sample counts differ (pushed separately) or n > F fall back
  /// to push() frame by frame. On x86-64 with AVX2 + FMA the wide form runs (bit-identical to
  /// push_frames_portable()). Cost: ~1.5 M multiply-adds per sample per channel, as push().
  /// Stack: about (2M + F) (3C + 8) doubles (56 kB for M = 8, F = 256, C = 6): an
  /// application-processor path; 32-bit targets buffer F = 64 frames (16 kB), see
  /// kAdevFrameBufferDefault.
  template <std::size_t C, std::size_t F>
  static void push_frames(OnlineAdev (&ch)[C], const std::int32_t (&frames)[F][C], std::size_t n) {
#if IMU_ADEV_AVX2_DISPATCH
    if (cpu_has_avx2_fma()) {
      push_frames_avx2(ch, frames, n);
      return;
    }
#endif
    push_frames_body<false>(ch, frames, n);
  }
  /// push_frames() through the baseline-ISA code whatever the CPU (bit-identical to it).
  template <std::size_t C, std::size_t F>
  static void push_frames_portable(OnlineAdev (&ch)[C], const std::int32_t (&frames)[F][C],
                                   std::size_t n) {
    push_frames_body<false>(ch, frames, n);
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

  /// The code path push_block() and push_frames() take on this CPU: "avx2+fma" or "portable".
  static const char* kernel_isa() {
#if IMU_ADEV_AVX2_DISPATCH
    if (cpu_has_avx2_fma()) {
      return "avx2+fma";
    }
#endif
    return "portable";
  }

  [[nodiscard]] std::uint64_t samples() const { return n_; }          ///< including missing
  [[nodiscard]] std::uint64_t missing_samples() const { return missing_; }
  [[nodiscard]] std::uint64_t gaps() const { return gaps_; }
  [[nodiscard]] double sample_period_s() const { return sample_period_s_; }
  [[nodiscard]] double lsb() const { return lsb_; }

 private:
  // push_block's body; kFma: the AVX2 + FMA instantiation (see second_diff).
  template <bool kFma>
  IMU_ADEV_INLINE void push_block_body(const std::int32_t* counts, std::size_t n) {
    alignas(32) double x0[kRing + kBatch];  // level 0: ring history, then the batch's phases
    double* const xd = x0 + kRing;  // phases relative to base; the absolute phase is base + xd
    while (n > 0) {
      const std::size_t b = n < kBatch ? n : kBatch;
      const std::uint64_t base = x_;  // every level's batch array is relative to this phase
      // Running phase relative to base (|rel| <= kBatch 2^31 = 2^39) kept as the bit pattern of
      // the double 1.5 * 2^52 + rel (see exact_relative): one integer add per sample, and the
      // conversion is one vectorised subtraction over the batch.
      std::uint64_t bits = kMagicBits;
      for (std::size_t j = 0; j < b; ++j) {
        bits += static_cast<std::uint64_t>(static_cast<std::int64_t>(counts[j]));
        std::memcpy(xd + j, &bits, sizeof bits);
      }
      for (std::size_t j = 0; j < b; ++j) {
        xd[j] -= kMagic;
      }
      x_ = base + (bits - kMagicBits);
      const std::uint64_t first = n_ + 1;  // sample (= point) index of xd[0]
      n_ += b;
      push_batch<kFma>(level0_, first, x0, base, 1, b);  // stride 1: x0's history slots are used in place
      for (std::size_t k = 1; k <= L; ++k) {
        // Level-k points are the phases at indices that are multiples of 2^k.
        const std::uint64_t q0 = (first + (std::uint64_t{1} << k) - 1) >> k;
        const std::uint64_t q1 = (first + b - 1) >> k;
        if (q1 < q0) {
          break;  // no multiple of 2^k in the batch, hence none of 2^(k+1) either
        }
        const std::size_t off = static_cast<std::size_t>((q0 << k) - first);
        push_batch<kFma>(upper_[k - 1], q0, x0 + off, base, std::size_t{1} << k,
                         static_cast<std::size_t>(q1 - q0 + 1));
      }
      counts += b;
      n -= b;
    }
  }

  // push_frames' body; kFma as in push_block_body.
  template <bool kFma, std::size_t C, std::size_t F>
  static IMU_ADEV_INLINE void push_frames_body(OnlineAdev (&ch)[C],
                                               const std::int32_t (&frames)[F][C], std::size_t n) {
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
    // Level-0 rows (channels inner): the ring history (filled by push_frames_level), then the
    // phase after each frame relative to base[c], then kPad values read past the last row.
    alignas(32) double x0[(kRing + F) * C + kPad<C>];
    double* const xs = x0 + kRing * C;
    std::uint64_t base[C];
    double run[C];  // running sums of integers below 2^39 in magnitude: exact in double
    for (std::size_t c = 0; c < C; ++c) {
      base[c] = ch[c].x_;
      run[c] = 0.0;
    }
    for (std::size_t f = 0; f < n; ++f) {
      for (std::size_t c = 0; c < C; ++c) {
        run[c] += static_cast<double>(frames[f][c]);
        xs[f * C + c] = run[c];
      }
    }
    const std::uint64_t first = ch[0].n_ + 1;  // sample (= point) index of frame 0
    for (std::size_t c = 0; c < C; ++c) {
      ch[c].x_ = absolute_phase(run[c], base[c]);
      ch[c].n_ += n;
    }
    {
      Level<M, 0>* lv[C];
      for (std::size_t c = 0; c < C; ++c) {
        lv[c] = &ch[c].level0_;
      }
      push_frames_level<F, kFma>(lv, first, x0, base, 1, n);  // stride 1: history rows in place
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
      push_frames_level<F, kFma>(lv, q0, x0 + off * C, base, std::size_t{1} << k,
                                 static_cast<std::size_t>(q1 - q0 + 1));
    }
  }

  // kMLo: the level's taus are m = kMLo + 1 .. kMLo + kTaus.
  template <std::size_t kTaus, std::size_t kMLo>
  struct Level {
    std::uint64_t ring[kRing] = {};       // wrapping phase points, slot = point index % kRing
    double total[kTaus] = {};             // sum of closed blocks
    double partial[kTaus] = {};           // sum of the current block (< 2^16 terms)
    std::uint64_t terms_done[kTaus] = {}; // terms of closed segments
    std::uint64_t seg_points = 0;         // points in the current gap-free segment
  };

  using V4 = double __attribute__((vector_size(32)));  // NOLINT: GNU vector extension
  using V2 = double __attribute__((vector_size(16)));  // NOLINT: GNU vector extension

  // Four lanes of doubles: one ymm register in the AVX2 + FMA path (QuadWide), two 2-lane
  // vectors in the portable one (QuadPair: SSE2, NEON, or register pairs on the M4; a 4-lane GNU
  // vector without AVX is kept in memory by GCC's lowering, twice as slow). Same lanes, same
  // IEEE operations, so both give the same doubles.
  struct QuadWide {
    V4 v;
  };
  struct QuadPair {
    V2 lo;
    V2 hi;
  };
  template <bool kWide>
  using Quad = std::conditional_t<kWide, QuadWide, QuadPair>;

  static IMU_ADEV_INLINE void load(QuadWide& q, const double* p) {
    std::memcpy(&q.v, p, sizeof q.v);
  }
  static IMU_ADEV_INLINE void load(QuadPair& q, const double* p) {
    std::memcpy(&q.lo, p, sizeof q.lo);
    std::memcpy(&q.hi, p + 2, sizeof q.hi);
  }
  // Lanes 0-1 from lo[0..1], lanes 2-3 from hi[0..1].
  static IMU_ADEV_INLINE void load_halves(QuadWide& q, const double* lo, const double* hi) {
    V2 l;
    V2 h;
    std::memcpy(&l, lo, sizeof l);
    std::memcpy(&h, hi, sizeof h);
    q.v = __builtin_shufflevector(l, h, 0, 1, 2, 3);
  }
  static IMU_ADEV_INLINE void load_halves(QuadPair& q, const double* lo, const double* hi) {
    std::memcpy(&q.lo, lo, sizeof q.lo);
    std::memcpy(&q.hi, hi, sizeof q.hi);
  }
  static IMU_ADEV_INLINE void store(const QuadWide& q, double* p) {
    std::memcpy(p, &q.v, sizeof q.v);
  }
  static IMU_ADEV_INLINE void store(const QuadPair& q, double* p) {
    std::memcpy(p, &q.lo, sizeof q.lo);
    std::memcpy(p + 2, &q.hi, sizeof q.hi);
  }
  // (lane 0 + lane 1) + (lane 2 + lane 3)
  static IMU_ADEV_INLINE double lane_sum(const QuadWide& q) {
    return (q.v[0] + q.v[1]) + (q.v[2] + q.v[3]);
  }
  static IMU_ADEV_INLINE double lane_sum(const QuadPair& q) {
    return (q.lo[0] + q.lo[1]) + (q.hi[0] + q.hi[1]);
  }

  // acc += d * d, rounded twice (the product, then the sum) whatever the translation unit's
  // -ffp-contract: on x86-64 the product passes through an empty asm in a register, which no
  // compiler can fuse with the add, so the FMA-enabled entry points (and a caller built with
  // -march=native) sum exactly as the baseline path and push() do. Clang checks asm operands
  // before inlining (a ymm operand in this baseline-ISA code is refused), so there a pragma says
  // the same. Elsewhere the compiler's contraction applies to every path alike (the fw library
  // itself is built with -ffp-contract=off).
  template <typename T>
  static IMU_ADEV_INLINE void add_square(T& acc, const T& d) {
#if defined(__clang__)
#pragma clang fp contract(off)
    acc += d * d;
#else
    T sq = d * d;
#if IMU_ADEV_AVX2_DISPATCH
    __asm__("" : "+x"(sq));
#endif
    acc += sq;
#endif
  }
  // The same on four lanes. (Templates, like second_diff: the wide form is compiled only where
  // it is inlined, into the AVX2 + FMA entry points.)
  template <bool kWide>
  static IMU_ADEV_INLINE void add_square_quad(Quad<kWide>& acc, const Quad<kWide>& d) {
    if constexpr (kWide) {
      add_square(acc.v, d.v);
    } else {
      add_square(acc.lo, d.lo);
      add_square(acc.hi, d.hi);
    }
  }

  template <std::size_t kTaus, std::size_t kMLo>
  static IMU_ADEV_INLINE void push_point(Level<kTaus, kMLo>& lv, std::uint64_t p, std::uint64_t x) {
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
      add_square(lv.partial[i], d);
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
  static IMU_ADEV_INLINE std::uint64_t absolute_phase(double rel, std::uint64_t base) {
    return base + static_cast<std::uint64_t>(static_cast<std::int64_t>(rel));
  }
  static constexpr std::uint64_t kMagicBits = 0x4338000000000000ULL;  // 1.5 * 2^52
  static constexpr double kMagic = 6755399441055744.0;
  static IMU_ADEV_INLINE double exact_relative(std::uint64_t x, std::uint64_t base) {
    const std::uint64_t u = (x - base) + kMagicBits;
    double d = 0.0;
    std::memcpy(&d, &u, sizeof d);
    return d - kMagic;
  }

  // d = (x + b) - 2a, exact (x, a, b are integers below 2^51 in magnitude, see push_batch).
  // Portable: a2 = 2a, precomputed once per point (arr2). AVX2 + FMA: a2 = a, and 2a is
  // subtracted by one fused multiply-add, vfnmadd231pd, whose exact result needs no rounding, so
  // d is the same double. GCC: the instruction as inline asm (this code runs only inside the
  // AVX2 + FMA entry points, and an intrinsic could not be inlined into a baseline-ISA
  // template); clang: its contraction, forced on.
  template <bool kWide>
  static IMU_ADEV_INLINE void second_diff(Quad<kWide>& d, const Quad<kWide>& x,
                                          const Quad<kWide>& b, const Quad<kWide>& a2) {
    if constexpr (kWide) {
      d.v = x.v + b.v;
#if IMU_ADEV_AVX2_DISPATCH
      const V4 two = {2.0, 2.0, 2.0, 2.0};
#if defined(__clang__)
      fused_subtract(d.v, a2.v, two);
#else
      __asm__("vfnmadd231pd %2, %1, %0" : "+x"(d.v) : "x"(a2.v), "x"(two));  // d -= a * two
#endif
#endif
    } else {
      d.lo = (x.lo + b.lo) - a2.lo;
      d.hi = (x.hi + b.hi) - a2.hi;
    }
  }
#if defined(__clang__)
  // d -= a * b as one fused multiply-add in an FMA-enabled caller.
  static IMU_ADEV_INLINE void fused_subtract(V4& d, const V4& a, const V4& b) {
#pragma clang fp contract(fast)
    d = d - a * b;
  }
#endif

  // Push cnt consecutive points of one level, the first with point index p0; point j is
  // xs[kRing + j stride], relative to `base` as an exact double (absolute_phase() gives the point
  // itself, for the ring and the start-up path). With stride 1, xs[0..kRing) is scratch that
  // takes the ring history in place (the level-0 array of push_block); otherwise the points are
  // gathered into a local array. In steady state (ring full, cnt >= 8) the terms are summed in
  // registers by sum_batch: the history and the new points span at most (2M + cnt) 2^k samples
  // of at most 2^31 counts, below 2^51 for the levels that take this path (cnt >= 8 means
  // 2^k <= kBatch / 8), so every double and every second difference formed from them is exact.
  template <bool kFma, std::size_t kTaus, std::size_t kMLo>
  static IMU_ADEV_INLINE void push_batch(Level<kTaus, kMLo>& lv, std::uint64_t p0, double* xs,
                                         std::uint64_t base, std::size_t stride,
                                         std::size_t cnt) {
    if (lv.seg_points < kRing || cnt < 8 || cnt > kBatch) {
      for (std::size_t j = 0; j < cnt; ++j) {
        push_point(lv, p0 + j, absolute_phase(xs[kRing + j * stride], base));
      }
      return;
    }
    alignas(32) double gathered[kRing + kBatch];
    double* const arr = stride == 1 ? xs : gathered;
    for (std::size_t i = 0; i < kRing; ++i) {
      arr[i] = exact_relative(lv.ring[(p0 - kRing + i) % kRing], base);
    }
    if (stride != 1) {
      for (std::size_t j = 0; j < cnt; ++j) {
        arr[kRing + j] = xs[kRing + j * stride];
      }
    }
    double acc[kTaus];
    sum_batch<kFma, kTaus, kMLo>(arr, kRing + cnt, acc);
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
      lv.ring[(p0 + q) % kRing] = absolute_phase(arr[kRing + q], base);
    }
    lv.seg_points += cnt;
  }

  // acc[i] = sum over the points j = kRing .. end-1 of arr of the squared second difference
  // (arr[j] + arr[j - 2m]) - 2 arr[j - m], m = kMLo + 1 + i (exact: integers below 2^51).
  // Four consecutive points per iteration in a 4-lane vector (sum_batch_taus), the lanes summed
  // as (0 + 1) + (2 + 3), then the last (end - kRing) mod 4 points one by one.
  template <bool kFma, std::size_t kTaus, std::size_t kMLo>
  static IMU_ADEV_INLINE void sum_batch(const double* arr, std::size_t end, double (&acc)[kTaus]) {
    alignas(32) double arr2[kFma ? 1 : kRing + kBatch];
    if constexpr (!kFma) {
      for (std::size_t i = 0; i < end; ++i) {
        arr2[i] = arr[i] + arr[i];
      }
    }
    const std::size_t tail = kRing + (end - kRing) / 4 * 4;
    sum_batch_taus<kFma, kMLo, 0, kTaus>(arr, arr2, tail, acc);
    for (std::size_t j = tail; j < end; ++j) {
      for (std::size_t i = 0; i < kTaus; ++i) {
        const std::size_t m = kMLo + 1 + i;
        const double d = (arr[j] + arr[j - 2 * m]) - (arr[j - m] + arr[j - m]);
        add_square(acc[i], d);
      }
    }
  }

  // The vector part of sum_batch for taus i0 .. kTaus-1, four at a time (four accumulators and
  // their operands stay in registers; eight would spill on x86-64), the taus as the inner loop
  // (unrolled), so x_j is loaded once for all of them.
  template <bool kFma, std::size_t kMLo, std::size_t i0, std::size_t kTaus>
  static IMU_ADEV_INLINE void sum_batch_taus(const double* arr, const double* arr2,
                                             std::size_t end, double (&acc)[kTaus]) {
    constexpr std::size_t kGroup = kTaus - i0 < kTauGroup<kFma> ? kTaus - i0 : kTauGroup<kFma>;
    Quad<kFma> vacc[kGroup] = {};
    const double* const twice = kFma ? arr : arr2;  // what second_diff subtracts (2a or a)
    for (std::size_t j = kRing; j < end; j += 4) {
      Quad<kFma> xj;
      load(xj, arr + j);
      for (std::size_t g = 0; g < kGroup; ++g) {
        const std::size_t m = kMLo + 1 + i0 + g;
        Quad<kFma> b;
        Quad<kFma> a2;
        load(b, arr + j - 2 * m);
        load(a2, twice + j - m);
        Quad<kFma> d;
        second_diff<kFma>(d, xj, b, a2);
        add_square_quad<kFma>(vacc[g], d);
      }
    }
    for (std::size_t g = 0; g < kGroup; ++g) {
      acc[i0 + g] = lane_sum(vacc[g]);
    }
    if constexpr (i0 + kGroup < kTaus) {
      sum_batch_taus<kFma, kMLo, i0 + kGroup, kTaus>(arr, arr2, end, acc);
    }
  }

  // The shared channels' rows of sum_frame_terms (see push_frames_batched).
  struct SharedRows {
    const double* a;
    const double* b;
  };

  // Taus summed together (one register accumulator each, x_j loaded once for all of them): 4 in
  // ymm registers, 2 as pairs of xmm (16 of them; 4 would spill).
  template <bool kWide>
  static constexpr std::size_t kTauGroup = kWide ? 4 : 2;

  // Values read past the last row of C channels by the 4-lane loads of sum_frame_terms.
  template <std::size_t C>
  static constexpr std::size_t kPad = (C + 3) / 4 * 4 - C;

  // One level of push_frames: cnt points from p0 on, point j of channel c being
  // xs[(kRing + j stride) C + c] relative to base[c]. With stride 1 (level 0) the kRing rows
  // before take the ring history in place; otherwise the points are gathered into a local array.
  // Each (tau, channel) partial sum gets its terms in point order, as push_point adds them, so
  // the sums are bit-identical; the terms themselves are exact (relative phases < 2^51, see
  // push_batch), hence equal to push_point's.
  template <std::size_t F, bool kFma, std::size_t kTaus, std::size_t kMLo, std::size_t C>
  static IMU_ADEV_INLINE void push_frames_level(Level<kTaus, kMLo>* const (&lv)[C],
                                                std::uint64_t p0, double* xs,
                                                const std::uint64_t (&base)[C],
                                                std::size_t stride, std::size_t cnt) {
    if constexpr (F >= 4) {
      // Exact in double: the points span at most (2M + cnt) stride samples of at most 2^31
      // counts around base, below 2^51 under this bound. Under 4 points, push_point is as fast.
      bool batched = cnt >= 4 && cnt <= F && (kRing + cnt) * stride <= (std::size_t{1} << 20U);
      for (std::size_t c = 0; c < C; ++c) {
        batched = batched && lv[c]->seg_points >= kRing;
      }
      if (batched) {
        push_frames_batched<F, kFma>(lv, p0, xs, base, stride, cnt);
        return;
      }
    }
    for (std::size_t c = 0; c < C; ++c) {
      for (std::size_t j = 0; j < cnt; ++j) {
        push_point(*lv[c], p0 + j, absolute_phase(xs[(kRing + j * stride) * C + c], base[c]));
      }
    }
  }

  // push_frames_level in steady state: ring history and new points as rows of C channels (arr),
  // and twice each value (arr2, without FMA). The rows are read as ceil(C/4) 4-lane vectors
  // from offset 0, 4, ..: the last one runs past the row by kPad values (the next row's first
  // channels, or zeros after the last row), whose lanes are summed and never used.
  template <std::size_t F, bool kFma, std::size_t kTaus, std::size_t kMLo, std::size_t C>
  static IMU_ADEV_INLINE void push_frames_batched(Level<kTaus, kMLo>* const (&lv)[C],
                                                  std::uint64_t p0, double* xs,
                                                  const std::uint64_t (&base)[C],
                                                  std::size_t stride, std::size_t cnt) {
    constexpr std::size_t kGather = (kRing + (F + 1) / 2) * C + kPad<C>;  // stride >= 2
    alignas(32) double gathered[kGather];
    alignas(32) double arr2[kFma ? 1 : (kRing + F) * C + kPad<C>];
    double* const arr = stride == 1 ? xs : gathered;
    for (std::size_t i = 0; i < kRing; ++i) {
      for (std::size_t c = 0; c < C; ++c) {
        arr[i * C + c] = exact_relative(lv[c]->ring[(p0 - kRing + i) % kRing], base[c]);
      }
    }
    if (stride != 1) {
      for (std::size_t j = 0; j < cnt; ++j) {
        for (std::size_t c = 0; c < C; ++c) {
          arr[(kRing + j) * C + c] = xs[(kRing + j * stride) * C + c];
        }
      }
    }
    const std::size_t used = (kRing + cnt) * C;
    for (std::size_t i = used; i < used + kPad<C>; ++i) {
      arr[i] = 0.0;
    }
    if constexpr (!kFma) {
      for (std::size_t i = 0; i < used + kPad<C>; ++i) {
        arr2[i] = arr[i] + arr[i];
      }
    }
    // When C mod 4 is 2, the last two channels r of row j as 4-lane rows for sum_frame_terms:
    // a: (2r_j, 2r_{j-1}) (or (r_j, r_{j-1}) with FMA), b: (r_j, r_{j-2}), so that the vector of
    // taus m, m + 1 is (r_j, r_j) (one broadcast), a[j - m], b[j - 2m]: one load each.
    constexpr std::size_t kShareRows = C % 4 == 2 ? 4 * (kRing + F) : 1;
    alignas(32) double shared_a[kShareRows];
    alignas(32) double shared_b[kShareRows];
    if constexpr (C % 4 == 2) {
      // One pass, one 4-lane store per row and array (rows before the first are never read:
      // they repeat row 0).
      const double* const twice = kFma ? arr : arr2;
      Quad<kFma> row;
      for (std::size_t j = 0; j < kRing + cnt; ++j) {
        const std::size_t r = j * C + C - 2;
        const std::size_t r1 = j >= 1 ? r - C : r;
        const std::size_t r2 = j >= 2 ? r - 2 * C : r;
        load_halves(row, twice + r, twice + r1);
        store(row, shared_a + 4 * j);
        load_halves(row, arr + r, arr + r2);
        store(row, shared_b + 4 * j);
      }
    }
    const SharedRows rows{shared_a, shared_b};
    // push_point closes a block after the term of a point p with p % 2^16 == 0: at most one
    // such point among cnt <= F < 2^16.
    const std::uint64_t pb = (p0 + kBlockMask) & ~kBlockMask;  // first multiple of 2^16 >= p0
    const bool closes = pb - p0 < cnt;
    const std::size_t split = closes ? static_cast<std::size_t>(pb - p0) + 1 : cnt;
    sum_frame_terms<kFma, 0>(lv, arr, arr2, rows, kRing, kRing + split);
    if (closes) {
      for (std::size_t c = 0; c < C; ++c) {
        for (std::size_t i = 0; i < kTaus; ++i) {
          lv[c]->total[i] += lv[c]->partial[i];
          lv[c]->partial[i] = 0.0;
        }
      }
    }
    sum_frame_terms<kFma, 0>(lv, arr, arr2, rows, kRing + split, kRing + cnt);
    const std::size_t keep = cnt < kRing ? cnt : kRing;
    for (std::size_t c = 0; c < C; ++c) {
      for (std::size_t q = cnt - keep; q < cnt; ++q) {
        lv[c]->ring[(p0 + q) % kRing] = absolute_phase(arr[(kRing + q) * C + c], base[c]);
      }
      lv[c]->seg_points += cnt;
    }
  }

  // Terms of points arr[j0..j1) (rows of C channels) added in point order to the partial sums of
  // taus i0, i0 + 1, .. (four at a time: the accumulators stay in registers), then of the next
  // four. Each tau's channels are summed as 4-lane vectors of channels 0-3, 4-7, ..; when C mod 4
  // is 2, the last two channels of two taus share one vector (no idle lanes: six channels take
  // 1.5 vectors per tau, not 2); when it is 1 or 3, the last vector runs past the row (kPad).
  // Each (tau, channel) sum gets push_point's terms, (x + x_{-2m}) - 2 x_{-m} being exact, in
  // push_point's order, in a lane of its own: bit-identical.
  template <bool kFma, std::size_t i0, std::size_t kTaus, std::size_t kMLo, std::size_t C>
  static IMU_ADEV_INLINE void sum_frame_terms(Level<kTaus, kMLo>* const (&lv)[C],
                                              const double* arr, const double* arr2,
                                              const SharedRows& rows, std::size_t j0,
                                              std::size_t j1) {
    constexpr std::size_t kGroup = kTaus - i0 < kTauGroup<kFma> ? kTaus - i0 : kTauGroup<kFma>;
    constexpr bool kShare = C % 4 == 2;
    constexpr std::size_t kVec = kShare ? C / 4 : (C + 3) / 4;  // vectors of one tau
    constexpr std::size_t kPairs = kShare ? (kGroup + 1) / 2 : 0;  // shared vectors
    constexpr std::size_t kR = kShare ? C - 2 : 0;  // first of the two shared channels
    constexpr std::size_t kLanes = kVec * 4 < C ? kVec * 4 : C;  // channels in acc
    const double* const twice = kFma ? arr : arr2;
    Quad<kFma> acc[kGroup][kVec > 0 ? kVec : 1];
    Quad<kFma> shared[kPairs > 0 ? kPairs : 1];
    // Lanes of the shared vector p: channels kR, kR + 1 of tau 2p, then of tau 2p + 1 (of 2p again
    // when kGroup is odd: the copy is summed and never stored).
    auto pair_taus = [](std::size_t p, std::size_t& g0, std::size_t& g1) {
      g0 = 2 * p;
      g1 = 2 * p + 1 < kGroup ? 2 * p + 1 : 2 * p;
    };
    for (std::size_t g = 0; g < kGroup; ++g) {
      double lanes[kVec * 4 + 4] = {};
      for (std::size_t c = 0; c < kLanes; ++c) {
        lanes[c] = lv[c]->partial[i0 + g];
      }
      for (std::size_t v = 0; v < kVec; ++v) {
        load(acc[g][v], lanes + 4 * v);
      }
    }
    if constexpr (kShare) {
      for (std::size_t p = 0; p < kPairs; ++p) {
        std::size_t g0 = 0;
        std::size_t g1 = 0;
        pair_taus(p, g0, g1);
        const double lanes[4] = {lv[kR]->partial[i0 + g0], lv[kR + 1]->partial[i0 + g0],
                                 lv[kR]->partial[i0 + g1], lv[kR + 1]->partial[i0 + g1]};
        load(shared[p], lanes);
      }
    }
    for (std::size_t j = j0; j < j1; ++j) {
      Quad<kFma> x[kVec > 0 ? kVec : 1];
      for (std::size_t v = 0; v < kVec; ++v) {
        load(x[v], arr + j * C + 4 * v);
      }
      for (std::size_t g = 0; g < kGroup; ++g) {
        const std::size_t m = kMLo + 1 + i0 + g;
        for (std::size_t v = 0; v < kVec; ++v) {
          Quad<kFma> b;
          Quad<kFma> a2;
          load(b, arr + (j - 2 * m) * C + 4 * v);
          load(a2, twice + (j - m) * C + 4 * v);
          Quad<kFma> d;
          second_diff<kFma>(d, x[v], b, a2);
          add_square_quad<kFma>(acc[g][v], d);
        }
      }
      if constexpr (kShare) {
        Quad<kFma> xr;
        load_halves(xr, arr + j * C + kR, arr + j * C + kR);
        for (std::size_t p = 0; p < kPairs; ++p) {
          std::size_t g0 = 0;
          std::size_t g1 = 0;
          pair_taus(p, g0, g1);
          const std::size_t m0 = kMLo + 1 + i0 + g0;
          const std::size_t m1 = kMLo + 1 + i0 + g1;
          Quad<kFma> b;
          Quad<kFma> a2;
          if (m1 == m0 + 1) {  // taus m, m + 1: the rows built for them
            load(b, rows.b + 4 * (j - 2 * m0));
            load(a2, rows.a + 4 * (j - m0));
          } else {  // the last tau of an odd group, with itself
            load_halves(b, arr + (j - 2 * m0) * C + kR, arr + (j - 2 * m1) * C + kR);
            load_halves(a2, twice + (j - m0) * C + kR, twice + (j - m1) * C + kR);
          }
          Quad<kFma> d;
          second_diff<kFma>(d, xr, b, a2);
          add_square_quad<kFma>(shared[p], d);
        }
      }
    }
    for (std::size_t g = 0; g < kGroup; ++g) {
      double lanes[kVec * 4 + 4];
      for (std::size_t v = 0; v < kVec; ++v) {
        store(acc[g][v], lanes + 4 * v);
      }
      for (std::size_t c = 0; c < kLanes; ++c) {
        lv[c]->partial[i0 + g] = lanes[c];
      }
    }
    if constexpr (kShare) {
      for (std::size_t p = 0; p < kPairs; ++p) {
        std::size_t g0 = 0;
        std::size_t g1 = 0;
        pair_taus(p, g0, g1);
        double lanes[4];
        store(shared[p], lanes);
        lv[kR]->partial[i0 + g0] = lanes[0];
        lv[kR + 1]->partial[i0 + g0] = lanes[1];
        if (g1 != g0) {
          lv[kR]->partial[i0 + g1] = lanes[2];
          lv[kR + 1]->partial[i0 + g1] = lanes[3];
        }
      }
    }
    if constexpr (i0 + kGroup < kTaus) {
      sum_frame_terms<kFma, i0 + kGroup>(lv, arr, arr2, rows, j0, j1);
    }
  }

#if IMU_ADEV_AVX2_DISPATCH
  // AVX2 and FMA, as the CPU reports them (libgcc's cpuid cache, which also checks that the OS
  // saves the ymm registers).
  static bool cpu_has_avx2_fma() {
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }
  // The AVX2 + FMA entry points: the always-inlined bodies, compiled for AVX2 and FMA.
  IMU_ADEV_TARGET_AVX2 void push_block_avx2(const std::int32_t* counts, std::size_t n) {
    push_block_body<true>(counts, n);
  }
  template <std::size_t C, std::size_t F>
  IMU_ADEV_TARGET_AVX2 static void push_frames_avx2(OnlineAdev (&ch)[C],
                                                    const std::int32_t (&frames)[F][C],
                                                    std::size_t n) {
    push_frames_body<true>(ch, frames, n);
  }
#endif

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

/// Frames MultiAdev buffers by default, i.e. the batch of OnlineAdev::push_frames. 256 on 64-bit
/// targets: a longer batch spreads each level's ring history over more points (six channels on
/// x86-64: 2.9 ns per sample per channel at 256, 3.3 at 128). 64 on 32-bit ones (the Cortex-M4
/// node), where push_frames' stack frame (about 3 (2M + F) C doubles) must stay small.
#if UINTPTR_MAX > 0xFFFFFFFFU
inline constexpr std::size_t kAdevFrameBufferDefault = 256;
#else
inline constexpr std::size_t kAdevFrameBufferDefault = 64;
#endif

/// The online ADEV of every channel of an IMU (6 by default), one estimator per channel.
/// push_frame() is the fast way to feed it one frame at a time: it buffers kFrameBuffer frames
/// (kChannels x 4 x kFrameBuffer bytes; at most Channel::kFrames, 1 for no buffer worth the name,
/// e.g. on the M4) and pushes them through OnlineAdev::push_frames, with results bit-identical to
/// push(). Buffered frames are pushed before anything reads or changes the channels: channel()
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

// The node's model tuned by the record's Whittle likelihood: see node_tuning.hpp.
#include "imu/analyze/node_tuning.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/analyze/fft.hpp"
#include "imu/analyze/long_memory.hpp"
#include "imu/cli/json.hpp"
#include "imu/edf.hpp"
#include "imu/node/node.hpp"

namespace imu::analyze {
namespace {

using imu::cli::num_text;

constexpr std::size_t kMinStretch = std::size_t{1} << 12U;
constexpr std::size_t kSegment = std::size_t{1} << 18U;  // Welch segments of at most this
constexpr std::size_t kMaxSegments = 16;
constexpr std::size_t kBandStart = 1024;     // the band starts at rate / 1024
constexpr double kBinGrowth = 0.03;          // a bin holds 3 % of its frequency
constexpr std::size_t kMaxBinShare = 1000;   // and at most rate / 1000
constexpr double kHannInflation = 35.0 / 18.0;  // n sum w^4 / (sum w^2)^2 of the Hann taper
constexpr double kOscillationAlpha = 0.01;   // the added oscillation's level over the bins
constexpr std::size_t kOscillationCandidates = 3;  // excesses tried for it
// The whiteness monitor's block (updates), and the least difference of colour (added to its
// Box-Pierce statistic over a block) it tells apart: at the 95 % bound of chi-square(4), 0.05
// moves a block's failure probability by about 0.3 %, a few blocks in a thousand.
const double kMonitorBlock = static_cast<double>(node::NodeConfig{}.monitor_window);
constexpr double kColourTie = 0.05;
constexpr double kTwoPi = 6.283185307179586;
constexpr double kRoundingShare = 1e-20;  // see above_rounding

// The periodogram's band, binned. Frequencies in cycles per sample; ordinates in the units of
// the model's discrete spectrum (their mean is S at the bin).
struct Band {
  std::vector<double> f;
  std::vector<double> mean;
  std::vector<double> count;  // ordinates in the bin
  std::size_t len = 0;        // samples per segment
  std::size_t samples = 0;    // in all segments
  double f_lo = 0.0;          // the band's start
};

// The longest run of finite samples: its start and length.
std::size_t finite_run(const double* x, std::size_t n, std::size_t& start) {
  std::size_t best = 0;
  std::size_t run = 0;
  for (std::size_t i = 0; i < n; ++i) {
    run = std::isfinite(x[i]) ? run + 1 : 0;
    if (run > best) {
      best = run;
      start = i + 1 - run;
    }
  }
  return best;
}

// The periodogram of `segments` consecutive segments of len samples from x, averaged (Welch,
// no overlap): each segment's least-squares line removed, the periodic Hann taper.
std::vector<double> mean_periodogram(const double* x, std::size_t len, std::size_t segments) {
  std::vector<double> mean(len / 2, 0.0);
  std::vector<std::complex<double>> a(len);
  const double tm = 0.5 * static_cast<double>(len - 1);
  for (std::size_t seg = 0; seg < segments; ++seg) {
    const double* y = x + seg * len;
    double sy = 0.0;
    double sty = 0.0;
    double stt = 0.0;
    for (std::size_t i = 0; i < len; ++i) {
      const double t = static_cast<double>(i) - tm;
      sy += y[i];
      sty += t * y[i];
      stt += t * t;
    }
    const double c0 = sy / static_cast<double>(len);
    const double c1 = sty / stt;
    double sw2 = 0.0;
    for (std::size_t i = 0; i < len; ++i) {
      const double w = 0.5 - 0.5 * std::cos(kTwoPi * static_cast<double>(i) /
                                            static_cast<double>(len));
      a[i] = (y[i] - c0 - c1 * (static_cast<double>(i) - tm)) * w;
      sw2 += w * w;
    }
    fft(a);
    for (std::size_t k = 0; k < len / 2; ++k) {
      mean[k] += std::norm(a[k]) / sw2 / static_cast<double>(segments);
    }
  }
  return mean;
}

// The band of a stretch of `run` finite samples: segments of the largest power of two up to
// kSegment that fits, as many as fit up to kMaxSegments.
Band band_of(const double* x, std::size_t run) {
  std::size_t len = kMinStretch;
  while (len * 2 <= std::min(run, kSegment)) {
    len *= 2;
  }
  const std::size_t segments = std::min(run / len, kMaxSegments);
  const std::vector<double> p = mean_periodogram(x, len, segments);
  Band b;
  b.len = len;
  b.samples = len * segments;
  const std::size_t j0 = std::max<std::size_t>(1, len / kBandStart);
  b.f_lo = static_cast<double>(j0) / static_cast<double>(len);
  const std::size_t max_width = std::max<std::size_t>(1, len / kMaxBinShare);
  for (std::size_t j = j0; j < len / 2;) {
    const auto grown = static_cast<std::size_t>(kBinGrowth * static_cast<double>(j));
    const std::size_t end = std::min(len / 2, j + std::clamp<std::size_t>(grown, 1, max_width));
    double s = 0.0;
    for (std::size_t k = j; k < end; ++k) {
      s += p[k];
    }
    const auto m = static_cast<double>(end - j);
    b.f.push_back(0.5 * static_cast<double>(j + end - 1) / static_cast<double>(len));
    b.mean.push_back(s / m);
    b.count.push_back(m * static_cast<double>(segments));
    j = end;
  }
  return b;
}

// The discrete spectrum of the model the node runs, S(f) = h (zI - Phi)^-1 Qd (..)^H h^T + R.
class NodeSpectrum {
 public:
  bool set(const hal::ModelRecord& rec, double fs_hz) {
    ModelParams p{};
    std::size_t process_states = 0;
    if (!node::model_record_valid(rec, p) ||
        !node::discretize_pushed(p, fs_hz, dm_, process_states)) {
      return false;
    }
    n_ = process_states + 1;
    return true;
  }
  // f in cycles per sample. NaN if the solve fails.
  [[nodiscard]] double at(double f) const {
    constexpr std::size_t kN = node::kNodeStates;
    double mr[kN][kN];  // M^T = (zI - Phi)^T, real and imaginary parts
    double mi[kN][kN];
    double ar[kN];      // right-hand side h^T, then the solution a^T
    double ai[kN];
    const double zr = std::cos(kTwoPi * f);
    const double zi = std::sin(kTwoPi * f);
    for (std::size_t i = 0; i < n_; ++i) {
      for (std::size_t j = 0; j < n_; ++j) {
        mr[i][j] = -dm_.phi(j, i) + (i == j ? zr : 0.0);
        mi[i][j] = i == j ? zi : 0.0;
      }
      ar[i] = dm_.h(0, i);
      ai[i] = 0.0;
    }
    // Gaussian elimination with partial pivoting, complex arithmetic written out.
    for (std::size_t c = 0; c < n_; ++c) {
      std::size_t piv = c;
      for (std::size_t r = c + 1; r < n_; ++r) {
        if (std::hypot(mr[r][c], mi[r][c]) > std::hypot(mr[piv][c], mi[piv][c])) {
          piv = r;
        }
      }
      if (piv != c) {
        for (std::size_t j = 0; j < n_; ++j) {
          std::swap(mr[c][j], mr[piv][j]);
          std::swap(mi[c][j], mi[piv][j]);
        }
        std::swap(ar[c], ar[piv]);
        std::swap(ai[c], ai[piv]);
      }
      const double d2 = mr[c][c] * mr[c][c] + mi[c][c] * mi[c][c];
      if (!(d2 > 0.0)) {
        return std::numeric_limits<double>::quiet_NaN();
      }
      const double ir = mr[c][c] / d2;  // 1 / pivot
      const double ii = -mi[c][c] / d2;
      for (std::size_t r = c + 1; r < n_; ++r) {
        const double fr = mr[r][c] * ir - mi[r][c] * ii;  // factor = M[r][c] / pivot
        const double fi = mr[r][c] * ii + mi[r][c] * ir;
        for (std::size_t j = c; j < n_; ++j) {
          mr[r][j] -= fr * mr[c][j] - fi * mi[c][j];
          mi[r][j] -= fr * mi[c][j] + fi * mr[c][j];
        }
        ar[r] -= fr * ar[c] - fi * ai[c];
        ai[r] -= fr * ai[c] + fi * ar[c];
      }
    }
    for (std::size_t c = n_; c-- > 0;) {
      double sr = ar[c];
      double si = ai[c];
      for (std::size_t j = c + 1; j < n_; ++j) {
        sr -= mr[c][j] * ar[j] - mi[c][j] * ai[j];
        si -= mr[c][j] * ai[j] + mi[c][j] * ar[j];
      }
      const double d2 = mr[c][c] * mr[c][c] + mi[c][c] * mi[c][c];
      ar[c] = (sr * mr[c][c] + si * mi[c][c]) / d2;
      ai[c] = (si * mr[c][c] - sr * mi[c][c]) / d2;
    }
    double s = dm_.r_filter();
    for (std::size_t i = 0; i < n_; ++i) {
      for (std::size_t j = 0; j < n_; ++j) {
        s += dm_.qd(i, j) * (ar[i] * ar[j] + ai[i] * ai[j]);
      }
    }
    return s;
  }

 private:
  DiscreteModel<node::kNodeStates> dm_{};
  std::size_t n_ = 0;
};

// The record's parameters the tuning may move.
enum class Knob { kN, kFilter, kGmSb0, kGmTb0, kGmSb1, kGmTb1, kOscSigma, kOscF0, kOscBeta };

// The field of knob k in r (const or not).
template <typename Record>
auto& knob(Record& r, Knob k) {
  switch (k) {
    case Knob::kN: return r.n;
    case Knob::kFilter: return r.n_filter_s;
    case Knob::kGmSb0: return r.gm_sb[0];
    case Knob::kGmTb0: return r.gm_tb_s[0];
    case Knob::kGmSb1: return r.gm_sb[1];
    case Knob::kGmTb1: return r.gm_tb_s[1];
    case Knob::kOscSigma: return r.osc_sigma;
    case Knob::kOscF0: return r.osc_f0_hz;
    case Knob::kOscBeta: break;
  }
  return r.osc_beta_per_s;
}

// The spectrum of rec at the band's bins (empty if not available).
std::vector<double> spectrum_at(const Band& b, double fs_hz, const hal::ModelRecord& rec) {
  NodeSpectrum sp;
  std::vector<double> s;
  if (sp.set(rec, fs_hz)) {
    s.resize(b.f.size());
    for (std::size_t i = 0; i < b.f.size(); ++i) {
      s[i] = sp.at(b.f[i]);
    }
  }
  return s;
}

// -ln L (Whittle, per the taper's inflation) of rec on the band; +inf if the node would not
// run rec or its spectrum is not positive.
double whittle_cost(const Band& b, double fs_hz, const hal::ModelRecord& rec) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (rec.osc_sigma > 0.0F && !(static_cast<double>(rec.osc_f0_hz) < 0.5 * fs_hz)) {
    return kInf;  // an oscillation above Nyquist is an alias of one below
  }
  const std::vector<double> s = spectrum_at(b, fs_hz, rec);
  double cost = s.empty() ? kInf : 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!(s[i] > 0.0) || !std::isfinite(s[i])) {
      return kInf;
    }
    cost += b.count[i] * (std::log(s[i]) + b.mean[i] / s[i]);
  }
  return cost / kHannInflation;
}

// The knobs of rec's fast terms: N, the output filter, GMs whose corner lies in the band, the
// oscillation.
std::vector<Knob> fast_knobs(const hal::ModelRecord& rec, double fast_tb_s) {
  std::vector<Knob> k = {Knob::kN};
  if (rec.n_filter_s > 0.0F) {
    k.push_back(Knob::kFilter);
  }
  for (std::size_t g = 0; g < 2; ++g) {
    if (rec.gm_sb[g] > 0.0F && rec.gm_tb_s[g] > 0.0F &&
        static_cast<double>(rec.gm_tb_s[g]) < fast_tb_s) {
      k.push_back(g == 0 ? Knob::kGmSb0 : Knob::kGmSb1);
      k.push_back(g == 0 ? Knob::kGmTb0 : Knob::kGmTb1);
    }
  }
  if (rec.osc_sigma > 0.0F) {
    k.insert(k.end(), {Knob::kOscSigma, Knob::kOscF0, Knob::kOscBeta});
  }
  return k;
}

// The knobs stay what they are: the output filter within the analysis's range of it, a fast
// GM's Tb in the band (else it is another term).
bool in_tuning_ranges(const hal::ModelRecord& r, const std::vector<Knob>& knobs, double fs_hz,
                      double fast_tb_s) {
  for (const Knob k : knobs) {
    const auto v = static_cast<double>(knob(r, k));
    if ((k == Knob::kFilter && (v * fs_hz < kMinOutputFilterPerTs ||
                                v * fs_hz > kMaxOutputFilterPerTs)) ||
        ((k == Knob::kGmTb0 || k == Knob::kGmTb1) && !(v < fast_tb_s))) {
      return false;
    }
  }
  return true;
}

// Maximise the likelihood over the knobs (log parameters) from rec; rec takes the optimum when
// it is better. Returns the cost at rec afterwards.
double fit_knobs(const Band& b, double fs_hz, double fast_tb_s, hal::ModelRecord& rec,
                 const std::vector<Knob>& knobs) {
  const auto with = [&](const std::vector<double>& v) {
    hal::ModelRecord r = rec;
    for (std::size_t i = 0; i < knobs.size(); ++i) {
      knob(r, knobs[i]) = static_cast<float>(std::exp(v[i]));
    }
    return r;
  };
  std::vector<double> start(knobs.size());
  for (std::size_t i = 0; i < knobs.size(); ++i) {
    start[i] = std::log(static_cast<double>(knob(rec, knobs[i])));
  }
  const double cost0 = whittle_cost(b, fs_hz, rec);
  const auto cost = [&](const std::vector<double>& v) {
    const hal::ModelRecord r = with(v);
    return in_tuning_ranges(r, knobs, fs_hz, fast_tb_s)
               ? whittle_cost(b, fs_hz, r)
               : std::numeric_limits<double>::infinity();
  };
  const std::vector<double> best =
      nelder_mead(cost, start, 0.1, 60 * static_cast<int>(knobs.size()));
  const double c = cost(best);
  if (c < cost0) {
    rec = with(best);
    return c;
  }
  return cost0;
}

// The bins where rec's spectrum falls furthest below the periodogram (Whittle deviance, local
// maxima of it, the largest first), at most `most`; s: rec's spectrum at the bins.
std::vector<std::size_t> excess_peaks(const Band& b, const std::vector<double>& s,
                                      std::size_t most) {
  std::vector<double> dev(b.f.size(), 0.0);
  for (std::size_t i = 0; i < b.f.size(); ++i) {
    const double ratio = b.mean[i] / s[i];
    dev[i] = ratio > 1.0 ? b.count[i] * (ratio - 1.0 - std::log(ratio)) : 0.0;
  }
  std::vector<std::size_t> peaks;
  for (std::size_t i = 0; i < b.f.size(); ++i) {
    if (dev[i] > 0.0 && (i == 0 || dev[i] >= dev[i - 1]) &&
        (i + 1 == b.f.size() || dev[i] > dev[i + 1])) {
      peaks.push_back(i);
    }
  }
  std::sort(peaks.begin(), peaks.end(),
            [&dev](std::size_t a, std::size_t c) { return dev[a] > dev[c]; });
  peaks.resize(std::min(peaks.size(), most));
  return peaks;
}

// An oscillation at bin `peak` of the band: its half-power width from the bins around it whose
// excess over s is over half the peak's, sigma^2 from their excess power (both sides of the
// spectrum).
hal::ModelRecord oscillation_at(const Band& b, double fs_hz, const std::vector<double>& s,
                                std::size_t peak, hal::ModelRecord rec) {
  const double half = 0.5 * (b.mean[peak] - s[peak]);
  std::size_t lo = peak;
  std::size_t hi = peak;
  while (lo > 0 && b.mean[lo - 1] - s[lo - 1] > half) {
    --lo;
  }
  while (hi + 1 < b.f.size() && b.mean[hi + 1] - s[hi + 1] > half) {
    ++hi;
  }
  double excess = 0.0;
  double ordinates = 0.0;
  for (std::size_t i = lo; i <= hi; ++i) {
    excess += b.count[i] * (b.mean[i] - s[i]);
    ordinates += b.count[i];
  }
  const double width_hz = ordinates / static_cast<double>(b.len) * fs_hz;
  rec.osc_sigma = static_cast<float>(std::sqrt(2.0 * excess / static_cast<double>(b.len)));
  rec.osc_f0_hz = static_cast<float>(b.f[peak] * fs_hz);
  rec.osc_beta_per_s = static_cast<float>(0.5 * kTwoPi * width_hz);  // width = beta / pi
  return rec;
}

// The node filter's innovations on the record, normalised by their predicted variance, have
// the spectrum S_data / S_model (the steady-state filter whitens the model's spectrum): their
// autocorrelation at lags 1..kMonitorLags from the band (the ordinates below it counted as
// white). Returns the sum of their squares, what the whiteness monitor's Box-Pierce statistic
// grows with (block length x this).
double innovation_colour(const Band& b, double fs_hz, const hal::ModelRecord& rec) {
  const std::vector<double> s = spectrum_at(b, fs_hz, rec);
  if (s.empty()) {
    return std::numeric_limits<double>::infinity();
  }
  const double below = b.f_lo * static_cast<double>(b.len);  // ordinates below the band
  double r0 = below;
  double r[node::kMonitorLags + 1] = {};
  for (std::size_t l = 1; l <= node::kMonitorLags; ++l) {
    r[l] = below;
  }
  for (std::size_t i = 0; i < b.f.size(); ++i) {
    const double w = b.count[i] * b.mean[i] / s[i];
    r0 += w;
    for (std::size_t l = 1; l <= node::kMonitorLags; ++l) {
      r[l] += w * std::cos(kTwoPi * b.f[i] * static_cast<double>(l));
    }
  }
  double sum = 0.0;
  for (std::size_t l = 1; l <= node::kMonitorLags; ++l) {
    sum += (r[l] / r0) * (r[l] / r0);
  }
  return sum;
}

// Ways to make room for an oscillation's two states in a model that fills the node (a set of
// them): the bias-instability bank's short end up a decade at a time (one state each) while a
// decade is left, the fastest GM inside the band to the white noise at its low-frequency level
// (2 Sb Tb^2 = 2 N^2), the output filter left out.
constexpr unsigned kNarrowBank = 1U;
constexpr unsigned kFoldFastGm = 2U;
constexpr unsigned kDropFilter = 4U;
constexpr unsigned kAllWays = 7U;

// r with the ways applied; what went is said in `given_up`. False if a way does not apply or
// the result does not run on the node.
bool make_room(hal::ModelRecord& r, unsigned ways, double fast_tb_s, std::size_t reserved,
               std::string& given_up) {
  ModelParams p{};
  const auto add = [&given_up](const std::string& t) {
    given_up += (given_up.empty() ? "" : ", ") + t;
  };
  if ((ways & kNarrowBank) != 0U) {
    const float bank_lo_s = r.bi_tau_lo_s;
    if (!narrow_flicker_bank(r, 10.0F, reserved)) {  // a decade left
      return false;
    }
    add("the bias-instability bank below " + num_text(static_cast<double>(r.bi_tau_lo_s)) +
        " s (from " + num_text(static_cast<double>(bank_lo_s)) + " s)");
  }
  if ((ways & kFoldFastGm) != 0U) {
    std::size_t g = 2;
    for (std::size_t i = 0; i < 2; ++i) {
      if (r.gm_sb[i] > 0.0F && r.gm_tb_s[i] > 0.0F &&
          static_cast<double>(r.gm_tb_s[i]) < fast_tb_s &&
          (g == 2 || r.gm_tb_s[i] < r.gm_tb_s[g])) {
        g = i;
      }
    }
    if (g == 2) {
      return false;
    }
    const auto n = static_cast<double>(r.n);
    const auto sb = static_cast<double>(r.gm_sb[g]);
    const auto tb = static_cast<double>(r.gm_tb_s[g]);
    r.n = static_cast<float>(std::sqrt(n * n + sb * tb * tb));
    add("the GM of Tb " + num_text(tb) + " s (now white noise)");
    r.gm_sb[g] = g == 0 ? r.gm_sb[1] : 0.0F;  // the GMs stay in slot order
    r.gm_tb_s[g] = g == 0 ? r.gm_tb_s[1] : 0.0F;
    r.gm_sb[1] = 0.0F;
    r.gm_tb_s[1] = 0.0F;
  }
  if ((ways & kDropFilter) != 0U) {
    if (!(r.n_filter_s > 0.0F)) {
      return false;
    }
    r.n_filter_s = 0.0F;
    add("the output filter");
  }
  return node::model_record_valid(r, p, reserved);
}

// An oscillation added at each of the band's largest excesses over rec (where rec fills the
// node, with each way of making room for it), each tuned with rec's fast terms; of those whose
// 2 ln LR beside rec (cost_rec) passes `level`, the one that leaves the node's innovations
// whitest at its monitor's lags (the node has one oscillation slot, and its whiteness monitor
// is what the term is for), the likelihood deciding between those the monitor cannot tell
// apart. Returns its 2 ln LR (0: none passed); `given_up` says what made room for it.
double best_oscillation(const Band& b, double fs_hz, double fast_tb_s, std::size_t reserved,
                        const hal::ModelRecord& rec, double cost_rec, double level,
                        hal::ModelRecord& best, std::string& given_up) {
  const std::vector<double> s = spectrum_at(b, fs_hz, rec);
  if (s.empty()) {
    return 0.0;
  }
  double best_lr = 0.0;
  double best_colour = std::numeric_limits<double>::infinity();
  ModelParams p{};
  std::vector<hal::ModelRecord> tried;
  for (const std::size_t peak : excess_peaks(b, s, kOscillationCandidates)) {
    const hal::ModelRecord added = oscillation_at(b, fs_hz, s, peak, rec);
    // Two peaks of one band (within their half-power widths) start the same fit.
    const auto same_band = [&added](const hal::ModelRecord& t) {
      const double width_hz = static_cast<double>(added.osc_beta_per_s + t.osc_beta_per_s) /
                              kTwoPi;
      return std::fabs(static_cast<double>(added.osc_f0_hz - t.osc_f0_hz)) <= width_hz;
    };
    if (!(added.osc_sigma > 0.0F) || std::any_of(tried.begin(), tried.end(), same_band)) {
      continue;
    }
    tried.push_back(added);
    // As it is if the node holds it, else every least way of making room that gives a model
    // it runs (not one that holds another that does).
    const bool fits = node::model_record_valid(added, p, reserved);
    std::vector<unsigned> valid;
    for (unsigned ways = 0; ways <= (fits ? 0U : kAllWays); ++ways) {
      hal::ModelRecord cand = added;
      std::string room;
      const auto holds = [ways](unsigned v) { return (ways & v) == v; };
      if (!fits && (ways == 0U || std::any_of(valid.begin(), valid.end(), holds) ||
                    !make_room(cand, ways, fast_tb_s, reserved, room))) {
        continue;
      }
      valid.push_back(ways);
      if (!std::isfinite(whittle_cost(b, fs_hz, cand))) {
        continue;
      }
      const double lr =
          2.0 * (cost_rec - fit_knobs(b, fs_hz, fast_tb_s, cand, fast_knobs(cand, fast_tb_s)));
      // What the colour adds to the whiteness monitor's Box-Pierce statistic over a block;
      // within kColourTie of each other two candidates are the same to the monitor.
      const double colour = kMonitorBlock * innovation_colour(b, fs_hz, cand);
      const bool whiter = colour < best_colour - kColourTie;
      const bool tied = !whiter && colour <= best_colour + kColourTie;
      if (lr > level && (whiter || (tied && lr > best_lr))) {
        best_colour = colour;
        best_lr = lr;
        best = cand;
        given_up = room;
      }
    }
  }
  return best_lr;
}

// "name a -> b" for every knob that moved.
std::string changes(const hal::ModelRecord& from, const hal::ModelRecord& to,
                    const std::vector<Knob>& knobs) {
  static constexpr const char* kNames[] = {"N",          "output filter s", "GM sb",
                                           "GM tb s",    "GM2 sb",          "GM2 tb s",
                                           "osc. sigma", "osc. f0 Hz",      "osc. beta /s"};
  std::string t;
  for (const Knob k : knobs) {
    const auto va = static_cast<double>(knob(from, k));
    const auto vb = static_cast<double>(knob(to, k));
    if (std::fabs(va - vb) > 0.0) {
      t += (t.empty() ? "" : ", ") + std::string(kNames[static_cast<int>(k)]) + " " + num_text(va) +
           " -> " + num_text(vb);
    }
  }
  return t;
}

// The band holds more than the rounding of the values: its mean ordinate (the variance per
// sample it holds) above 1e-20 of their mean square (doubles round at 1e-16 of a value; an
// exact line or a constant leaves ~1e-32 after its line is removed, a sensor's noise 1e-10 of
// its gravity offset or more).
bool above_rounding(const Band& b, const double* x, std::size_t n) {
  double level = 0.0;
  double ordinates = 0.0;
  for (std::size_t i = 0; i < b.f.size(); ++i) {
    level += b.count[i] * b.mean[i];
    ordinates += b.count[i];
  }
  double ms = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    ms += x[i] * x[i] / static_cast<double>(n);
  }
  return ordinates > 0.0 && level / ordinates > kRoundingShare * ms;
}

}  // namespace

bool remove_signals(double* x, std::size_t n, double fs_hz,
                    const hal::ModelSignalsRecord& signals) {
  constexpr std::size_t kMaxReg = 6;  // constant, line, 2 x (sine, cosine)
  double freq[2] = {};
  std::size_t nf = 0;
  for (std::size_t i = 0; i < 2; ++i) {
    if (signals.sin_a[i] > 0.0F && signals.sin_f0_hz[i] > 0.0F) {
      freq[nf++] = static_cast<double>(signals.sin_f0_hz[i]);
    }
  }
  const std::size_t m = 2 + 2 * nf;
  if (!(fs_hz > 0.0) || n < 4 * m) {
    return false;
  }
  const double mid = 0.5 * static_cast<double>(n);
  const auto regressors = [&](std::size_t k, double (&r)[kMaxReg]) {
    const double t_s = static_cast<double>(k) / fs_hz;
    r[0] = 1.0;
    r[1] = (static_cast<double>(k) - mid) / mid;  // the line, scaled to [-1, 1]
    for (std::size_t j = 0; j < nf; ++j) {
      const double ph = kTwoPi * freq[j] * t_s;
      r[2 + 2 * j] = std::sin(ph);
      r[3 + 2 * j] = std::cos(ph);
    }
  };
  double a[kMaxReg][kMaxReg + 1] = {};  // normal equations, right-hand side in the last column
  double r[kMaxReg] = {};
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(x[k])) {
      continue;
    }
    regressors(k, r);
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t j = 0; j < m; ++j) {
        a[i][j] += r[i] * r[j];
      }
      a[i][m] += r[i] * x[k];
    }
  }
  for (std::size_t c = 0; c < m; ++c) {  // Gauss-Jordan with partial pivoting
    std::size_t piv = c;
    for (std::size_t i = c + 1; i < m; ++i) {
      piv = std::fabs(a[i][c]) > std::fabs(a[piv][c]) ? i : piv;
    }
    if (!(std::fabs(a[piv][c]) > 1e-12 * static_cast<double>(n))) {
      return false;
    }
    for (std::size_t j = 0; j <= m; ++j) {
      std::swap(a[c][j], a[piv][j]);
    }
    for (std::size_t i = 0; i < m; ++i) {
      if (i != c) {
        const double f = a[i][c] / a[c][c];
        for (std::size_t j = c; j <= m; ++j) {
          a[i][j] -= f * a[c][j];
        }
      }
    }
  }
  double coef[kMaxReg] = {};
  for (std::size_t i = 0; i < m; ++i) {
    coef[i] = a[i][m] / a[i][i];
  }
  for (std::size_t k = 0; k < n; ++k) {
    if (std::isfinite(x[k])) {
      regressors(k, r);
      for (std::size_t i = 0; i < m; ++i) {
        x[k] -= coef[i] * r[i];
      }
    }
  }
  return true;
}

bool narrow_flicker_bank(hal::ModelRecord& rec, float min_span, std::size_t reserved_states) {
  ModelParams p{};
  const float lo_s = rec.bi_tau_lo_s;
  while (!node::model_record_valid(rec, p, reserved_states) && rec.bi > 0.0F && rec.bi_tau_lo_s > 0.0F &&
         std::isfinite(rec.bi_tau_hi_s) && rec.bi_tau_lo_s * 10.0F * min_span <= rec.bi_tau_hi_s) {
    rec.bi_tau_lo_s *= 10.0F;
  }
  return rec.bi_tau_lo_s > lo_s;
}

NodeTuning tune_node_record(const double* x, std::size_t n, double fs_hz,
                            hal::ModelRecord& rec, std::size_t reserved_states) {
  NodeTuning out;
  std::size_t start = 0;
  const std::size_t run = finite_run(x, n, start);
  if (run < kMinStretch || !(fs_hz > 0.0)) {
    out.note = "not tuned: fewer than " + std::to_string(kMinStretch) +
               " finite samples in a row";
    return out;
  }
  const double* const first = x + start;
  const auto same = [first](double v) { return !(std::fabs(v - *first) > 0.0); };
  if (std::all_of(first, first + run, same)) {
    out.note = "not tuned: the record does not vary (a constant channel)";
    return out;
  }
  const Band b = band_of(x + start, run);
  if (!above_rounding(b, first, run)) {
    out.note = "not tuned: the record holds nothing above its values' rounding (a line or a "
               "constant)";
    return out;
  }
  out.samples = b.samples;
  const double fast_tb_s = 1.0 / (kTwoPi * b.f_lo * fs_hz);
  const hal::ModelRecord given = rec;
  const double cost_given = whittle_cost(b, fs_hz, given);
  if (!std::isfinite(cost_given)) {
    out.note = "not tuned: the node's spectrum of the model is not available";
    return out;
  }
  const std::vector<Knob> knobs = fast_knobs(rec, fast_tb_s);
  double cost = fit_knobs(b, fs_hz, fast_tb_s, rec, knobs);
  std::string what = changes(given, rec, knobs);
  std::string given_up;
  if (!(rec.osc_sigma > 0.0F)) {
    out.oscillation_level =
        chi2_quantile(1.0 - kOscillationAlpha / static_cast<double>(b.f.size()), 3.0);
    hal::ModelRecord with_osc = rec;
    out.oscillation_two_ln_lr = best_oscillation(b, fs_hz, fast_tb_s, reserved_states, rec, cost,
                                                 out.oscillation_level, with_osc, given_up);
    if (out.oscillation_two_ln_lr > 0.0) {
      out.oscillation_added = true;
      cost -= 0.5 * out.oscillation_two_ln_lr;
      rec = with_osc;
      what = changes(given, rec, fast_knobs(rec, fast_tb_s));
    }
  }
  out.two_ln_lr = 2.0 * (cost_given - cost);
  out.tuned = !what.empty();
  out.note = "tuned to the node's filter by the Whittle likelihood of " +
             std::to_string(b.samples) + " samples (2 ln LR " + num_text(out.two_ln_lr) +
             "): " + (what.empty() ? "unchanged" : what);
  if (out.oscillation_added) {
    out.note += "; the oscillation added (2 ln LR " + num_text(out.oscillation_two_ln_lr) + " > " +
                num_text(out.oscillation_level) + ")";
    if (!given_up.empty()) {
      out.note += " in place of " + given_up + ": the node holds " +
                  std::to_string(node::kNodeProcessStates) + " states" +
                  (reserved_states > 0 ? " (" + std::to_string(reserved_states) +
                                             " of them the deterministic terms')"
                                       : std::string());
    }
  }
  return out;
}

}  // namespace imu::analyze

// The analysis pipeline (see analyze.hpp for the method).
#include "imu/analyze/analyze.hpp"
#include "effects.hpp"
#include "imu/analyze/long_memory.hpp"
#include "imu/analyze/fft.hpp"
#include "data_faults.hpp"
#include "noise_level.hpp"
#include "radix_sort.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <ctime>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <numeric>

#include "imu/bias_kf.hpp"
#include "imu/covariance_check.hpp"
#include "imu/edf.hpp"
#include "imu/effect_monitor.hpp"
#include "imu/linalg.hpp"
#include "imu/model_fit.hpp"
#include "imu/residual_monitor.hpp"

namespace imu::analyze {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Block means for the auxiliary likelihood comparisons (steps, the long-tau family, a ramp's
// bend): half the RRW test's 2048, a quarter of its cost (the step profile is O(blocks^2)).
constexpr std::size_t kAuxBlocks = 1024;
// A sinusoid is looked for from this many periods in the record; below kSineCyclesByAdev its
// line must also be needed on the record's likelihood (slow_line_stands).
constexpr double kMinSineCycles = 5.0;
constexpr double kSineCyclesByAdev = 20.0;
// Events each scale's step detector keeps: enough to count repeated level shifts.
constexpr std::size_t kStepEvents = 64;
// The longest Tb the first-order model's GM may take in place of a walk (slow_gm_for_walk), in
// record lengths: over the record such a GM is the walk (its PSD is the walk's above 1 / (2 pi
// Tb)), so the walk can beat it only with a GM the ADEV shows beside it.
constexpr double kSlowGmTbPerRecord = 100.0;
// A walk the record cannot tell from a slow GM is named where every GM the record allows peaks
// beyond this fraction of the record (T / 4, 2.5 x the analysis's longest tau T / 10).
constexpr double kWalkGmPeakPerRecord = 0.25;
using Adev = OnlineAdev<8, 22>;
using Points = std::vector<AdevPoint>;

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// ---------------------------------------------------------------- ADEV helpers

// Counts of y - offset (the offset keeps a record with a large mean, e.g. gravity, inside int32
// at a fine LSB; the ADEV does not see a constant).
std::vector<std::int32_t> to_counts(const std::vector<double>& y, double offset, double lsb,
                                    std::size_t& sat) {
  std::vector<std::int32_t> c(y.size());
  sat = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const QuantizeResult q = quantize(y[i] - offset, lsb);
    c[i] = q.counts;
    sat += q.saturated ? 1U : 0U;
  }
  return c;
}

// The ADEV of counts through the online estimator; gap (may be empty): 1 marks a sample that
// is missing (non-finite in the record): the estimator skips it with mark_missing (no term spans
// it), the other samples go in runs through push_block.
std::unique_ptr<Adev> adev_estimate(const std::vector<std::int32_t>& counts,
                                    const std::vector<std::uint8_t>& gap, double ts, double lsb) {
  auto est = std::make_unique<Adev>(ts, lsb);
  if (gap.empty()) {
    est->push_block(counts.data(), counts.size());
    return est;
  }
  std::size_t i = 0;
  while (i < counts.size()) {
    std::size_t j = i;
    const bool missing = gap[i] != 0;
    while (j < counts.size() && (gap[j] != 0) == missing) {
      ++j;
    }
    if (!missing) {
      est->push_block(counts.data() + i, j - i);
    } else {
      est->mark_missing(j - i);
    }
    i = j;
  }
  return est;
}

// Snapshots of one estimator, one per noise exponent alpha = -2..2 (index alpha + 2).
struct AdevSet {
  std::array<Points, 5> by_alpha;
};

AdevSet snapshots(const Adev& est) {
  AdevSet s;
  for (std::size_t i = 0; i < s.by_alpha.size(); ++i) {
    AdevPoint pts[Adev::kMaxPoints];
    const std::size_t n = est.snapshot(pts, Adev::kMaxPoints, static_cast<int>(i) - 2);
    s.by_alpha[i].assign(pts, pts + n);
  }
  return s;
}

// The record's ADEV with its gaps. No term of the estimator spans a gap (adev_estimate), so
// scattered missing samples (one in a thousand) leave no term at the long taus at all, and the
// terms a few long dropouts leave are a subset of the record's (its ADEV 5 % off the whole
// record's at taus of a few hundred seconds with 0.5 % of the samples missing). Each tau where a
// gap took any term takes the AVAR of the bin means of the recorded samples instead (GapAvar),
// at the estimator's taus and strides, its EDF scaled by the terms it kept. A gap bridged by
// an interpolation of its neighbours biases the AVAR (a line holds no noise and correlates
// with the neighbours it is drawn from): with 5 % of the samples missing at random, the ADEV
// with gaps of up to 16 samples bridged by lines lay 3-4 % above the record's without gaps from
// 0.08 s (where it took over from the gap-free terms) to 10 s, a step the fit read as an output
// filter on the white noise or a second GM, N 3-4 % off; bridged by the local level plus white
// noise (the local means correlate in the same way), 4.5 % high from 1 to 30 s.

// Prefix sums of the recorded counts and of their number (gap samples left out).
struct RecordedPrefix {
  std::vector<std::int64_t> sum;
  std::vector<std::uint32_t> count;
  double white_var = 0.0;  // half the mean squared first difference over recorded pairs
};

RecordedPrefix recorded_prefix(const std::vector<std::int32_t>& counts,
                               const std::vector<std::uint8_t>& gap) {
  RecordedPrefix p;
  p.sum.assign(counts.size() + 1, 0);
  p.count.assign(counts.size() + 1, 0);
  double sq = 0.0;
  double pairs = 0.0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    const bool rec = gap[i] == 0;
    p.sum[i + 1] = p.sum[i] + (rec ? counts[i] : 0);
    p.count[i + 1] = p.count[i] + (rec ? 1U : 0U);
    if (rec && i > 0 && gap[i - 1] == 0) {
      const double d = static_cast<double>(counts[i]) - static_cast<double>(counts[i - 1]);
      sq += d * d;
      pairs += 1.0;
    }
  }
  p.white_var = pairs > 0.0 ? 0.5 * sq / pairs : 0.0;
  return p;
}

// The AVAR (counts^2) at averaging factor m, one term every `stride` samples, from the means of
// the recorded samples in each pair of adjacent bins (each bin at least half recorded): a bin of
// k recorded samples carries white noise of variance s2 / k where the full bin's is s2 / m, which
// each term gives back (s2: RecordedPrefix::white_var), so that white noise reads as without
// gaps; the slower terms' bin means are unbiased by samples missing at random.
struct GapAvar {
  double avar = 0.0;
  std::uint64_t terms = 0;
};

GapAvar gap_avar(const RecordedPrefix& p, std::size_t m, std::size_t stride) {
  GapAvar g;
  const std::size_t n = p.sum.size() - 1;
  double acc = 0.0;
  for (std::size_t i = 0; i + 2 * m <= n; i += std::max<std::size_t>(stride, 1)) {
    const std::uint32_t k1 = p.count[i + m] - p.count[i];
    const std::uint32_t k2 = p.count[i + 2 * m] - p.count[i + m];
    if (2 * static_cast<std::size_t>(k1) < m || 2 * static_cast<std::size_t>(k2) < m) {
      continue;
    }
    const double a = static_cast<double>(k1);
    const double b = static_cast<double>(k2);
    const double d = static_cast<double>(p.sum[i + 2 * m] - p.sum[i + m]) / b -
                     static_cast<double>(p.sum[i + m] - p.sum[i]) / a;
    acc += d * d - p.white_var * (1.0 / a + 1.0 / b - 2.0 / static_cast<double>(m));
    ++g.terms;
  }
  g.avar = g.terms > 0 ? acc / (2.0 * static_cast<double>(g.terms)) : 0.0;
  return g;
}

AdevSet adev_of(const std::vector<std::int32_t>& counts, const std::vector<std::uint8_t>& gap,
                double ts, double lsb) {
  AdevSet s = snapshots(*adev_estimate(counts, gap, ts, lsb));
  if (std::find(gap.begin(), gap.end(), std::uint8_t{1}) == gap.end()) {
    return s;
  }
  // The estimator's taus, strides, term counts and EDF for the record without gaps, from its
  // counts as they stand (the gaps hold fill_gaps' values); only that layout is kept from it.
  const AdevSet full = snapshots(*adev_estimate(counts, {}, ts, lsb));
  const RecordedPrefix prefix = recorded_prefix(counts, gap);
  std::map<std::uint32_t, GapAvar> by_af;
  for (std::size_t i = 0; i < s.by_alpha.size(); ++i) {
    Points merged;
    for (const AdevPoint& b : full.by_alpha[i]) {
      const auto it = std::find_if(s.by_alpha[i].begin(), s.by_alpha[i].end(),
                                   [&b](const AdevPoint& a) { return a.af == b.af; });
      if (it != s.by_alpha[i].end() && it->n_terms == b.n_terms) {
        merged.push_back(*it);
        continue;
      }
      auto g = by_af.find(b.af);
      if (g == by_af.end()) {
        g = by_af.emplace(b.af, gap_avar(prefix, b.af, b.stride)).first;
      }
      if (g->second.terms == 0 || !(g->second.avar > 0.0) || b.n_terms == 0) {
        continue;
      }
      AdevPoint p = b;
      p.avar = g->second.avar * lsb * lsb;
      p.adev = std::sqrt(p.avar);
      p.n_terms = g->second.terms;
      p.edf = b.edf * static_cast<double>(g->second.terms) / static_cast<double>(b.n_terms);
      const DevInterval ci = deviation_interval(p.adev, p.edf);
      p.ci_lo = ci.lo;
      p.ci_hi = ci.hi;
      merged.push_back(p);
    }
    s.by_alpha[i] = std::move(merged);
  }
  return s;
}

// Local log-log slope of the model AVAR -> power-law noise exponent alpha for the EDF.
int model_alpha(const ModelParams& p, double tau) {
  const double lo = model_avar(p, tau / 1.1);
  const double hi = model_avar(p, tau * 1.1);
  if (!(lo > 0.0) || !(hi > 0.0)) {
    return 0;
  }
  const double mu = std::log(hi / lo) / std::log(1.21);
  const long a = std::lround(-mu - 1.0);
  return static_cast<int>(std::clamp(a, -2L, 2L));
}

// Points with the EDF (and interval) of the noise type the model says dominates at each tau.
Points points_for_model(const AdevSet& s, const ModelParams& p) {
  Points out = s.by_alpha[2];
  for (auto& pt : out) {
    const int alpha = model_alpha(p, pt.tau_s);  // -2..2
    const std::size_t index = alpha < 0 ? 2U - static_cast<std::size_t>(-alpha)
                                        : 2U + static_cast<std::size_t>(alpha);
    for (const auto& q : s.by_alpha[index]) {
      if (q.af == pt.af) {
        pt = q;
        break;
      }
    }
  }
  return out;
}

Points in_range(const Points& p, double tau_max) {
  Points out;
  for (const auto& pt : p) {
    if (pt.tau_s <= tau_max * (1.0 + 1e-9)) {
      out.push_back(pt);
    }
  }
  return out;
}

struct Residual {
  AdevCheckResult<8> check{};
  std::vector<double> z;
  double cost = 0.0;
};

Residual residual(const Points& pts, const ModelParams& m, const Options& o, double tau_min,
                  double tau_max) {
  Residual r;
  r.z.assign(pts.size(), 0.0);
  AdevCheckOptions co;
  co.tau_min_s = tau_min;
  co.tau_max_s = tau_max;
  co.threshold = o.z_run;
  co.min_run = o.min_run;
  std::size_t n_in = 0;
  for (const auto& pt : pts) {
    n_in += pt.tau_s >= tau_min * (1.0 - 1e-9) && pt.tau_s <= tau_max * (1.0 + 1e-9) ? 1U : 0U;
  }
  co.z_single = two_sided_normal_threshold(o.alpha / static_cast<double>(n_in > 0 ? n_in : 1));
  if (check_adev_residual(pts.data(), pts.size(), m, co, r.check, r.z.data()) !=
      EffectStatus::kOk) {
    return r;
  }
  for (double z : r.z) {
    r.cost += z * z;
  }
  return r;
}

// The lower end of the bias-instability bank: the shortest tau at which the data's ADEV is within
// sqrt(11) of its lowest value (bias instability is that floor; where the ADEV is higher, the
// white noise's AVAR exceeds the floor's tenfold and the bank's fall-off below its range costs
// under a tenth of the AVAR), but no shorter than 10 tau_min or 1e-4 tau_max (four decades,
// six GMs) and no longer than 0.1 tau_max. At 1e-3 tau_max, on records longer than a few hours
// a GM at the shortest taus held the flicker below the bank and the record's own GM was then
// named as a second GM (the selection benchmark: 38 of 500 reports, 27 at 1e-4). A bank
// reaching below where the floor begins competes with the GM of the sensor's own filter (the
// ADIS16405's, ~0.1 s), which it then imitates: tau_floor, not the bound, keeps it above. A
// bank that stops short of where the floor begins makes the fit raise B to fill the gap: on
// pure flicker (B = 1e-2, N = 3e-3, 2e6 samples at 100 Hz) a lower end at tau_min_adev / 30 and
// 1e-2 tau_max biased B by +2 % to +15 %, this one by -0.5 % to +1.2 %.
double flicker_tau_lo(double tau_min, double tau_max, const Points& pts) {
  double t_min_adev = 0.0;
  double a_min = 0.0;
  for (const auto& pt : pts) {
    if (pt.tau_s >= tau_min && pt.tau_s <= tau_max && pt.adev > 0.0 &&
        (!(a_min > 0.0) || pt.adev < a_min)) {
      a_min = pt.adev;
      t_min_adev = pt.tau_s;
    }
  }
  double t_floor = t_min_adev;
  for (const auto& pt : pts) {
    if (pt.tau_s >= tau_min && pt.tau_s < t_floor && pt.adev > 0.0 &&
        pt.adev <= std::sqrt(11.0) * a_min) {
      t_floor = pt.tau_s;
    }
  }
  const double lo = std::max({10.0 * tau_min, 1e-4 * tau_max, t_floor});
  return std::min(lo, 0.1 * tau_max);
}

// p with the sinusoids of `from` (the fit's linear terms never hold them).
ModelParams with_sines(ModelParams p, const ModelParams& from) {
  p.sin_a = from.sin_a;
  p.sin_f0_hz = from.sin_f0_hz;
  p.sin2_a = from.sin2_a;
  p.sin2_f0_hz = from.sin2_f0_hz;
  p.sin_ts_s = from.sin_ts_s;
  p.sin2_ts_s = from.sin2_ts_s;
  return p;
}

// The AVAR of a sampled 1/f sequence (Kasdin's, of white variance b^2, no anti-alias filter
// ahead of the sampler) at tau = m Ts, less the continuous floor avar_flicker_ideal, per b^2:
// 2 int_0^1/2 sin^4(pi f m) / (m^2 sin^3(pi f)) df - 2 ln 2 / pi (its spectrum b^2 / (2 sin pi f)
// in cycles per sample), by Simpson's rule. 0.195 at m = 1, 0.0068 at 8, 1.7e-4 at 64: the
// excess is read as white noise unless the model knows it. 0 beyond m = 64.
double flicker_sampled_excess(std::uint32_t m) {
  if (m == 0 || m > 64) {
    return 0.0;
  }
  const double md = static_cast<double>(m);
  const std::uint32_t steps = 64 * m + 256;  // even: 64 per period of sin^4(pi f m)
  const double h = 0.5 / static_cast<double>(steps);
  double sum = 0.0;
  for (std::uint32_t i = 1; i <= steps; ++i) {  // the integrand is 0 at f = 0
    const double f = h * static_cast<double>(i);
    const double s = std::sin(kPi * f);
    const double a = std::sin(kPi * f * md);
    const double w = i == steps ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += w * a * a * a * a / (md * md * s * s * s);
  }
  return 2.0 * sum * h / 3.0 - avar_flicker_ideal(1.0);
}

// What a fit's status means, for a note.
const char* fit_status_text(FitStatus s) {
  switch (s) {
    case FitStatus::kOk: return "ok";
    case FitStatus::kBadOptions: return "no usable range or term";
    case FitStatus::kTooFewPoints: return "fewer usable ADEV points than parameters";
    case FitStatus::kTooManyPoints: return "more ADEV points than the fit holds";
    case FitStatus::kSingular: return "singular normal equations";
  }
  return "unknown";
}

// tb_max_s > 0 bounds the GM correlation time (0: model_fit's default, 10 tau_max), tb_min_s
// from below. shape: the oscillation's f0 and beta when terms hold kFitOscillation.
// flicker_lo_s: the bias-instability bank's lower end (0: flicker_tau_lo's rule).
FitOptions fit_options(const Points& pts, std::uint32_t terms, double tau_min, double tau_max,
                       double tb_max_s = 0.0, const ModelParams* shape = nullptr,
                       double white_filter_s = 0.0, double tb_min_s = 0.0,
                       double flicker_lo_s = 0.0, double k_fixed = 0.0) {
  FitOptions fo;
  fo.k_fixed = k_fixed;
  fo.white_filter_s = white_filter_s;
  if (shape != nullptr) {
    fo.osc_f0_hz = shape->osc_f0_hz;
    fo.osc_beta_per_s = shape->osc_beta_per_s;
    fo.osc_ts_s = shape->osc_ts_s;
  }
  fo.terms = terms;
  fo.tau_min_s = tau_min;
  fo.tau_max_s = tau_max;
  fo.tb_min_s = tb_min_s;
  fo.tb_max_s = tb_max_s;
  fo.flicker_tau_hi_s = tau_max;
  fo.flicker_tau_lo_s = flicker_lo_s > 0.0 ? flicker_lo_s : flicker_tau_lo(tau_min, tau_max, pts);
  return fo;
}

// The fit of fit_options(...) to pts.
FitResult fit_terms(const Points& pts, std::uint32_t terms, double tau_min, double tau_max,
                    double tb_max_s = 0.0, const ModelParams* shape = nullptr,
                    double white_filter_s = 0.0, double tb_min_s = 0.0,
                    double flicker_lo_s = 0.0, double k_fixed = 0.0) {
  const FitOptions fo = fit_options(pts, terms, tau_min, tau_max, tb_max_s, shape,
                                    white_filter_s, tb_min_s, flicker_lo_s, k_fixed);
  return fit(pts.data(), pts.size(), fo);
}

// ---------------------------------------------------------------- filters and checks

struct FilterRun {
  bool ok = false;
  double nis_mean = 0.0;
  double nis_flagged = 0.0;        // fraction of NisMonitor blocks outside the band
  double whiteness_flagged = 0.0;  // fraction of WhitenessMonitor blocks above the bound
  std::size_t states = 0;
  // Per sample, in single precision (the fw monitors read the innovations as float; a record
  // of 2^22 samples holds 16 MB per vector, not 32):
  std::vector<float> nu;        // normalised innovation (0 when not updated)
  std::vector<float> pred_rel;  // predicted measurement minus the known signal (empty unless asked)
};

constexpr std::size_t kStates = kModelMaxStates;
using Model = DiscreteModel<kStates>;

// A model as the node observes it: each sample the mean of the model over its interval
// (imu::discretize_averaged; node::discretize_pushed), so that the filters and the covariance
// check see the samples the AVAR formulas describe (a filtered white noise's point samples
// would have the wrong variance). Only white noise: no state at all.
bool discretize_params(const ModelParams& p, double ts, Model& d) {
  ContinuousModel<kStates> c;
  if (build_model(p, c) != ModelStatus::kOk) {
    return false;
  }
  return c.n_states == 0 ? discretize(c, ts, d) == ModelStatus::kOk
                         : discretize_averaged(c, ts, d) == ModelStatus::kOk;
}

// The stochastic part of a model: the deterministic terms (ramp, sinusoids) have no process
// noise, so a steady-state filter would never learn them; the analysis removes its own
// least-squares estimates of them from the record before filtering instead.
ModelParams stochastic_part(ModelParams p) {
  p.r = 0.0;
  p.sin_a = 0.0;
  p.sin_f0_hz = 0.0;
  p.sin2_a = 0.0;
  p.sin2_f0_hz = 0.0;
  p.sin_ts_s = 0.0;
  p.sin2_ts_s = 0.0;
  return p;
}

// Dense n x n helpers (row-major) for the intervals' covariances and the Riccati doubling.
using Dense = std::vector<double>;
Dense mul(const Dense& a, const Dense& b, std::size_t n, bool transpose_b = false) {
  Dense c(n * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < n; ++k) {
      const double aik = a[i * n + k];
      for (std::size_t j = 0; j < n; ++j) {
        c[i * n + j] += aik * (transpose_b ? b[j * n + k] : b[k * n + j]);
      }
    }
  }
  return c;
}
Dense transposed(const Dense& a, std::size_t n) {
  Dense t(n * n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      t[j * n + i] = a[i * n + j];
    }
  }
  return t;
}
// Gauss-Jordan inverse with partial pivoting; false if singular.
bool inverse(Dense a, std::size_t n, Dense& inv) {
  inv.assign(n * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    inv[i * n + i] = 1.0;
  }
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t piv = c;
    for (std::size_t r = c + 1; r < n; ++r) {
      piv = std::fabs(a[r * n + c]) > std::fabs(a[piv * n + c]) ? r : piv;
    }
    if (!(std::fabs(a[piv * n + c]) > 0.0)) {
      return false;
    }
    for (std::size_t j = 0; j < n; ++j) {
      std::swap(a[c * n + j], a[piv * n + j]);
      std::swap(inv[c * n + j], inv[piv * n + j]);
    }
    const double d = a[c * n + c];
    for (std::size_t j = 0; j < n; ++j) {
      a[c * n + j] /= d;
      inv[c * n + j] /= d;
    }
    for (std::size_t r = 0; r < n; ++r) {
      const double f = a[r * n + c];
      if (r == c || !(std::fabs(f) > 0.0)) {
        continue;
      }
      for (std::size_t j = 0; j < n; ++j) {
        a[r * n + j] -= f * a[c * n + j];
        inv[r * n + j] -= f * inv[c * n + j];
      }
    }
  }
  return true;
}

// ---------------------------------------------------------------- 95 % intervals

// Every nonzero parameter of m the ADEV sees, by name, as pointers into m.
std::vector<std::pair<std::string, double*>> free_params(ModelParams& m) {
  std::vector<std::pair<std::string, double*>> v;
  const auto add = [&v](const std::string& name, double& x) {
    if (std::fabs(x) > 0.0) {
      v.emplace_back(name, &x);
    }
  };
  add("n", m.n);
  add("n_filter_s", m.n_filter_s);
  add("q", m.q);
  for (std::size_t i = 0; i < m.n_gm; ++i) {
    add("gm" + std::to_string(i) + "_sb", m.gm[i].sb);
    add("gm" + std::to_string(i) + "_tb_s", m.gm[i].tb_s);
  }
  add("k", m.k);
  add("r", m.r);
  add("sin_a", m.sin_a);
  add("sin_f0_hz", m.sin_f0_hz);
  add("sin2_a", m.sin2_a);
  add("sin2_f0_hz", m.sin2_f0_hz);
  add("bi", m.bi);
  add("osc_sigma", m.osc_sigma);
  add("osc_f0_hz", m.osc_f0_hz);
  add("osc_beta_per_s", m.osc_beta_per_s);
  return v;
}

// The covariance of m's log-parameters from the ADEV residual over [tau_min, tau_max] (see
// ParamInterval): central differences of 1 % in each. cov empty: too few points or singular.
struct LogCov {
  std::vector<std::string> names;
  Dense cov;
};

// The ADEV fit's two log covariances: `scaled`, the residual's scale times (J^T J)^-1, which
// takes the model as right; `robust`, the heteroskedasticity and autocorrelation consistent
// sandwich (J^T J)^-1 S (J^T J)^-1, S = sum_l w_l sum_k g_k g_{k-l}^T over lags -L..L (Bartlett
// weights w_l = 1 - |l| / (L + 1)) of the points' scores g_k = z_k J_k (Newey and West, "A
// simple, positive semi-definite, heteroskedasticity and autocorrelation consistent covariance
// matrix", Econometrica 55(3), 1987; White, Econometrica 48(4), 1980). Where the model misses
// the data, the misses lie at the taus that carry a parameter's information and widen that
// parameter's interval, not the others': a term the report does not name leaves its power to
// N, B or K, whose intervals then hold the truth only by being as wide as that miss.
struct FitCov {
  LogCov scaled;
  LogCov robust;
};

// The weight of the lag-`lag` autocovariance in a Newey-West long-run sum over lags -L..L
// (Bartlett, L = lags), both signs of a lag > 0 counted: 1 at lag 0, 2 (1 - lag / (L + 1)).
double bartlett_weight(std::size_t lag, std::size_t lags) {
  return lag == 0 ? 1.0
                  : 2.0 * (1.0 - static_cast<double>(lag) / (static_cast<double>(lags) + 1.0));
}

// The sandwich of FitCov::robust from the points' Jacobian jac (in.size() x np, row-major), the
// unscaled (J^T J)^-1 and the residuals z at the points `in`; empty if not positive.
Dense hac_sandwich(const Dense& jac, const Dense& bread, const std::vector<double>& z,
                   const std::vector<std::size_t>& in, std::size_t np, std::size_t lags) {
  const std::size_t n = in.size();
  Dense meat(np * np, 0.0);
  for (std::size_t lag = 0; lag <= lags && lag < n; ++lag) {
    const double w = bartlett_weight(lag, lags);
    for (std::size_t k = lag; k < n; ++k) {
      const double zz = w * z[in[k]] * z[in[k - lag]];
      for (std::size_t a = 0; a < np; ++a) {
        for (std::size_t b = 0; b < np; ++b) {  // symmetric part of g_k g_{k-lag}^T
          meat[a * np + b] +=
              0.5 * zz * (jac[k * np + a] * jac[(k - lag) * np + b] +
                          jac[(k - lag) * np + a] * jac[k * np + b]);
        }
      }
    }
  }
  const double small_sample = static_cast<double>(n) / static_cast<double>(n - np);
  Dense out = mul(mul(bread, meat, np), bread, np);
  for (double& v : out) {
    v *= small_sample;
  }
  for (std::size_t j = 0; j < np; ++j) {
    if (!(out[j * np + j] > 0.0)) {
      return {};
    }
  }
  return out;
}

FitCov log_covariance(const Points& pts, const ModelParams& m, const Options& o, double tau_min,
                      double tau_max) {
  FitCov fc;
  LogCov& lc = fc.scaled;
  ModelParams w = m;
  const auto params = free_params(w);
  const std::size_t np = params.size();
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (pts[i].tau_s >= tau_min * (1.0 - 1e-9) && pts[i].tau_s <= tau_max * (1.0 + 1e-9)) {
      in.push_back(i);
    }
  }
  for (const auto& pr : params) {
    lc.names.push_back(pr.first);
  }
  fc.robust.names = lc.names;
  if (np == 0 || in.size() <= np) {
    return fc;
  }
  constexpr double kH = 0.01;
  Dense jac(in.size() * np, 0.0);
  for (std::size_t j = 0; j < np; ++j) {
    double& x = *params[j].second;
    const double x0 = x;
    x = x0 * std::exp(kH);
    const std::vector<double> zp = residual(pts, w, o, tau_min, tau_max).z;
    x = x0 * std::exp(-kH);
    const std::vector<double> zm = residual(pts, w, o, tau_min, tau_max).z;
    x = x0;
    for (std::size_t k = 0; k < in.size(); ++k) {
      jac[k * np + j] = (zp[in[k]] - zm[in[k]]) / (2.0 * kH);
    }
  }
  Dense f(np * np, 0.0);
  for (std::size_t a = 0; a < np; ++a) {
    for (std::size_t b = 0; b < np; ++b) {
      for (std::size_t k = 0; k < in.size(); ++k) {
        f[a * np + b] += jac[k * np + a] * jac[k * np + b];
      }
    }
  }
  Dense inv;
  if (!inverse(f, np, inv)) {
    return fc;
  }
  const Residual r0 = residual(pts, m, o, tau_min, tau_max);
  const double s2 = std::max(1.0, r0.cost / static_cast<double>(in.size() - np));
  // Neighbouring overlapping estimates are correlated, which J^T J counts as independent: the
  // variance is inflated by the long-run factor of the residual sequence, 1 + 2 sum_k w_k
  // rho_k over the taus (Newey-West, Bartlett weights w_k = 1 - k / (L + 1), L = one octave),
  // and by no less than the analysis's own allowance, cost_factor.
  constexpr std::size_t kLags = 12;
  double c0 = 0.0;
  for (const std::size_t i : in) {
    c0 += r0.z[i] * r0.z[i];
  }
  double long_run = 1.0;
  for (std::size_t lag = 1; lag <= kLags && lag < in.size() && c0 > 0.0; ++lag) {
    double ck = 0.0;
    for (std::size_t k = lag; k < in.size(); ++k) {
      ck += r0.z[in[k]] * r0.z[in[k - lag]];
    }
    long_run += bartlett_weight(lag, kLags) * ck / c0;
  }
  fc.robust.cov = hac_sandwich(jac, inv, r0.z, in, np, kLags);
  const double inflate = std::max(o.cost_factor, long_run) * s2;
  for (double& v : inv) {
    v *= inflate;
  }
  for (std::size_t j = 0; j < np; ++j) {
    if (!(inv[j * np + j] > 0.0)) {
      return fc;
    }
  }
  lc.cov = std::move(inv);
  return fc;
}

// The Cramer-Rao bound of m's stochastic log-parameters on a record of t_rec_s seconds
// sampled every ts: the inverse of the Whittle approximation of a stationary Gaussian record's
// Fisher information, I_ij = T int d_i(f) d_j(f) df over [1 / T, 1 / (2 Ts)], d_i = d ln S /
// d ln p_i, S the model's one-sided PSD (term_psd: the deterministic terms, regressors, have
// none, and their parameters, which S does not see, are left out). No unbiased estimator of
// p_i, however it reads the record, has sd(ln p_i) below sqrt((I^-1)_ii): with K alone,
// sd(ln K) = 1 / sqrt(2 n) (n chi-square(1) readings of K^2); beside white noise N it is
// 1.07 sqrt(tau_d / T), tau_d = sqrt(3) N / K where the walk's AVAR meets the white noise's.
// Whittle, "Estimation and information in stationary time series", Ark. Mat. 2 (1953);
// Percival and Walden, "Spectral Analysis for Physical Applications" (1993).
// Names as free_params'; cov empty if the information is singular.
LogCov whittle_covariance(const ModelParams& m, double ts, double t_rec_s) {
  LogCov lc;
  const double f_lo = 1.0 / t_rec_s;
  const double f_hi = 0.5 / ts;
  if (!(f_hi > 4.0 * f_lo)) {
    return lc;
  }
  std::vector<double> f;  // 64 per decade, and finer across the oscillation's band
  const double step = std::log(10.0) / 64.0;
  const auto n_log = static_cast<int>(std::ceil(std::log(f_hi / f_lo) / step));
  f.reserve(static_cast<std::size_t>(n_log) + 1 + 321);  // + f_hi and the band's points
  for (int i = 0; i < n_log; ++i) {
    f.push_back(f_lo * std::exp(step * i));
  }
  f.push_back(f_hi);
  if (m.osc_sigma > 0.0 && m.osc_beta_per_s > 0.0) {
    for (int i = -160; i <= 160; ++i) {  // sinh(-8 .. 8): the band's core and its tails
      const double x = m.osc_f0_hz + m.osc_beta_per_s / (2.0 * kPi) * std::sinh(0.05 * i);
      if (x > f_lo && x < f_hi) {
        f.push_back(x);
      }
    }
    std::sort(f.begin(), f.end());
  }
  ModelParams w = m;
  const auto ln_psd = [&w, ts](double fq) {
    double s = 0.0;
    for (const TermInfo& t : kTermTable) {
      for (std::size_t i = 0; i < t.max_instances; ++i) {
        s += term_psd(w, t.kind, i, fq, ts);
      }
    }
    return std::log(s);
  };
  constexpr double kH = 1e-3;
  std::vector<std::vector<double>> d;  // d[j][k]: parameter j at frequency k
  for (const auto& [name, x] : free_params(w)) {
    const double x0 = *x;
    std::vector<double> dj(f.size());
    for (std::size_t k = 0; k < f.size(); ++k) {
      *x = x0 * std::exp(kH);
      const double up = ln_psd(f[k]);
      *x = x0 * std::exp(-kH);
      dj[k] = (up - ln_psd(f[k])) / (2.0 * kH);
      *x = x0;
    }
    if (std::any_of(dj.begin(), dj.end(), [](double v) { return std::fabs(v) > 0.0; })) {
      lc.names.push_back(name);
      d.push_back(std::move(dj));
    }
  }
  const std::size_t np = d.size();
  if (np == 0) {
    return lc;
  }
  Dense info(np * np, 0.0);
  for (std::size_t k = 0; k + 1 < f.size(); ++k) {
    const double width = 0.5 * (f[k + 1] - f[k]) * t_rec_s;  // trapezoid, T df
    for (std::size_t a = 0; a < np; ++a) {
      for (std::size_t b = 0; b < np; ++b) {
        info[a * np + b] += width * (d[a][k] * d[b][k] + d[a][k + 1] * d[b][k + 1]);
      }
    }
  }
  Dense inv;
  if (std::isfinite(std::accumulate(info.begin(), info.end(), 0.0)) &&
      inverse(info, np, inv)) {
    lc.cov = std::move(inv);
  }
  return lc;
}

// iv (a positive value's 95 % interval) widened to hold `floor` too, when both are determined.
ParamInterval no_narrower_than(ParamInterval iv, const ParamInterval& floor) {
  const auto determined = [](const ParamInterval& x) {
    return x.lo > 0.0 && std::isfinite(x.hi);
  };
  if (determined(iv) && determined(floor)) {
    iv.lo = std::min(iv.lo, floor.lo);
    iv.hi = std::max(iv.hi, floor.hi);
  }
  return iv;
}

// The 95 % interval of `value` = exp(sum_i a_i ln p_i) (times a constant) from the log
// covariance; [0, inf) (or (-inf, 0] for a negative value) when a parameter is not in it.
ParamInterval log_interval(const LogCov& lc, const std::string& name, double value,
                           const std::vector<std::pair<std::string, double>>& comb) {
  ParamInterval iv{name, 0.0, std::numeric_limits<double>::infinity()};
  const std::size_t np = lc.names.size();
  std::vector<double> a(np, 0.0);
  bool all = !lc.cov.empty();
  for (const auto& [pname, coef] : comb) {
    const auto it = std::find(lc.names.begin(), lc.names.end(), pname);
    all = all && it != lc.names.end();
    if (it != lc.names.end()) {
      a[static_cast<std::size_t>(it - lc.names.begin())] = coef;
    }
  }
  if (all) {
    double var = 0.0;
    for (std::size_t i = 0; i < np; ++i) {
      for (std::size_t j = 0; j < np; ++j) {
        var += a[i] * lc.cov[i * np + j] * a[j];
      }
    }
    const double sd = std::sqrt(std::max(var, 0.0));
    iv.lo = value * std::exp(-1.96 * sd);
    iv.hi = value * std::exp(1.96 * sd);
  }
  if (value < 0.0) {  // value exp(-+1.96 sd) runs downwards: swap; undetermined: (-inf, 0]
    iv = all ? ParamInterval{name, iv.hi, iv.lo}
             : ParamInterval{name, -std::numeric_limits<double>::infinity(), 0.0};
  }
  return iv;
}


// The index of m's GM whose Tb is closest to tb_s (in log).
std::size_t gm_index(const ModelParams& m, double tb_s) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < m.n_gm; ++i) {
    if (std::fabs(std::log(m.gm[i].tb_s / tb_s)) < std::fabs(std::log(m.gm[best].tb_s / tb_s))) {
      best = i;
    }
  }
  return best;
}

// iv (the 95 % interval of a positive value, from log_interval) widened to no less than
// value exp(+-1.96 sd_ln_floor).
ParamInterval with_log_sd_floor(const ParamInterval& iv, double value, double sd_ln_floor) {
  if (!(value > 0.0) || !(sd_ln_floor > 0.0)) {
    return iv;
  }
  return no_narrower_than(iv, ParamInterval{iv.name, value * std::exp(-1.96 * sd_ln_floor),
                                            value * std::exp(1.96 * sd_ln_floor)});
}

// The standard deviation of ln sigma when sigma^2 is a stationary process's variance estimated
// from a record of t_rec_s seconds: var(sigma^2 hat) = (2 / T) integral R(t)^2 dt (Bendat and
// Piersol, "Random Data", 4th ed., sec. 8.2), so sd(ln sigma) = sqrt(integral R^2 / (2 T)) /
// sigma^2. A GM, R = sigma^2 exp(-|t| / Tb): integral R^2 = sigma^4 Tb, sd = sqrt(Tb / (2 T)).
// A narrowband oscillation, R = sigma^2 exp(-beta |t|) cos(2 pi f0 t), beta << 2 pi f0:
// integral R^2 = sigma^4 / (2 beta), sd = 1 / (2 sqrt(beta T)). The ADEV fit's covariance
// cannot see this limit: its points' EDF assume power-law noise, for which a record holds as
// many independent samples of the process as it holds of the ADEV's averages.
double process_sd_ln_sigma(double corr_integral_s, double t_rec_s) {
  return t_rec_s > 0.0 && corr_integral_s > 0.0 ? std::sqrt(corr_integral_s / (2.0 * t_rec_s))
                                                : 0.0;
}

// The ADEV fit's log covariances and the record's Cramer-Rao bound (whittle_covariance): an
// interval is the fit's scaled one, no narrower than its robust one (for a parameter the
// spectrum does not see, a ramp's or a sinusoid's, that is all) or the bound's.
struct IntervalSources {
  FitCov fit;
  LogCov crb;
};

ParamInterval fit_interval(const IntervalSources& c, const std::string& name, double value,
                           const std::vector<std::pair<std::string, double>>& comb) {
  return no_narrower_than(log_interval(c.fit.scaled, name, value, comb),
                          log_interval(c.fit.robust, name, value, comb));
}

ParamInterval interval(const IntervalSources& c, const std::string& name, double value,
                       const std::vector<std::pair<std::string, double>>& comb) {
  return no_narrower_than(fit_interval(c, name, value, comb),
                          log_interval(c.crb, name, value, comb));
}

// A GM's sigma = sqrt(Sb Tb / 2) and Tb intervals (GM `g` of the log covariance), named
// `prefix` + "sigma" and `prefix` + "tb_s"; sigma's no narrower than its record allows.
void gm_intervals(const IntervalSources& c, const ModelParams& m, std::size_t g,
                  const std::string& prefix, double t_rec_s, std::vector<ParamInterval>& out) {
  const std::string sb = "gm" + std::to_string(g) + "_sb";
  const std::string tb = "gm" + std::to_string(g) + "_tb_s";
  const double sigma = std::sqrt(m.gm[g].sb * m.gm[g].tb_s / 2.0);
  out.push_back(with_log_sd_floor(interval(c, prefix + "sigma", sigma, {{sb, 0.5}, {tb, 0.5}}),
                                  sigma, process_sd_ln_sigma(m.gm[g].tb_s, t_rec_s)));
  out.push_back(interval(c, prefix + "tb_s", m.gm[g].tb_s, {{tb, 1.0}}));
}

// A parameter whose 95 % interval spans more than two decades (in magnitude; or is not finite)
// is not determined by the record.
constexpr double kDeterminedSpan = 100.0;
bool determined(const ParamInterval& iv) {
  const double lo = std::min(std::fabs(iv.lo), std::fabs(iv.hi));
  const double hi = std::max(std::fabs(iv.lo), std::fabs(iv.hi));
  return hi <= kDeterminedSpan * lo;
}

// Each effect's 95 % intervals and the model after's white noise and first GM (see
// ParamInterval), from the points the error after is scored on. A parameter the record does
// not determine (determined()) gets a note.
void attach_intervals(const Points& pts, const Options& o, double ts, double tau_max,
                      Report& out) {
  const ModelParams& m = out.model_after;
  const double t_rec_s = static_cast<double>(out.samples) * ts;
  const IntervalSources lc{log_covariance(pts, m, o, ts, tau_max),
                           whittle_covariance(m, ts, t_rec_s)};
  out.model_after_ci95.clear();
  out.model_after_ci95.push_back(interval(lc, "n", m.n, {{"n", 1.0}}));
  if (m.n_gm > 0) {
    gm_intervals(lc, m, 0, "gm_", t_rec_s, out.model_after_ci95);
  }
  for (Effect& e : out.effects) {
    std::vector<ParamInterval>& c = e.ci95;
    c.clear();
    if (e.type == "quantization") {
      c.push_back(interval(lc, "q", e.q, {{"q", 1.0}}));
    } else if (e.type == "rate_random_walk") {
      c.push_back(interval(lc, "k", e.k, {{"k", 1.0}}));
    } else if (e.type == "ramp") {
      c.push_back(fit_interval(lc, "r", e.r, {{"r", 1.0}}));
    } else if (e.type == "bias_instability") {
      c.push_back(interval(lc, "b", e.b, {{"bi", 1.0}}));
    } else if (e.type == "sinusoid") {
      const bool first = std::fabs(e.freq_hz - m.sin_f0_hz) <= std::fabs(e.freq_hz - m.sin2_f0_hz);
      const std::string w = first ? "sin" : "sin2";
      c.push_back(fit_interval(lc, "amplitude", e.amplitude, {{w + "_a", 1.0}}));
      c.push_back(fit_interval(lc, "freq_hz", e.freq_hz, {{w + "_f0_hz", 1.0}}));
    } else if (e.type == "oscillation") {
      c.push_back(with_log_sd_floor(
          interval(lc, "sigma", e.amplitude, {{"osc_sigma", 1.0}}), e.amplitude,
          process_sd_ln_sigma(m.osc_beta_per_s > 0.0 ? 0.5 / m.osc_beta_per_s : 0.0, t_rec_s)));
      c.push_back(interval(lc, "freq_hz", e.freq_hz, {{"osc_f0_hz", 1.0}}));
      c.push_back(interval(lc, "bandwidth_hz", e.bandwidth_hz, {{"osc_beta_per_s", 1.0}}));
    } else if (e.type == "gauss_markov" && m.n_gm > 0) {
      gm_intervals(lc, m, gm_index(m, e.tb_s), "", t_rec_s, c);
    } else if (e.type == "bias_step" && e.statistic > 0.0) {
      // statistic: the size's |z| (its standard error is |size| / |z|)
      const double half = 1.96 * std::fabs(e.size) / e.statistic;
      c.push_back(ParamInterval{"size", e.size - half, e.size + half});
      c.push_back(ParamInterval{"time_s", e.time_lo_s, e.time_hi_s});
    }
    for (const ParamInterval& iv : c) {
      if (e.type != "bias_step" && !determined(iv)) {
        out.notes.push_back(e.type + " " + iv.name + ": not determined by this record (95 % "
                            "interval " + fmt("%.3g", iv.lo) + " to " + fmt("%.3g", iv.hi) +
                            "; a longer record narrows it)");
      }
    }
  }
}

// Steady-state predicted covariance X = Phi X Phi' - Phi X H' (R + H X H')^-1 H X Phi' + Q by
// the structure-preserving doubling algorithm (Chu, Fan, Lin, Wang, "Structure-preserving
// algorithms for periodic discrete-time algebraic Riccati equations", Int. J. Control 77(8),
// 2004): A0 = Phi', G0 = H' H / R, H0 = Q; A+ = A W^-1 A, G+ = G + A W^-1 G A',
// H+ = H + A' H W^-1 A with W = I + G H; H_k -> X quadratically.
bool steady_state_covariance(const Model& d, std::size_t n, double r, Dense& x) {
  Dense a(n * n);
  Dense g(n * n);
  Dense h(n * n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      a[i * n + j] = d.phi(j, i);
      g[i * n + j] = d.h(0, i) * d.h(0, j) / r;
      h[i * n + j] = d.qd(i, j);
    }
  }
  for (int it = 0; it < 80; ++it) {
    Dense w = mul(g, h, n);
    for (std::size_t i = 0; i < n; ++i) {
      w[i * n + i] += 1.0;
    }
    Dense wi;
    if (!inverse(w, n, wi)) {
      return false;
    }
    const Dense at = transposed(a, n);
    const Dense wia = mul(wi, a, n);                    // W^-1 A
    const Dense a1 = mul(a, wia, n);                    // A W^-1 A
    const Dense g1 = mul(mul(a, mul(wi, g, n), n), at, n);  // A W^-1 G A'
    const Dense h1 = mul(mul(at, h, n), wia, n);        // A' H W^-1 A
    double change = 0.0;
    double scale = 0.0;
    for (std::size_t i = 0; i < n * n; ++i) {
      g[i] += g1[i];
      h[i] += h1[i];
      change = std::max(change, std::fabs(h1[i]));
      scale = std::max(scale, std::fabs(h[i]));
      a[i] = a1[i];
    }
    if (!std::isfinite(scale)) {
      return false;
    }
    if (change <= 1e-13 * scale) {
      x = h;
      return true;
    }
  }
  return false;
}

// A model matrix's first n x n entries, row-major.
template <typename M>
Dense to_dense(const M& m, std::size_t n) {
  Dense out(n * n);
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = 0; b < n; ++b) {
      out[a * n + b] = m(a, b);
    }
  }
  return out;
}

// The steady-state gain k = P H' / s and innovation variance s = H P H' + r from the
// steady-state covariance p (n x n, row-major).
double steady_gain(const Model& d, const Dense& p, double r, std::vector<double>& k) {
  const std::size_t n = d.n_states;
  k.assign(n, 0.0);
  double s = r;
  for (std::size_t i = 0; i < n; ++i) {
    double ph = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      ph += p[i * n + j] * d.h(0, j);
    }
    k[i] = ph;
    s += d.h(0, i) * ph;
  }
  for (auto& v : k) {
    v /= s;
  }
  return s;
}

// The fw residual monitors over the normalised innovations of the updates: the fractions of
// their blocks that fail the NIS and the whiteness test.
void monitor_fractions(const std::vector<std::uint8_t>* skip, FilterRun& out) {
  const std::vector<float>& nu = out.nu;
  NisMonitor nis;
  WhitenessMonitor<4> white;
  if (nis.configure(1000, 0.99) == MonitorStatus::kOk &&
      white.configure(1000, 0.95) == MonitorStatus::kOk) {
    for (std::size_t i = 0; i < nu.size(); ++i) {
      if (skip == nullptr || (*skip)[i] == 0) {
        nis.push(nu[i]);
        white.push(nu[i]);
      }
    }
    out.nis_flagged = nis.blocks() > 0 ? static_cast<double>(nis.flagged_blocks()) /
                                             static_cast<double>(nis.blocks())
                                       : 0.0;
    out.whiteness_flagged = white.blocks() > 0 ? static_cast<double>(white.flagged_blocks()) /
                                                     static_cast<double>(white.blocks())
                                               : 0.0;
  }
}

// The bias filter of model p over y (known signal `known`), with the steady-state gain of its
// stochastic part (the deterministic terms must already be removed from y): x = Phi x,
// e = y - known - H x, x += K e on the samples not skipped. Its innovations are those of the
// time-varying Kalman filter once that has converged (a few of the slowest correlation times);
// the steady gain costs O(n^2) per sample instead of O(n^3).
FilterRun run_filter(const ModelParams& p_full, double ts, const std::vector<double>& y,
                     double known, const std::vector<std::uint8_t>* skip, bool want_pred) {
  FilterRun out;
  out.nu.assign(y.size(), 0.0F);
  if (want_pred) {
    out.pred_rel.assign(y.size(), 0.0F);
  }
  Model d;
  if (!discretize_params(stochastic_part(p_full), ts, d)) {
    return out;
  }
  const std::size_t n = d.n_states;
  out.states = n > 0 ? n - 1 : 0;  // the model's states, without the sample mean
  const double r = d.r_filter();
  Dense x;
  if (!(r > 0.0) || (n > 0 && !steady_state_covariance(d, n, r, x))) {
    return out;
  }
  std::vector<double> k;
  const double s = steady_gain(d, x, r, k);
  std::vector<double> st(n, 0.0);
  std::vector<double> tmp(n, 0.0);
  double nis_sum = 0.0;
  std::size_t updates = 0;
  // The first samples run the time-varying filter from the model's P0 (the initial bias is
  // unknown; a steady gain from x = 0 would see it as a burst of large innovations), then the
  // steady gain takes over.
  const std::size_t burn_in = std::min<std::size_t>(y.size(), 4096);
  Dense pk = to_dense(d.p0, n);
  const Dense phi = to_dense(d.phi, n);
  const Dense q = to_dense(d.qd, n);
  for (std::size_t i = 0; i < y.size(); ++i) {
    double hx = 0.0;
    for (std::size_t a = 0; a < n; ++a) {
      double v = 0.0;
      for (std::size_t b = 0; b < n; ++b) {
        v += d.phi(a, b) * st[b];
      }
      tmp[a] = v;
      hx += d.h(0, a) * v;
    }
    st.swap(tmp);
    if (want_pred) {
      out.pred_rel[i] = static_cast<float>(hx);
    }
    const bool tv = i < burn_in;
    double s_i = s;
    if (tv) {  // P = Phi P Phi' + Q, gain from it
      pk = mul(mul(phi, pk, n), phi, n, true);
      for (std::size_t a = 0; a < n * n; ++a) {
        pk[a] += q[a];
      }
      s_i = r;
      for (std::size_t a = 0; a < n; ++a) {
        double ph = 0.0;
        for (std::size_t b = 0; b < n; ++b) {
          ph += pk[a * n + b] * d.h(0, b);
        }
        tmp[a] = ph;  // P H'
        s_i += d.h(0, a) * ph;
      }
    }
    if (skip == nullptr || (*skip)[i] == 0) {
      const double e = y[i] - known - hx;
      for (std::size_t a = 0; a < n; ++a) {
        st[a] += (tv ? tmp[a] / s_i : k[a]) * e;
      }
      if (tv) {  // P = P - (P H')(P H')' / s
        for (std::size_t a = 0; a < n; ++a) {
          for (std::size_t b = 0; b < n; ++b) {
            pk[a * n + b] -= tmp[a] * tmp[b] / s_i;
          }
        }
      }
      out.nu[i] = static_cast<float>(e / std::sqrt(s_i));
      nis_sum += e * e / s_i;
      ++updates;
    } else {
      // not updated; its innovation is still recorded (the outlier check reads it)
      out.nu[i] = static_cast<float>((y[i] - known - hx) / std::sqrt(s_i));
    }
  }
  out.nis_mean = updates > 0 ? nis_sum / static_cast<double>(updates) : 0.0;
  out.ok = true;
  monitor_fractions(skip, out);
  return out;
}

// The example's covariance check (T_avg = 10 s, T_int = 20 s, up to 1000 overlapping windows): robust
// std of the integral at T_int over the predicted std. 0 when the record is too short.
double covariance_ratio(const ModelParams& p, double ts, const std::vector<double>& y) {
  const auto n_avg = static_cast<std::size_t>(std::lround(10.0 / ts));
  const auto n_int = static_cast<std::size_t>(std::lround(20.0 / ts));
  const std::size_t span = n_avg + n_int;
  if (y.size() < span + 100) {
    return 0.0;
  }
  std::size_t windows = std::min<std::size_t>(1000, y.size() - span + 1);
  const std::size_t stride = windows > 1 ? (y.size() - span) / (windows - 1) : 1;
  Model d;
  if (!discretize_params(stochastic_part(p), ts, d)) {
    return 0.0;
  }
  std::vector<double> sd(n_int);
  if (predict_integral_std(d, n_avg, n_int, sd.data()) != ModelStatus::kOk || !(sd.back() > 0.0)) {
    return 0.0;
  }
  std::vector<double> traj(n_int);
  std::vector<double> ends(windows);
  for (std::size_t w = 0; w < windows; ++w) {
    integrate_window(y.data() + w * stride, n_avg, n_int, ts, traj.data());
    ends[w] = traj.back();
  }
  return robust_std(ends.data(), windows) / sd.back();
}

// The median of v (destroyed): robust_std's rule, in single precision.
double median_inplace(std::vector<float>& v) {
  if (v.empty()) {
    return 0.0;
  }
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  const double upper = static_cast<double>(*mid);
  if (v.size() % 2 == 1) {
    return upper;
  }
  return 0.5 * (static_cast<double>(*std::max_element(v.begin(), mid)) + upper);
}

double robust_scale(const std::vector<double>& v) {
  std::vector<double> c(v);
  return robust_std(c.data(), c.size());
}

// The spread of normalised innovations for the outlier gate, on the record's lattice of
// normalised step `step` (0: none). On a coarse lattice most innovations are a fraction of a step
// and the MAD sees only them (a sample one step away would be an "outlier"): the spread is the
// larger of the MAD's and the standard deviation of the innovations within 6 of those spreads
// (the MAD's, or half a step if larger) of their median, which the gross outliers do not reach.
// A sample's distance is then taken less half a step, the most the rounding can add to it.
struct GateScale {
  double scale = 0.0;
  double half_step = 0.0;
  [[nodiscard]] double z(float nu) const {
    const double a = std::max(std::fabs(static_cast<double>(nu)) - half_step, 0.0);
    return scale > 0.0 ? std::copysign(a / scale, static_cast<double>(nu)) : 0.0;
  }
};

GateScale lattice_gate_scale(const std::vector<float>& nu, double step) {
  GateScale g;
  g.half_step = 0.5 * step;
  // 1.4826 x the median absolute deviation on one float copy (a 2^22-sample record's is 16 MB),
  // its median also the centre of the clipped std
  std::vector<float> c(nu);
  const double med = median_inplace(c);
  for (float& x : c) {
    x = static_cast<float>(std::fabs(static_cast<double>(x) - med));
  }
  const double mad = 1.4826 * median_inplace(c);
  const double clip = 6.0 * std::max(mad, g.half_step);
  double sum = 0.0;
  double n = 0.0;
  for (const float x : nu) {
    const double d = static_cast<double>(x) - med;
    if (std::fabs(d) <= clip) {
      sum += d * d;
      n += 1.0;
    }
  }
  g.scale = std::max(mad, n > 1.0 ? std::sqrt(sum / (n - 1.0)) : 0.0);
  return g;
}

// Which part's gate spread judges sample i of a record whose white noise changes level at
// sample `split`, located to within `guard` samples: 0 (before) or 1 (after); within the guard
// the louder part's, as either level may hold there (else the louder part's first samples
// would be "outliers" of the quieter one). Without a change (split at the end) always 0.
int gate_part(std::size_t i, std::size_t split, std::size_t guard, double scale_a,
              double scale_b) {
  if (i + guard >= split && i < split + guard) {
    return scale_a >= scale_b ? 0 : 1;
  }
  return i < split ? 0 : 1;
}

// The known signal of the bias filters, as the node sets it (host_sim/node: init_samples): the
// mean of the first 1000 samples. The record's mean would be wrong for a record that drifts:
// its first innovations would be the whole drift (seen as outliers).
double initial_level(const std::vector<double>& y) {
  const std::size_t n = std::min<std::size_t>(1000, y.size());
  double s = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    s += y[i];
  }
  return n > 0 ? s / static_cast<double>(n) : 0.0;
}

// ---------------------------------------------------------------- sinusoid estimation

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) {
    s += x;
  }
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}


// |DTFT|^2 of Hann-windowed x at frequency f (cycles per sample).
// Golden-section search for the minimum of a unimodal f on [lo, hi]: `iterations` steps, one
// evaluation each (the interior point kept is reused); the final bracket's midpoint.
template <typename F>
double golden_min(const F& f, double lo, double hi, int iterations) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = hi - g * (hi - lo);
  double d = lo + g * (hi - lo);
  double fc = f(c);
  double fd = f(d);
  for (int it = 0; it < iterations; ++it) {
    if (fc < fd) {
      hi = d;
      d = c;
      fd = fc;
      c = hi - g * (hi - lo);
      fc = f(c);
    } else {
      lo = c;
      c = d;
      fc = fd;
      d = lo + g * (hi - lo);
      fd = f(d);
    }
  }
  return 0.5 * (lo + hi);
}

double dtft_power(const std::vector<double>& xw, double f) {
  double re = 0.0;
  double im = 0.0;
  const double w = 2.0 * kPi * f;
  // Recurrence for cos/sin (Goertzel-like), exact enough over 1e6 steps in double.
  const std::complex<double> step(std::cos(w), -std::sin(w));
  std::complex<double> ph(1.0, 0.0);
  for (std::size_t i = 0; i < xw.size(); ++i) {
    re += xw[i] * ph.real();
    im += xw[i] * ph.imag();
    ph *= step;
    if ((i & 1023U) == 1023U) {
      ph /= std::abs(ph);
    }
  }
  return re * re + im * im;
}

struct SineFit {
  bool ok = false;
  double f_hz = 0.0;
  double a = 0.0;      // cos coefficient
  double b = 0.0;      // sin coefficient
  double amplitude = 0.0;
};

// Least-squares a cos(wt) + b sin(wt) + c at f over the full-rate record.
SineFit sine_ls(const std::vector<double>& y, double ts, double f_hz) {
  double s[3][3] = {};
  double r[3] = {};
  const double w = 2.0 * kPi * f_hz * ts;
  // cos/sin by rotation, renormalised every 1024 steps (phase error ~1e-13 over 1e6 steps).
  const std::complex<double> step(std::cos(w), std::sin(w));
  std::complex<double> ph(1.0, 0.0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double g[3] = {ph.real(), ph.imag(), 1.0};
    ph *= step;
    if ((i & 1023U) == 1023U) {
      const double a = w * static_cast<double>(i + 1);
      ph = std::complex<double>(std::cos(a), std::sin(a));
    }
    for (int a = 0; a < 3; ++a) {
      r[a] += g[a] * y[i];
      for (int b = 0; b < 3; ++b) {
        s[a][b] += g[a] * g[b];
      }
    }
  }
  // Cramer's rule on the 3x3 normal equations.
  const auto det3 = [](const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  const double d = det3(s);
  SineFit out;
  if (!(std::fabs(d) > 0.0)) {
    return out;
  }
  double coef[2];
  for (int c = 0; c < 2; ++c) {
    double m[3][3];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        m[i][j] = j == c ? r[i] : s[i][j];
      }
    }
    coef[c] = det3(m) / d;
  }
  out.ok = true;
  out.f_hz = f_hz;
  out.a = coef[0];
  out.b = coef[1];
  out.amplitude = std::hypot(coef[0], coef[1]);
  return out;
}

// Is a line at f one sinusoid over the whole record? A narrowband random process whose band is
// narrower than the spectrum's resolution shows a line too, but its amplitude and phase wander
// with its correlation time. The record is cut into kSegments; in each, the least-squares
// complex amplitude at f (sine_ls, referred to the record's time origin) and, for the noise
// beside the line, at f +- 8.5 and +- 16.5 bins of a segment (1 / T_seg: beyond a band a few
// bins wide, within a few per cent of f where f T_seg >= 24). Under one sinusoid in
// locally flat noise, X = sum_k |c_k - mean c|^2 / s2 (s2 the off-line coefficients' variance
// per component) is chi2 with 2 (kSegments - 1) degrees of freedom. Leakage of the line into
// the off-line bins and band power there raise s2 (the test errs towards the sinusoid).
// Untested (tested = false) when a segment holds under 24 periods. Cost: 5 passes over y.
struct SineCoherence {
  bool tested = false;
  double stat = 0.0;
  double thr = 0.0;
};
SineCoherence sine_coherence(const std::vector<double>& y, double ts, double f_hz, double alpha) {
  constexpr std::size_t kSegments = 16;
  SineCoherence out;
  const std::size_t len = y.size() / kSegments;
  const double t_seg = static_cast<double>(len) * ts;
  if (len < 64 || f_hz * t_seg < 24.0) {
    return out;
  }
  constexpr double kOff[4] = {-16.5, -8.5, 8.5, 16.5};
  std::vector<double> seg(len);
  std::complex<double> c[kSegments];
  std::complex<double> mean(0.0, 0.0);
  double s2 = 0.0;
  std::size_t n_off = 0;
  for (std::size_t k = 0; k < kSegments; ++k) {
    std::copy(y.begin() + static_cast<std::ptrdiff_t>(k * len),
              y.begin() + static_cast<std::ptrdiff_t>((k + 1) * len), seg.begin());
    const SineFit at = sine_ls(seg, ts, f_hz);
    if (!at.ok) {
      return out;
    }
    const double t0 = static_cast<double>(k * len) * ts;
    c[k] = std::complex<double>(at.a, -at.b) * std::polar(1.0, -2.0 * kPi * f_hz * t0);
    mean += c[k] / static_cast<double>(kSegments);
    for (const double off : kOff) {
      const SineFit beside = sine_ls(seg, ts, f_hz + off / t_seg);
      if (beside.ok) {
        s2 += 0.5 * (beside.a * beside.a + beside.b * beside.b);
        ++n_off;
      }
    }
  }
  if (n_off == 0 || !(s2 > 0.0)) {
    return out;
  }
  s2 /= static_cast<double>(n_off);
  for (const auto& ck : c) {
    out.stat += std::norm(ck - mean) / s2;
  }
  out.thr = chi2_quantile(1.0 - alpha, 2.0 * static_cast<double>(kSegments - 1));
  out.tested = true;
  return out;
}

// The Hann-windowed record and its spectrum, computed once per channel: the record the
// sinusoid search reads does not change in the greedy loop, and every bump's search window is
// a slice of the one full-rate spectrum.
struct SpectrumCache {
  std::size_t dec = 0;
  std::vector<double> x;                // Hann-windowed block means
  std::vector<double> power;  // |DFT|^2 of x zero-padded to a power of two n, bins 0 .. n / 2
};

// Frequency near f_c (from the ADEV bump): periodogram of the Hann-windowed record in
// [f_c / 2, 2 f_c], parabolic then golden-section refinement of the DTFT peak, then the
// full-rate LS amplitude.
SineFit estimate_sinusoid(const std::vector<double>& y, double ts, double f_c,
                          SpectrumCache& cache) {
  const double fs = 1.0 / ts;
  // One full-rate spectrum serves every bump of every round: one FFT per channel instead of
  // one per decimation (the block means of a decimation saved samples, not time).
  const std::size_t dec = 1;
  const std::size_t nd = y.size() / dec;
  SineFit none;
  if (nd < 64) {
    return none;
  }
  if (cache.dec != dec) {
    cache.dec = dec;
    cache.x = block_means(y, dec);
    std::vector<double>& x = cache.x;
    const double mean = mean_of(x);
    for (std::size_t j = 0; j < nd; ++j) {
      const double w = 0.5 - 0.5 * std::cos(2.0 * kPi * static_cast<double>(j) /
                                            static_cast<double>(nd - 1));
      x[j] = (x[j] - mean) * w;
    }
    std::size_t n2 = 1;
    while (n2 < nd) {
      n2 <<= 1;
    }
    cache.power = real_fft_power(x, n2);
  }
  const std::vector<double>& x = cache.x;
  const std::vector<double>& power = cache.power;
  const std::size_t nfft = 2 * (power.size() - 1);
  const double fsd = fs / static_cast<double>(dec);  // decimated rate
  const double df = fsd / static_cast<double>(nfft);
  const auto k_lo = static_cast<std::size_t>(std::max(1.0, std::floor(0.5 * f_c / df)));
  const auto k_hi = static_cast<std::size_t>(std::min(static_cast<double>(nfft) / 2.0 - 1.0,
                                                      std::ceil(2.0 * f_c / df)));
  if (k_hi <= k_lo) {
    return none;
  }
  std::size_t kbest = k_lo;
  double pbest = -1.0;
  for (std::size_t k = k_lo; k <= k_hi; ++k) {
    const double p = power[k];
    if (p > pbest) {
      pbest = p;
      kbest = k;
    }
  }
  // Parabolic interpolation of the log power over the peak bin and its neighbours (Hann),
  // then golden section of the DTFT power on +-0.3 bin around it (unimodal there).
  double centre = static_cast<double>(kbest);
  if (kbest > k_lo && kbest < k_hi) {
    const double l0 = std::log(power[kbest - 1] + 1e-300);
    const double l1 = std::log(power[kbest] + 1e-300);
    const double l2 = std::log(power[kbest + 1] + 1e-300);
    const double den = l0 - 2.0 * l1 + l2;
    if (den < 0.0) {
      centre += std::clamp(0.5 * (l0 - l2) / den, -0.5, 0.5);
    }
  }
  // 0.6 bin * 0.618^16 = 2.8e-4 bin
  const double f_norm =
      golden_min([&](double f) { return -dtft_power(x, f); }, (centre - 0.3) * df / fsd,
                 (centre + 0.3) * df / fsd, 16);
  const double f_hz = f_norm * fsd;
  return sine_ls(y, ts, f_hz);
}

std::vector<double> minus_sine(const std::vector<double>& y, double ts, const SineFit& s) {
  std::vector<double> out(y.size());
  const double w = 2.0 * kPi * s.f_hz * ts;
  const std::complex<double> step(std::cos(w), std::sin(w));
  std::complex<double> ph(1.0, 0.0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    out[i] = y[i] - s.a * ph.real() - s.b * ph.imag();
    ph *= step;
    if ((i & 1023U) == 1023U) {
      const double a = w * static_cast<double>(i + 1);
      ph = std::complex<double>(std::cos(a), std::sin(a));
    }
  }
  return out;
}

// A narrowband oscillation near f_c (from an ADEV bump): Welch PSD of the record (Hann
// segments of 2^k samples, half overlap, >= 32 segments), peak of the excess over the local
// floor (the median of the flanks 3-8 half-widths away) between f_c / 3 and 3 f_c, its
// half-power points. A band only: the half-power width must be >= 6 bins (a Hann-windowed line
// is ~1.5 bins wide, 3 after the 3-bin smoothing) and the peak at least twice the floor, with
// both half-power points inside the window. Those give the start; centre and width are then
// fitted (fit_lorentzian): read off the half-power points of the noisy PSD, the width comes out
// 15-50 % narrow (the highest bin overstates the peak, the flanks hold the band's own tails),
// and the ADEV fit's shape below 1 / f0 with it. The ADEV fit then sizes sigma^2.
struct OscFit {
  bool ok = false;
  double f0_hz = 0.0;
  double beta_per_s = 0.0;
};

// The Welch PSD of a record, 3-bin smoothed (computed once per record version: every bump's
// estimate reads it).
struct WelchPsd {
  double df = 0.0;
  std::vector<double> sm;  // smoothed, per bin
};

WelchPsd welch_psd(const std::vector<double>& y, double ts) {
  WelchPsd out;
  const double fs = 1.0 / ts;
  std::size_t len = 1024;
  while (2 * len * 32 <= y.size() && len < 65536) {
    len *= 2;
  }
  if (y.size() < 8 * len) {
    return out;
  }
  const double df = fs / static_cast<double>(len);
  std::vector<double> psd(len / 2 + 1, 0.0);
  std::vector<double> win(len);
  for (std::size_t j = 0; j < len; ++j) {
    win[j] = 0.5 - 0.5 * std::cos(2.0 * kPi * static_cast<double>(j) / static_cast<double>(len));
  }
  std::vector<std::complex<double>> a(len);
  std::size_t segs = 0;
  for (std::size_t start = 0; start + len <= y.size(); start += len / 2) {
    double mean = 0.0;
    for (std::size_t j = 0; j < len; ++j) {
      mean += y[start + j];
    }
    mean /= static_cast<double>(len);
    for (std::size_t j = 0; j < len; ++j) {
      a[j] = (y[start + j] - mean) * win[j];
    }
    fft(a);
    for (std::size_t k = 0; k < psd.size(); ++k) {
      psd[k] += std::norm(a[k]);
    }
    ++segs;
  }
  // 3-bin smoothing (the averaged periodogram still scatters ~1/sqrt(segments) per bin).
  out.df = df;
  out.sm.assign(psd.size(), 0.0);
  for (std::size_t k = 1; k + 1 < psd.size(); ++k) {
    out.sm[k] = (psd[k - 1] + psd[k] + psd[k + 1]) / (3.0 * static_cast<double>(segs));
  }
  return out;
}

// The expected smoothed Welch PSD of a band (f0_hz, half-width gamma_hz at half power) at bin
// k: a damped oscillation's spectrum (a Lorentzian at +f0 and its mirror at -f0) seen through
// the Hann window's power response and the 3-bin smoothing (a kernel on a quarter-bin grid).
struct BandShape {
  static constexpr int kTaps = 41;  // offsets -5 .. 5 bins
  static constexpr int kMid = 20;   // the tap at offset 0
  std::array<double, kTaps> kernel{};
  BandShape() {
    std::array<double, kTaps> hann{};
    for (int i = 0; i < kTaps; ++i) {
      const double d = 0.25 * (i - kMid);
      const auto sinc = [](double x) {
        return std::fabs(x) < 1e-12 ? 1.0 : std::sin(kPi * x) / (kPi * x);
      };
      const double w = 0.5 * sinc(d) + 0.25 * sinc(d - 1.0) + 0.25 * sinc(d + 1.0);
      hann[static_cast<std::size_t>(i)] = std::fabs(d) <= 4.0 ? w * w : 0.0;
    }
    double sum = 0.0;
    for (int i = 0; i < kTaps; ++i) {  // the 3-bin box: offsets -1, 0, +1 (4 quarter-bins)
      double v = 0.0;
      for (const int j : {-4, 0, 4}) {
        const int k = i + j;
        v += k >= 0 && k < kTaps ? hann[static_cast<std::size_t>(k)] : 0.0;
      }
      kernel[static_cast<std::size_t>(i)] = v;
      sum += v;
    }
    for (double& v : kernel) {
      v /= sum;
    }
  }
  [[nodiscard]] double at(double f_hz, double df, double f0_hz, double gamma_hz) const {
    double v = 0.0;
    for (int i = 0; i < kTaps; ++i) {
      const double f = f_hz - 0.25 * (i - kMid) * df;
      const double u = (f - f0_hz) / gamma_hz;
      const double m = (f + f0_hz) / gamma_hz;
      v += kernel[static_cast<std::size_t>(i)] * (1.0 / (1.0 + u * u) + 1.0 / (1.0 + m * m));
    }
    return v;
  }
};

// Least squares of the smoothed PSD over [k0, k1] against floor + slope + P x band, weighted by
// 1 / (the start's model)^2 (an averaged periodogram scatters in proportion to its level): a
// grid over the centre and the half-width (moved while the best lies on its edge, at most three
// times), then narrowed three times around the best. Returns false (out unchanged) when the
// best stays on the edge or P is not positive.
bool fit_lorentzian(const WelchPsd& w_psd, std::size_t k0, std::size_t k1, double floor_level,
                    double peak, OscFit& fit) {
  static const BandShape shape;
  const double df = w_psd.df;
  const std::size_t stride = std::max<std::size_t>(1, (k1 - k0) / 400);
  std::vector<std::size_t> bins;
  for (std::size_t k = k0; k <= k1; k += stride) {
    bins.push_back(k);
  }
  const double kc = 0.5 * static_cast<double>(k0 + k1);
  const double g_start = 0.5 * fit.beta_per_s / kPi;  // half-width at half power, Hz
  std::vector<double> wt(bins.size());
  for (std::size_t i = 0; i < bins.size(); ++i) {
    const double m =
        floor_level + peak * shape.at(static_cast<double>(bins[i]) * df, df, fit.f0_hz, g_start);
    wt[i] = 1.0 / (m * m);
  }
  std::vector<double> band(bins.size());
  // Weighted residual sum of squares at (f0, gamma), the linear terms solved; +inf if P <= 0.
  const auto rss = [&](double f0, double g) {
    Mat<double, 3, 3> a{};
    Mat<double, 3, 1> b{};
    for (std::size_t i = 0; i < bins.size(); ++i) {
      band[i] = shape.at(static_cast<double>(bins[i]) * df, df, f0, g);
      const std::array<double, 3> x{1.0, static_cast<double>(bins[i]) - kc, band[i]};
      for (std::size_t r = 0; r < 3; ++r) {
        for (std::size_t c = 0; c < 3; ++c) {
          a(r, c) += wt[i] * x[r] * x[c];
        }
        b(r, 0) += wt[i] * x[r] * w_psd.sm[bins[i]];
      }
    }
    Mat<double, 3, 1> sol{};
    if (!lu_solve(a, b, sol) || !(sol(2, 0) > 0.0)) {
      return std::numeric_limits<double>::infinity();
    }
    double e = 0.0;
    for (std::size_t i = 0; i < bins.size(); ++i) {
      const double r = w_psd.sm[bins[i]] - sol(0, 0) -
                       sol(1, 0) * (static_cast<double>(bins[i]) - kc) - sol(2, 0) * band[i];
      e += wt[i] * r * r;
    }
    return e;
  };
  double f0 = fit.f0_hz;
  double ln_g = std::log(g_start);
  double f_span = g_start;        // the centre's grid: f0 +- f_span
  double g_span = std::log(2.0);  // the half-width's: ln g +- g_span
  constexpr int kHalf = 6;        // 13 x 13 points per grid
  // One grid around (f0, ln_g), moved to its best point; false if no point has P > 0, else
  // on_edge tells whether the best lay on the grid's edge.
  const auto step = [&](bool& on_edge) {
    double best = std::numeric_limits<double>::infinity();
    int bi = 0;
    int bj = 0;
    for (int i = -kHalf; i <= kHalf; ++i) {
      for (int j = -kHalf; j <= kHalf; ++j) {
        const double e = rss(f0 + f_span * i / kHalf, std::exp(ln_g + g_span * j / kHalf));
        if (e < best) {
          best = e;
          bi = i;
          bj = j;
        }
      }
    }
    f0 += f_span * bi / kHalf;
    ln_g += g_span * bj / kHalf;
    on_edge = std::abs(bi) == kHalf || std::abs(bj) == kHalf;
    return std::isfinite(best);
  };
  bool on_edge = true;
  for (int moves = 0; on_edge; ++moves) {  // the coarse grid, moved at most 3 times
    if (moves > 3 || !step(on_edge)) {
      return false;
    }
  }
  for (int round = 0; round < 3; ++round) {
    f_span *= 2.0 / kHalf;
    g_span *= 2.0 / kHalf;
    if (!step(on_edge)) {
      return false;
    }
  }
  fit.f0_hz = f0;
  fit.beta_per_s = 2.0 * kPi * std::exp(ln_g);
  return true;
}

OscFit estimate_oscillation(const WelchPsd& w_psd, double f_c) {
  OscFit none;
  const std::vector<double>& sm = w_psd.sm;
  const double df = w_psd.df;
  if (sm.size() < 64) {
    return none;
  }
  const auto k_lo = static_cast<std::size_t>(std::max(2.0, std::floor(f_c / 3.0 / df)));
  const auto k_hi = static_cast<std::size_t>(
      std::min(static_cast<double>(sm.size()) - 3.0, std::ceil(3.0 * f_c / df)));
  if (k_hi <= k_lo + 16) {
    return none;
  }
  const auto median_of = [&sm](std::size_t lo, std::size_t hi) {  // [lo, hi)
    std::vector<double> v(sm.begin() + static_cast<std::ptrdiff_t>(lo),
                          sm.begin() + static_cast<std::ptrdiff_t>(hi));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  double floor_level = median_of(k_lo, k_hi + 1);
  std::size_t kp = 0;
  std::size_t a_lo = 0;
  std::size_t a_hi = 0;
  for (int pass = 0; pass < 2; ++pass) {
    kp = k_lo;
    for (std::size_t k = k_lo; k <= k_hi; ++k) {
      kp = sm[k] > sm[kp] ? k : kp;
    }
    const double peak = sm[kp] - floor_level;
    if (!(peak > floor_level)) {
      return none;  // not twice the floor
    }
    a_lo = kp;
    while (a_lo > k_lo && sm[a_lo] - floor_level > 0.5 * peak) {
      --a_lo;
    }
    a_hi = kp;
    while (a_hi < k_hi && sm[a_hi] - floor_level > 0.5 * peak) {
      ++a_hi;
    }
    if (a_lo == k_lo || a_hi == k_hi) {
      return none;  // the peak is not inside the window
    }
    // Local floor from the flanks 3-8 half-widths from the peak.
    const std::size_t w = std::max<std::size_t>(2, (a_hi - a_lo) / 2);
    std::vector<double> flank;
    for (std::size_t k = k_lo; k <= k_hi; ++k) {
      const std::size_t d = k > kp ? k - kp : kp - k;
      if (d >= 3 * w && d <= 8 * w) {
        flank.push_back(sm[k]);
      }
    }
    if (flank.size() < 8) {
      return none;
    }
    std::nth_element(flank.begin(), flank.begin() + static_cast<std::ptrdiff_t>(flank.size() / 2),
                     flank.end());
    floor_level = flank[flank.size() / 2];
  }
  const double width = static_cast<double>(a_hi - a_lo);
  if (width < 6.0) {
    return none;  // a line, not a band: the sinusoid's business
  }
  double sw = 0.0;
  double swf = 0.0;
  for (std::size_t k = a_lo; k <= a_hi; ++k) {
    const double e = std::max(0.0, sm[k] - floor_level);
    sw += e;
    swf += e * static_cast<double>(k);
  }
  OscFit out;
  out.f0_hz = swf / sw * df;
  out.beta_per_s = kPi * width * df;
  // Underdamped only (a peak further from 0 Hz than its half-power width, beta / pi):
  // otherwise it is a GM's business.
  const auto underdamped = [](const OscFit& f) { return f.f0_hz > f.beta_per_s / kPi; };
  out.ok = sw > 0.0 && underdamped(out);
  if (out.ok) {
    const double reach = 8.0 * std::max(3.0, 0.5 * width);  // the flanks' outer edge
    const double lo = std::max(static_cast<double>(k_lo), static_cast<double>(kp) - reach);
    const double hi = std::min(static_cast<double>(k_hi), static_cast<double>(kp) + reach);
    fit_lorentzian(w_psd, static_cast<std::size_t>(lo), static_cast<std::size_t>(hi),
                   floor_level, sm[kp] - floor_level, out);
    out.ok = underdamped(out);
  }
  return out;
}

// A candidate term of the greedy ADEV search.
struct SineCand {
  SineFit fit;
  AdevSet adev;
  // A line of few periods (slow_line_stands): its 2 ln LR on the record's block means and the
  // level it passed; lr_thr = 0 for a line the ADEV's residual proposed.
  double lr = 0.0;
  double lr_thr = 0.0;
};
struct Cand {
  std::string type;
  std::uint32_t terms;
  ModelParams p;
  double cost;
  const SineCand* sine;  // the sinusoid candidate's estimate and ADEV, else null
};

struct LongTauInput {
  const std::vector<double>& y;
  double ts;
  double tb_max;
  bool ramp;
  const std::vector<std::uint64_t>& step_at;
  const ModelParams& cur;
  double cur_cost;
  double cost_thr;
  double lr_thr;  // the record likelihood's level: a line the model lacks must pass it
};

// See the call: among the long-tau candidates that pass the ADEV test, the one the record's
// likelihood prefers (AIC); `best` unchanged when fewer than two of them pass or it is another
// kind of term.
const Cand* long_tau_choice(const LongTauInput& in, const std::vector<Cand>& cands,
                            const Cand* best, std::vector<std::string>& notes, bool& line) {
  line = false;
  const auto passes = [&](const Cand& c) { return in.cur_cost - c.cost > in.cost_thr; };
  const Cand* bi = nullptr;
  const Cand* rw = nullptr;
  const Cand* gm = nullptr;
  for (const auto& c : cands) {
    if (!passes(c)) {
      continue;
    }
    bi = c.type == "bias_instability" ? &c : bi;
    rw = c.type == "rate_random_walk" ? &c : rw;
    // a second GM slow enough for the block means (the test's blocks: T / kRrwTestBlocks)
    const double block_s =
        static_cast<double>(in.y.size()) * in.ts / static_cast<double>(kRrwTestBlocks);
    if (c.type == "second_gm" && c.p.n_gm == 2 && c.p.gm[1].tb_s >= 2.0 * block_s) {
      gm = &c;
    }
  }
  const bool family = best == bi || best == rw || best == gm;
  if (!family || (bi != nullptr) + (rw != nullptr) + (gm != nullptr) < 2) {
    return best;
  }
  struct Scored {
    const Cand* c;
    double score;
    bool line;  // its score is the one beside a line the model does not hold yet
  };
  std::vector<Scored> scored;
  std::string what;
  // Each member scored as it is and, where the model has no ramp yet, beside a line when the
  // line passes the record likelihood's test beside it (then one parameter more): a ramp under
  // flicker is a walk's curve over the range as well, and flicker's long excursions beside an
  // unmodelled line would otherwise raise only the walk's likelihood. The line itself is left
  // to the search's next step.
  const auto score = [&](const Cand* c, const ModelParams& p, bool walk, double extra) {
    const auto loglik = [&](bool with_line) {
      const RrwLikelihoodTest t =
          test_rrw(in.y, in.ts, p, in.tb_max, with_line, in.step_at, kAuxBlocks, walk);
      return t.ok ? (walk ? t.h1.loglik : t.h0.loglik) : -std::numeric_limits<double>::infinity();
    };
    const double plain = loglik(in.ramp);
    const double lined = in.ramp ? plain : loglik(true);
    const bool needs_line = !in.ramp && 2.0 * (lined - plain) > in.lr_thr;
    const double ll = needs_line ? lined - 1.0 : plain;
    if (std::isfinite(ll)) {
      scored.push_back({c, ll - extra, needs_line});
    }
  };
  if (bi != nullptr) {
    ModelParams p = bi->p;
    p.k = 0.0;
    score(bi, p, false, 1.0);
  }
  if (rw != nullptr) {
    score(rw, in.cur, true, 1.0);
  }
  if (gm != nullptr) {
    score(gm, gm->p, false, 2.0);
  }
  bool best_scored = false;
  for (const auto& sc : scored) {
    best_scored = best_scored || sc.c == best;
  }
  if (scored.size() < 2 || !best_scored) {
    return best;  // the ADEV's choice stands where the record could not weigh it
  }
  const Scored* win = &scored[0];
  for (const auto& sc : scored) {
    what += (what.empty() ? "" : ", ") + sc.c->type + (sc.line ? " beside a line " : " ") +
            fmt("%.1f", sc.score);
    win = sc.score > win->score ? &sc : win;
  }
  notes.push_back("long-tau family by the record's likelihood (ln L less extra parameters): " +
                  what + ": " + win->c->type);
  line = win->line;
  return win->c;
}

// 2 (l(GMs + B) - l(GMs)) on the record's block means: the evidence for bias instability
// against the base family (test: the base test already run on the same record). B starts from
// the data's ADEV near T/100 as the flicker floor. 0 when it cannot be computed. with_bi, when
// given, receives the test whose H0 holds the fitted bias instability. means, when given: the
// block means test was run on (test_rrw_on_means), instead of y's.
double bias_instability_lr(const std::vector<double>& y, double ts, const ModelParams& base,
                           double tb_max, const std::vector<std::uint64_t>& step_at,
                           const AdevSet& adev, const RrwLikelihoodTest& test,
                           RrwLikelihoodTest* with_bi = nullptr,
                           const std::vector<double>* means = nullptr) {
  const double t_rec = static_cast<double>(y.size()) * ts;
  double b0 = 0.0;
  for (const auto& pt : adev.by_alpha[2]) {
    if (pt.tau_s <= t_rec / 100.0) {
      b0 = pt.adev / kFlickerAdevFactor;
    }
  }
  if (!(b0 > 0.0) || !test.ok) {
    return 0.0;
  }
  ModelParams p = base;
  p.bi = b0;
  p.bi_tau_hi_s = 0.1 * t_rec;
  p.bi_tau_lo_s = flicker_tau_lo(ts, p.bi_tau_hi_s, adev.by_alpha[2]);
  RrwLikelihoodTest t =
      means != nullptr
          ? test_rrw_on_means(*means, test.per_block, ts, p, tb_max, step_at, false)
          : test_rrw(y, ts, p, tb_max, false, step_at, kAuxBlocks, false);
  const double lr = t.ok ? std::max(0.0, 2.0 * (t.h0.loglik - test.h0.loglik)) : 0.0;
  if (with_bi != nullptr) {
    *with_bi = std::move(t);
  }
  return lr;
}

// Keeps the outliers whose after-model innovation also passes the gate (same threshold, the
// after innovations' spread on the record's lattice of normalised step `step`:
// lattice_gate_scale, each part's own before and after sample `split`, where the white noise's
// level changes, as in the gate: gate_part); the rest are dropped with a note.
void confirm_outliers(const FilterRun& fa, const std::vector<std::uint8_t>& skip,
                      const std::vector<std::pair<std::size_t, double>>& found, double alpha,
                      double ts, double step, std::size_t split, std::size_t guard,
                      Report& out) {
  if (found.empty() || !fa.ok) {
    return;
  }
  const auto part = [&](std::size_t a, std::size_t b) {
    std::vector<float> used;
    used.reserve(b - a);
    for (std::size_t i = a; i < b; ++i) {
      if (skip[i] == 0) {
        used.push_back(fa.nu[i]);
      }
    }
    return lattice_gate_scale(used, step);
  };
  const std::size_t n = fa.nu.size();
  const GateScale scale_a = part(0, std::min(split, n));
  const GateScale scale_b = split < n ? part(split, n) : scale_a;
  const double thr =
      two_sided_normal_threshold(alpha / static_cast<double>(fa.nu.size()));
  std::vector<double> times;
  std::uint64_t count = 0;
  double max_abs = 0.0;
  for (const auto& f : found) {
    const int k = gate_part(f.first, split, guard, scale_a.scale, scale_b.scale);
    const double z = std::fabs((k == 0 ? scale_a : scale_b).z(fa.nu[f.first]));
    if (z > thr) {
      ++count;
      max_abs = std::max(max_abs, z);
      if (times.size() < 100) {
        times.push_back(static_cast<double>(f.first) * ts);
      }
    }
  }
  for (auto it = out.effects.begin(); it != out.effects.end(); ++it) {
    if (it->type != "outliers") {
      continue;
    }
    if (count < it->count) {
      out.notes.push_back(std::to_string(it->count - count) + " of " + std::to_string(it->count) +
                          " outliers of the before-model's innovations are not outliers of the "
                          "after-model's (|nu| <= " + fmt("%.2f", thr) + " robust sigma)");
    }
    if (count == 0) {
      out.effects.erase(it);
    } else {
      it->count = count;
      it->times_s = times;
      it->statistic = max_abs;
    }
    break;
  }
}

// ---------------------------------------------------------------- error statistics

void fill_errors(const Points& pts, const ModelParams& m, const Options& o, double ts,
                 double tau_max, ErrorStats& e) {
  const Residual all = residual(pts, m, o, ts, tau_max);
  const Residual ex = residual(pts, m, o, ts, std::min(o.example_tau_max_s, tau_max));
  e.adev_rms_rel = all.check.rms_rel;
  e.adev_max_rel = all.check.max_rel;
  e.n_taus = all.check.n_checked;
  e.cost = all.cost;
  e.tau_min_s = ts;
  e.tau_max_s = 0.0;
  for (const auto& p : pts) {
    if (p.tau_s <= tau_max * (1.0 + 1e-9)) {
      e.tau_max_s = std::max(e.tau_max_s, p.tau_s);
    }
  }
  e.example_rms_rel = ex.check.rms_rel;
  e.example_max_rel = ex.check.max_rel;
  e.example_tau_max_s = std::min(o.example_tau_max_s, e.tau_max_s);
}

// ---------------------------------------------------------------- the after-model

// Least-squares slope of y against time [unit/s].
double ls_slope(const std::vector<double>& y, double ts) {
  const double n = static_cast<double>(y.size());
  double sty = 0.0;
  double stt = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double t = static_cast<double>(i) - 0.5 * (n - 1.0);
    sty += t * y[i];
    stt += t * t;
  }
  return stt > 0.0 ? sty / stt / ts : 0.0;
}

void remove_line(std::vector<double>& y, double ts) {
  const double slope = ls_slope(y, ts) * ts;  // per sample
  const double mid = 0.5 * (static_cast<double>(y.size()) - 1.0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    y[i] -= slope * (static_cast<double>(i) - mid);
  }
}

struct AfterContext {
  const Options& o;
  double ts;
  double tau_max;
  double tb_max;
  const AdevSet& clean;    // the cleaned record's ADEV (errors are measured against it)
  const AdevSet& fit_set;  // the same without the sinusoids found (the linear terms' fit)
  const ErrorStats& before;
  double cost_thr;         // the ADEV cost drop a term must make (the search's test)
  double white_filter_s;   // the sensor's output filter on the white noise (0: none)
  // Terms the record's likelihood requires (kFitRrw, kFitFlicker when its 2 ln LR beside the
  // model's other terms passed the test): the ADEV never-worse rule does not remove them, and a
  // residual run where one dominates does not un-name it; a model worse on the ADEV is kept and
  // said.
  std::uint32_t required = 0;
  double required_lr = 0.0;     // the walk's 2 ln LR
  double required_bi_lr = 0.0;  // bias instability's 2 ln LR beside the model's other terms
  double gm_tb_fixed_s = 0.0;   // fit_after's one GM at this Tb (0: searched)
};

// The 2 ln LR by which the record requires the term of FitTerm bit `bit` (0: not tested).
double required_lr_of(const AfterContext& c, std::uint32_t bit) {
  return bit == kFitRrw ? c.required_lr : bit == kFitFlicker ? c.required_bi_lr : 0.0;
}

// "rate_random_walk (2 ln LR = 33.7), bias_instability (2 ln LR = 12.0)": the required bits
// of `bits`.
std::string required_list(const AfterContext& c, std::uint32_t bits) {
  std::string s;
  for (const std::uint32_t bit : {kFitRrw, kFitFlicker}) {
    if ((bits & c.required & bit) != 0U) {
      s += (s.empty() ? "" : ", ") + std::string(term_by_fit_bit(bit)->name) + " (2 ln LR = " +
           fmt("%.1f", required_lr_of(c, bit)) + ")";
    }
  }
  return s;
}

struct AfterChoice {
  std::uint32_t terms = 0;
  ModelParams p{};
  ErrorStats e{};
  bool ok = false;
};

bool not_worse(const ErrorStats& e, const ErrorStats& before) {
  return e.adev_rms_rel <= before.adev_rms_rel && e.adev_max_rel <= before.adev_max_rel;
}

// a is preferred to b: not worse than before where b is worse; both not worse: the lower
// sum(z^2) over [Ts, T/10] (the statistical fit); both worse: the lower max error.
bool preferred(const AfterChoice& a, const AfterChoice& b, const ErrorStats& before) {
  if (!a.ok) {
    return false;
  }
  if (!b.ok) {
    return true;
  }
  const bool ok_a = not_worse(a.e, before);
  const bool ok_b = not_worse(b.e, before);
  if (ok_a != ok_b) {
    return ok_a;
  }
  return ok_a ? a.e.cost < b.e.cost : a.e.adev_max_rel < b.e.adev_max_rel;
}

// The joint fit of `terms` (sinusoids from `sines`, or none), two weightings: the 1/var weights
// of the EDF and a cap of 100 on the EDF (close to a relative least-squares fit; the 1/var
// weights let the very precise shortest taus decide alone when the model cannot follow the data
// everywhere); the preferred one (below).
AfterChoice fit_after(const AfterContext& c, std::uint32_t terms, const ModelParams& sines,
                      bool keep_sines) {
  AfterChoice best;
  const AdevSet& base = keep_sines ? c.fit_set : c.clean;
  const Points pts = in_range(points_for_model(base, sines), c.tau_max);
  // The GM bounded (peak and an octave inside [Ts, T/10], as in the search) or as free as the
  // before-model's (10 x its 100 s range): a before-model whose GM sits at its bound can follow
  // a long-tau rise that the bounded GM leaves to K alone.
  const double wide = std::max(c.tb_max, 10.0 * std::min(c.o.example_tau_max_s, c.tau_max));
  // First the variants that keep every term; only if none does, those where the joint fit
  // zeroed a term (the term then leaves the set: its effect is not reported).
  for (const bool allow_zeroed : {false, true}) {
    for (const double tb_max : {c.tb_max, wide}) {
      for (const double cap : {0.0, 100.0}) {
        FitOptions fo;
        fo.terms = terms;
        fo.tau_min_s = c.ts;
        fo.tau_max_s = c.tau_max;
        fo.tb_max_s = c.gm_tb_fixed_s > 0.0 ? c.gm_tb_fixed_s * (1.0 + 1e-9) : tb_max;
        fo.tb_min_s = c.gm_tb_fixed_s > 0.0 ? c.gm_tb_fixed_s * (1.0 - 1e-9) : 0.0;
        fo.white_filter_s = c.white_filter_s;
        fo.edf_cap = cap;
        fo.flicker_tau_hi_s = c.tau_max;
        fo.flicker_tau_lo_s = flicker_tau_lo(c.ts, c.tau_max, pts);
        fo.osc_f0_hz = sines.osc_f0_hz;
        fo.osc_beta_per_s = sines.osc_beta_per_s;
        fo.osc_ts_s = sines.osc_ts_s;
        const FitResult f = fit(pts.data(), pts.size(), fo);
        if (f.status != FitStatus::kOk) {
          continue;
        }
        const ModelParams& q = f.params;
        std::uint32_t zeroed = 0;
        zeroed |= (terms & kFitQuantization) != 0U && !(q.q > 0.0) ? kFitQuantization : 0U;
        zeroed |= (terms & kFitRrw) != 0U && !(q.k > 0.0) ? kFitRrw : 0U;
        zeroed |= (terms & kFitRamp) != 0U && !(q.r > 0.0) ? kFitRamp : 0U;
        zeroed |= (terms & kFitFlicker) != 0U && !(q.bi > 0.0) ? kFitFlicker : 0U;
        zeroed |= (terms & kFitOscillation) != 0U && !(q.osc_sigma > 0.0) ? kFitOscillation : 0U;
        if (zeroed != 0U && !allow_zeroed) {
          continue;
        }
        AfterChoice ch;
        ch.terms = terms & ~zeroed;
        ch.p = keep_sines ? with_sines(q, sines) : q;
        fill_errors(points_for_model(c.clean, ch.p), ch.p, c.o, c.ts, c.tau_max, ch.e);
        ch.ok = true;
        if (preferred(ch, best, c.before)) {
          best = ch;
        }
      }
    }
    if (best.ok) {
      break;
    }
  }
  return best;
}

// A model after that misses the ADEV by more than this RMS of |model / data - 1| over [Ts, T/10]
// (on average a factor of two) describes none of the record: robust_after refits it. So does one
// that lies above the data by more than kGrossAboveFactor beyond their 68 % interval at any of
// those taus: what a model lacks only adds variance, so a model that far above the data holds
// what the record does not (a GM bent onto a wandering line, white noise traded to 0 for it).
constexpr double kGrossMisfitRms = 1.0;
constexpr double kGrossAboveFactor = 2.0;

// ln(model ADEV / data ADEV) beyond the data's 68 % interval on either side (0 inside it; -1e300
// where the model or the interval is empty).
double ci_excess(const ModelParams& q, const AdevPoint& pt) {
  const double m = std::sqrt(std::max(model_avar(q, pt.tau_s), 0.0));
  if (!(m > 0.0) || !(pt.ci_lo > 0.0) || !(pt.ci_hi > 0.0)) {
    return -1e300;
  }
  return m > pt.ci_hi ? std::log(m / pt.ci_hi) : m < pt.ci_lo ? std::log(m / pt.ci_lo) : 0.0;
}

// True where q lies above the data by more than exp(log_margin) beyond their 68 % interval at
// some point of pts.
bool lies_above(const Points& pts, const ModelParams& q, double log_margin) {
  return std::any_of(pts.begin(), pts.end(),
                     [&](const AdevPoint& pt) { return ci_excess(q, pt) > log_margin; });
}

bool lies_far_above(const AfterContext& c, const ModelParams& p) {
  return lies_above(in_range(points_for_model(c.clean, p), c.tau_max), p,
                    std::log(kGrossAboveFactor));
}

// One start of robust_after's consensus: fit kept, keep the taus the model does not lie more
// than exp(margin) below (at most 8 rounds; EDF capped at 10 for the first, then at 100), then,
// while the model lies that far above the data anywhere in `all`, drop the datum highest above
// it and refit. False when a fit fails or fewer than min_kept taus agree; q and kept are the
// start's model and taus.
template <class FitOn>
bool envelope_from_start(const Points& all, std::size_t min_kept, double margin,
                         const FitOn& fit_on, Points& kept, ModelParams& q) {
  constexpr double kConsensusEdfCap = 10.0;  // the start: every tau one vote
  constexpr double kRefineEdfCap = 100.0;    // then the shortest taus (the white noise) weigh more
  bool ok = false;
  for (int round = 0; round < 8; ++round) {
    ok = fit_on(kept, q, round == 0 ? kConsensusEdfCap : kRefineEdfCap);
    if (!ok) {
      break;
    }
    Points next;
    for (const AdevPoint& pt : all) {
      if (ci_excess(q, pt) >= -margin) {
        next.push_back(pt);
      }
    }
    const bool same = next.size() == kept.size() &&
                      std::equal(next.begin(), next.end(), kept.begin(),
                                 [](const AdevPoint& x, const AdevPoint& y) { return x.af == y.af; });
    ok = next.size() >= min_kept;
    if (!ok || same) {
      break;
    }
    kept = std::move(next);
  }
  // The lower envelope: while the model lies above the data anywhere, the datum highest above
  // the model leaves the set (inside the margin it still pulls the fit up: a line's leakage
  // next to the shortest taus, where the white noise is read) and the rest are refitted.
  while (ok && kept.size() > min_kept && lies_above(all, q, margin)) {
    kept.erase(std::min_element(kept.begin(), kept.end(),
                                [&](const AdevPoint& x, const AdevPoint& y) {
                                  return ci_excess(q, x) < ci_excess(q, y);
                                }));
    ok = fit_on(kept, q, kRefineEdfCap);
  }
  return ok && !lies_above(all, q, margin);
}

// White noise and one GM refitted to the lower envelope of the ADEV. A disturbance no term of the
// analysis is (a line whose amplitude or frequency wanders: a motor's vibration, a chirp) can
// hold the shortest taus, where the EDF are ~1e5; the least-squares fit then bends the GM onto
// that bump, and its tail lies 5 to 15 times above the data at every longer tau, the bias and
// the white noise lost with it. An effect the model lacks only adds variance: the data may lie
// above the model, never below it. So, as a consensus fit in the manner of RANSAC (Fischler and
// Bolles 1981): from each start (the first two taus, where the white noise is read, with every
// tau from one of the ADEV's octaves on), fit, leave out the taus where the data lie above the
// model by more than 25 % beyond their 68 % interval, refit on the rest, until the set holds
// (at most 8 rounds; EDF capped at 10 for the start, every tau one vote, then at 100 as the
// after-model's second weighting does, so that the shortest taus hold the white noise while
// the leakage of a disturbance at the middle taus does not). A model that lies above the data by
// as much anywhere is refused; of the rest, the one that agrees with the most taus wins (then
// the lower cost). At least a third of the taus, and 8, must agree. The taus left out are the
// report's unexplained runs; the others are returned in `agreed` (the intervals are read there).
struct EnvelopeFit {
  AfterChoice choice;  // ok = false: no start gave a model that stays under the data
  Points agreed;       // the taus it describes
};

EnvelopeFit robust_after(const AfterContext& c, const AfterChoice& chosen) {
  EnvelopeFit best;
  const bool sines = chosen.p.sin_a > 0.0;
  const Points all = in_range(points_for_model(sines ? c.fit_set : c.clean, chosen.p), c.tau_max);
  const std::size_t min_kept = std::max<std::size_t>(8, all.size() / 3);
  const double margin = std::log(1.25);
  const auto fit_on = [&](const Points& pts, ModelParams& q, double edf_cap) {
    FitOptions fo = fit_options(pts, kFitWhite | kFitGm1, c.ts, c.tau_max, c.tb_max, nullptr,
                                c.white_filter_s);
    fo.edf_cap = edf_cap;
    const FitResult f = fit(pts.data(), pts.size(), fo);
    if (f.status != FitStatus::kOk) {
      return false;
    }
    q = sines ? with_sines(f.params, chosen.p) : f.params;
    return true;
  };
  std::vector<Points> starts;
  double octave_s = 0.0;  // the first tau of the last start
  for (std::size_t i = 2; i + min_kept <= all.size(); ++i) {
    if (all[i].tau_s >= 2.0 * octave_s * (1.0 - 1e-9)) {
      octave_s = all[i].tau_s;
      Points st(all.begin(), all.begin() + 2);
      st.insert(st.end(), all.begin() + static_cast<std::ptrdiff_t>(i), all.end());
      starts.push_back(std::move(st));
    }
  }
  for (Points kept : starts) {
    ModelParams q{};
    if (!envelope_from_start(all, min_kept, margin, fit_on, kept, q)) {
      continue;
    }
    AfterChoice ch;
    ch.terms = kFitWhite | kFitGm1;
    ch.p = q;
    fill_errors(points_for_model(c.clean, q), q, c.o, c.ts, c.tau_max, ch.e);
    ch.ok = true;
    if (kept.size() > best.agreed.size() ||
        (kept.size() == best.agreed.size() && ch.e.cost < best.choice.e.cost)) {
      best = EnvelopeFit{ch, std::move(kept)};
    }
  }
  return best;
}

// The white noise N and bias instability B of model_after are read off the shortest taus, where
// the record may hold more than the model says: quantization the search did not keep (its AVAR
// 3 Q^2 / tau^2 and N's trade there), flicker below the bank's lower end (flicker_tau_lo: the
// bank stops short of Ts, and the white noise takes the floor's AVAR there), flicker made as a
// sampled 1/f sequence (its first taus hold more than the floor: without_sampled_flicker_excess),
// a white level that changes part way (the model's N is the record's average) and an
// oscillation seen through the other sampling (point samples or a sensor's averages over each
// sample period: oscillation_candidates keeps the cheaper, and the two readings of one band
// differ in sigma by (pi f0 Ts / sin(pi f0 Ts)), 3.5 % at fs / 7, where the ADEV often cannot
// tell them apart). An interval that knows only the chosen model's scatter misses the truth
// wherever that model is one of several the data allow. Each such reading that the ADEV does not
// rule out (its fit's cost at most cost_thr above the model's own refit, same points and
// options) moves N, B and the oscillation's sigma by the ratio of its fit to that refit (a noise
// change: N by each part's white level, NoiseParts). long_tau_readings does the same for K.
struct AdevReading {
  std::string what;
  double n_ratio = 1.0;
  double b_ratio = 1.0;
  double n_sd_ln = 0.0;  // the reading's own scatter (sd of ln N), added to the interval's ends
  double osc_ratio = 1.0;
  double k_ratio = 1.0;
};

// The AVAR at tau = Ts of the record before and after a change of the white noise's level, and
// of the whole (half the mean squared first difference; pairs with a gap left out, and those
// within one of the change's blocks of its place, which the block grid only locates), with the
// pairs each part holds. found: the record has such a change.
struct NoiseParts {
  bool found = false;
  double avar_before = 0.0;
  double avar_after = 0.0;
  double avar_all = 0.0;
  double pairs_before = 0.0;
  double pairs_after = 0.0;
};

NoiseParts noise_parts(const std::vector<double>& y, const std::vector<std::uint8_t>& gap,
                       const NoiseLevelChange& nc) {
  NoiseParts p;
  if (!nc.found || nc.at < 2 || nc.at + 2 > y.size()) {
    return p;
  }
  double sum[2] = {0.0, 0.0};
  double pairs[2] = {0.0, 0.0};
  const std::size_t guard = nc.block_len;
  for (std::size_t i = 1; i < y.size(); ++i) {
    const bool near_change = i + guard >= nc.at && i < nc.at + guard;
    if (near_change || (!gap.empty() && (gap[i] != 0U || gap[i - 1] != 0U))) {
      continue;
    }
    const double d = y[i] - y[i - 1];
    const std::size_t part = i < nc.at ? 0 : 1;
    sum[part] += d * d;
    pairs[part] += 1.0;
  }
  if (!(pairs[0] > 0.0) || !(pairs[1] > 0.0)) {
    return p;
  }
  p.found = true;
  p.avar_before = 0.5 * sum[0] / pairs[0];
  p.avar_after = 0.5 * sum[1] / pairs[1];
  p.avar_all = 0.5 * (sum[0] + sum[1]) / (pairs[0] + pairs[1]);
  p.pairs_before = pairs[0];
  p.pairs_after = pairs[1];
  return p;
}

// pts with the excess of a sampled 1/f sequence of bias instability b over its floor
// (flicker_sampled_excess) taken off each point: the data as the model's bank would see them if
// the record's flicker were such a sequence. False (out untouched) for b = 0 or where the excess
// would take a point's whole AVAR.
bool without_sampled_flicker_excess(const Points& pts, double b, Points& out) {
  if (!(b > 0.0)) {
    return false;
  }
  Points p = pts;
  for (AdevPoint& pt : p) {
    const double avar = pt.avar - b * b * flicker_sampled_excess(pt.af);
    if (!(avar > 0.0)) {
      return false;
    }
    const double ratio = std::sqrt(avar / pt.avar);
    pt.avar = avar;
    pt.adev *= ratio;
    pt.ci_lo *= ratio;
    pt.ci_hi *= ratio;
  }
  out = std::move(p);
  return true;
}

// The points a reading of model m refits: the ADEV over [Ts, T/10] without the sinusoids m
// holds (the linear terms' fit set), else the cleaned record's.
Points reading_points(const AfterContext& c, const ModelParams& m) {
  return in_range(points_for_model(m.sin_a > 0.0 ? c.fit_set : c.clean, m), c.tau_max);
}

// The lower bound of a reading's GM search: the fastest of m's GMs less 1 % (0 without a GM:
// the fit's default, Ts).
double fastest_gm_tb_bound(const ModelParams& m) {
  double tb_lo = 0.0;
  for (std::size_t i = 0; i < m.n_gm; ++i) {
    tb_lo = i == 0 ? 0.99 * m.gm[i].tb_s : std::min(tb_lo, 0.99 * m.gm[i].tb_s);
  }
  return tb_lo;
}

std::vector<AdevReading> short_tau_readings(const AfterContext& c, std::uint32_t terms,
                                                const ModelParams& m, const NoiseParts& np) {
  std::vector<AdevReading> out;
  const Points pts = reading_points(c, m);
  // The GMs' correlation times held near the model's (the readings differ at the shortest taus)
  const double tb_lo = fastest_gm_tb_bound(m);
  double tb_hi = c.tb_max;
  for (std::size_t i = 0; i < m.n_gm; ++i) {
    tb_hi = i == 0 ? 1.01 * m.gm[i].tb_s : std::max(tb_hi, 1.01 * m.gm[i].tb_s);
  }
  // shape: m's, or another reading of its oscillation (its sampling)
  const auto refit = [&](std::uint32_t t, double flicker_lo_s, const Points& on,
                          double filter_s, const ModelParams* shape = nullptr) {
    return fit_terms(on, t, c.ts, c.tau_max, tb_hi, shape != nullptr ? shape : &m, filter_s,
                     tb_lo, flicker_lo_s);
  };
  const double lo_rule = flicker_tau_lo(c.ts, c.tau_max, pts);
  const FitResult base = refit(terms, lo_rule, pts, m.n_filter_s);
  if (base.status != FitStatus::kOk || !(base.params.n > 0.0)) {
    return out;
  }
  const auto add = [&](const char* what, const FitResult& f) {
    if (f.status == FitStatus::kOk && f.params.n > 0.0 && f.cost <= base.cost + c.cost_thr) {
      const bool b = base.params.bi > 0.0 && f.params.bi > 0.0;
      const bool osc = base.params.osc_sigma > 0.0 && f.params.osc_sigma > 0.0;
      out.push_back({what, f.params.n / base.params.n, b ? f.params.bi / base.params.bi : 1.0,
                     0.0, osc ? f.params.osc_sigma / base.params.osc_sigma : 1.0, 1.0});
    }
  };
  if ((terms & kFitQuantization) == 0U) {
    add("with quantization", refit(terms | kFitQuantization, lo_rule, pts, m.n_filter_s));
  }
  if (m.osc_sigma > 0.0) {
    ModelParams other = m;
    other.osc_ts_s = m.osc_ts_s > 0.0 ? 0.0 : c.ts;
    add(m.osc_ts_s > 0.0 ? "with the oscillation averaged over each sample period"
                         : "with the oscillation point-sampled",
        refit(terms, lo_rule, pts, m.n_filter_s, &other));
  }
  const double lo_ts = std::max(0.1 * c.ts, 1e-6 * c.tau_max);
  if ((terms & kFitFlicker) != 0U && lo_rule > 1.5 * c.ts) {
    // below Ts too, as far as the bank's decades reach (kMaxFlickerGm)
    add("with the flicker bank down to Ts / 10", refit(terms, lo_ts, pts, m.n_filter_s));
  }
  Points sampled;
  if ((terms & kFitFlicker) != 0U && without_sampled_flicker_excess(pts, m.bi, sampled)) {
    add("with the bias instability a sampled 1/f sequence",
        refit(terms, lo_ts, sampled, m.n_filter_s));
    if (m.n_filter_s > 0.0) {  // the excess falls off faster than white, as a filter's dip does
      add("with the bias instability a sampled 1/f sequence and no output filter",
          refit(terms, lo_ts, sampled, 0.0));
    }
  }
  // Each part's white AVAR at Ts: its AVAR less the model's other terms' there, against the
  // whole record's (the other terms dilute the change's std ratio on the first differences).
  ModelParams others = m;
  others.n = 0.0;
  const double white_all = np.avar_all - model_avar(others, c.ts);
  // A part's mean of squared first differences of white noise (an MA(1) of lag-1 correlation
  // -1/2) has var 3 AVAR^2 / pairs: sd(ln N) = sqrt(3 / pairs) / 2, in the ratio of the part's
  // AVAR to its white AVAR.
  const auto part = [&](const char* what, double avar, double pairs) {
    const double white = avar - model_avar(others, c.ts);
    if (white > 0.0 && pairs > 0.0) {
      out.push_back({what, std::sqrt(white / white_all), 1.0,
                     0.5 * std::sqrt(3.0 / pairs) * avar / white});
    }
  };
  if (np.found && white_all > 0.0) {
    part("before the white level changes", np.avar_before, np.pairs_before);
    part("after it", np.avar_after, np.pairs_after);
  }
  return out;
}

// The walk's K of model_after is read off the longest taus, where a GM near the fit's bound on
// the correlation times (tb_max, about T/40) makes much the same rise as the walk: the fit may
// place its GM elsewhere (Tb of a few seconds, or none) and leave that rise to the walk. On
// records of 1 and 2 h of a GM at Tb ~ T/40 beside a walk, K came out 1.3 to 1.7 x the truth
// with an interval that excluded it. The cost's profile over K: K held at 0.9, 0.8, .. x its
// value (0: no walk, unless the record's likelihood requires the walk: AfterContext::required)
// and the other terms refitted with one GM more (the only one, if the model has none;
// tb <= tb_max) while the cost stays within the 95 % level of the model's own refit
// (cost_factor x chi-square(1) at 0.95, the profile's bound for a 95 % interval, with the same
// allowance for the correlated taus as the covariance's); the lowest such K is the reading.
std::vector<AdevReading> long_tau_readings(const AfterContext& c, std::uint32_t terms,
                                           const ModelParams& m) {
  std::vector<AdevReading> out;
  if ((terms & kFitRrw) == 0U || !(m.k > 0.0) || !(c.tb_max > 0.0)) {
    return out;
  }
  const Points pts = reading_points(c, m);
  const double tb_lo = fastest_gm_tb_bound(m);
  const auto refit = [&](std::uint32_t t, double tb_hi, double k_fixed) {
    return fit_terms(pts, t, c.ts, c.tau_max, tb_hi, &m, m.n_filter_s, tb_lo, 0.0, k_fixed);
  };
  const FitResult base = refit(terms, c.tb_max, 0.0);
  if (base.status != FitStatus::kOk || !(base.params.k > 0.0)) {
    return out;
  }
  const std::uint32_t slow = terms | ((terms & kFitGm1) != 0U ? kFitGm2 : kFitGm1);
  constexpr int kSteps = 10;
  const int last = (c.required & kFitRrw) != 0U ? 1 : 0;
  const double allowed = c.o.cost_factor * chi2_quantile(0.95, 1.0);
  double lowest = 1.0;
  for (int i = kSteps - 1; i >= last; --i) {
    const double ratio = static_cast<double>(i) / kSteps;
    const FitResult f = i > 0 ? refit(slow, c.tb_max, ratio * base.params.k)
                              : refit(slow & ~kFitRrw, c.tb_max, 0.0);
    if (f.status != FitStatus::kOk || f.cost > base.cost + allowed) {
      break;
    }
    lowest = ratio;
  }
  if (lowest < 1.0) {
    AdevReading rd;
    rd.what = "with K held lower and one GM more (Tb <= " + fmt("%.3g", c.tb_max) + " s)";
    rd.k_ratio = lowest;
    out.push_back(rd);
  }
  return out;
}

// iv (a non-negative parameter's 95 % interval) widened to hold the same interval moved by
// `ratio` (0: a reading without the parameter) and widened by the reading's own scatter sd_ln;
// true if it grew.
bool widen_by_ratio(ParamInterval& iv, double ratio, double sd_ln = 0.0) {
  if (!(iv.lo >= 0.0) || !std::isfinite(iv.hi) || !(ratio >= 0.0)) {
    return false;
  }
  const double lo = std::min(iv.lo, iv.lo * ratio * std::exp(-1.96 * sd_ln));
  const double hi = std::max(iv.hi, iv.hi * ratio * std::exp(1.96 * sd_ln));
  const bool grew = lo < iv.lo || hi > iv.hi;
  iv.lo = lo;
  iv.hi = hi;
  return grew;
}

// N's, B's, the oscillation's sigma's and K's 95 % intervals widened to hold every reading of
// short_tau_readings and long_tau_readings; a note names the readings that widened them.
void widen_for_readings(const std::vector<AdevReading>& readings, Report& out) {
  std::string said;
  for (const AdevReading& rd : readings) {
    std::string grew;  // the parameters this reading widened, with its ratio
    for (ParamInterval& iv : out.model_after_ci95) {
      if (iv.name == "n" && widen_by_ratio(iv, rd.n_ratio, rd.n_sd_ln)) {
        grew += "N x" + fmt("%.4f", rd.n_ratio);
      }
    }
    for (Effect& e : out.effects) {
      for (ParamInterval& iv : e.ci95) {
        if (e.type == "bias_instability" && iv.name == "b" && widen_by_ratio(iv, rd.b_ratio)) {
          grew += (grew.empty() ? "" : ", ") + std::string("B x") + fmt("%.4f", rd.b_ratio);
        }
        if (e.type == "oscillation" && iv.name == "sigma" && widen_by_ratio(iv, rd.osc_ratio)) {
          grew += (grew.empty() ? "" : ", ") + std::string("oscillation sigma x") +
                  fmt("%.4f", rd.osc_ratio);
        }
        if (e.type == "rate_random_walk" && iv.name == "k" && widen_by_ratio(iv, rd.k_ratio)) {
          grew += (grew.empty() ? "" : ", ") + std::string("K x") + fmt("%.4f", rd.k_ratio);
        }
      }
    }
    if (!grew.empty()) {
      said += (said.empty() ? "" : ", ") + rd.what + " (" + grew + ")";
    }
  }
  if (!said.empty()) {
    out.notes.push_back("the 95 % intervals hold the readings of the ADEV it does not rule out "
                        "at its shortest and longest taus: " + said);
  }
}

// The name of one term bit (a FitTerm bit or kSineBit).
const char* term_name(std::uint32_t t) {
  if (t == kSineBit) {
    return term_info(TermKind::kSinusoid).name;
  }
  const TermInfo* row = term_by_fit_bit(t);
  return row != nullptr ? row->name : "unknown term";
}

// The after-model is accepted only if its RMS and max error over every tau up to T/10 are no
// higher than the before-model's; otherwise terms are removed one at a time (backward
// elimination: at each round the preferred removal), and every removal is said. kSineBit stands
// for the sinusoids (removed together).
AfterChoice choose_after(const AfterContext& c, std::uint32_t terms, const ModelParams& cur,
                         const ModelParams& before_model, std::vector<std::string>& notes) {
  const std::uint32_t base = kFitWhite | kFitGm1 | (terms & c.required);
  std::uint32_t set = terms | (cur.sin_a > 0.0 ? kSineBit : 0U);
  AfterChoice best = fit_after(c, terms, cur, (set & kSineBit) != 0U);
  while (!(best.ok && not_worse(best.e, c.before)) && (set & ~base) != 0U) {
    AfterChoice next;
    std::uint32_t removed = 0;
    for (std::uint32_t bit = 1; bit != 0U; bit <<= 1U) {
      if ((set & bit) == 0U || (base & bit) != 0U) {
        continue;
      }
      const std::uint32_t s2 = set & ~bit;
      const AfterChoice ch = fit_after(c, s2 & ~kSineBit, cur, (s2 & kSineBit) != 0U);
      if (!ch.ok) {
        continue;
      }
      if (preferred(ch, next, c.before)) {
        next = ch;
        removed = bit;
      }
    }
    if (!next.ok) {
      break;
    }
    notes.push_back(std::string("dropped: ") + term_name(removed) +
                    " (with it the after-model's error over [Ts, T/10] was RMS " +
                    fmt("%.3f", best.e.adev_rms_rel) + " / max " + fmt("%.3f", best.e.adev_max_rel) +
                    " against " + fmt("%.3f", c.before.adev_rms_rel) + " / " +
                    fmt("%.3f", c.before.adev_max_rel) + " before: never worse than before)");
    set &= ~removed;
    best = next;
  }
  if (best.ok && !not_worse(best.e, c.before) && (base & c.required) != 0U) {
    notes.push_back("kept: " + required_list(c, base) +
                    ", which the record's likelihood requires, although the model after is worse "
                    "than before on the ADEV over [Ts, T/10] (RMS " +
                    fmt("%.3f", best.e.adev_rms_rel) +
                    " / max " + fmt("%.3f", best.e.adev_max_rel) + " against " +
                    fmt("%.3f", c.before.adev_rms_rel) + " / " +
                    fmt("%.3f", c.before.adev_max_rel) + ")");
    return best;
  }
  if (!best.ok || !not_worse(best.e, c.before)) {
    // The before-model was fitted to the record as measured, its steps and outliers in it; the
    // after-models are fitted and judged on the record without the named ones. Where the
    // before-model is worse there than the after-model, it cannot stand in for it.
    ErrorStats before_clean;
    fill_errors(points_for_model(c.clean, before_model), before_model, c.o, c.ts, c.tau_max,
                before_clean);
    if (best.ok && not_worse(best.e, before_clean)) {
      notes.push_back("kept: the model after's error over [Ts, T/10] (RMS " +
                      fmt("%.3f", best.e.adev_rms_rel) + " / max " +
                      fmt("%.3f", best.e.adev_max_rel) + ") is above the before-model's on the "
                      "record as measured (" + fmt("%.3f", c.before.adev_rms_rel) + " / " +
                      fmt("%.3f", c.before.adev_max_rel) + ") but below it on the record without "
                      "the named steps and outliers (" + fmt("%.3f", before_clean.adev_rms_rel) +
                      " / " + fmt("%.3f", before_clean.adev_max_rel) + "), the record the model "
                      "after describes");
      return best;
    }
    // Not even the base family is as good: the before-model stays (it is not worse than itself).
    notes.emplace_back("no after-model with the terms found is as good as the before-model at "
                       "every measure: after = before");
    best.p = before_model;
    fill_errors(points_for_model(c.clean, before_model), before_model, c.o, c.ts, c.tau_max,
                best.e);
    best.terms = kFitWhite | kFitGm1;
    best.ok = true;
  }
  return best;
}

// A walk and a slow GM are one curve on the ADEV up to T/10 (AVAR ~ Sb tau / 3 = K^2 tau / 3
// for tau << Tb): with both in the model, the joint fit shares the walk's power between them at
// random from one realisation to the next, and its K comes out anywhere from half to all of the
// truth. The record decides whether the slow GM is there at all: the block-mean likelihood
// (long_memory.hpp) of white + slow GMs + K against white + K, 2 ln LR against chi-square(2) at
// alpha (a GM has two parameters). If the GMs are not needed, the model takes the walk alone:
// the slow GMs (tb >= slow_tb_s) leave it and K is the walk-only likelihood's. k = 0 when n/a.
struct WalkOnly {
  double k = 0.0;
  double slow_tb_s = 0.0;
};

// A level that decays from the start of the record (a warm-up transient, A exp(-t / tau)) by the
// record's likelihood under the test's H0: the GLS 2 ln LR of the regressor at kTransientTaus
// taus from two blocks to a fifth of the record, H0's parameters fixed at their fit to the record
// (which holds the decay: H0's slow terms take part of it, so the statistic errs low). At a fixed
// tau it is chi-square(1) under H0; the best tau is compared at alpha / kTransientTaus
// (Bonferroni over the grid; neighbouring taus are correlated, so the level is conservative).
// detrend: the block means had their least-squares line removed (a ramp in the model), and the
// regressor has it removed too.
struct TransientLr {
  double lr = 0.0;
  double tau_s = 0.0;
  double size = 0.0;  // A [unit]
};
constexpr int kTransientTaus = 24;

// exp(-t / tau) at the block centres, prepared as test_rrw prepares the block means.
std::vector<double> decay_regressor(std::size_t nb, double block_s, double tau_s, bool detrend) {
  std::vector<double> u(nb);
  for (std::size_t k = 0; k < nb; ++k) {
    u[k] = std::exp(-(static_cast<double>(k) + 0.5) * block_s / tau_s);
  }
  remove_mean_and_line(u, detrend);
  return u;
}

TransientLr warmup_transient_lr(const RrwLikelihoodTest& lt, bool detrend) {
  TransientLr best;
  const std::size_t nb = lt.means.size();
  if (!lt.ok || !lt.h0.ok || nb < 64) {
    return best;
  }
  const double lo = 2.0 * lt.block_s;
  const double hi = static_cast<double>(nb) * lt.block_s / 5.0;
  for (int g = 0; g < kTransientTaus; ++g) {
    const double tau = lo * std::pow(hi / lo, g / static_cast<double>(kTransientTaus - 1));
    double size = 0.0;
    const double lr = regressor_lr(lt, decay_regressor(nb, lt.block_s, tau, detrend), &size);
    if (lr > best.lr) {
      best = TransientLr{lr, tau, size};
    }
  }
  return best;
}

// The ramp's two checks on the record's likelihood (both 0 without a ramp in p). The null is
// the composite one of a drift that is not a straight line: the model's stationary terms (GMs,
// bias instability) with a rate random walk of any K >= 0 (the walk's likelihood maximum), and,
// when the record's start holds a significant decay (transient_thr, warmup_transient_lr's
// level), that decay fitted beside the regressor (a warm-up transient bends the start).
//   line_lr: 2 ln LR of the line beside that null: a ramp is a trend the record needs beside a
//     walk and a decay (a walk's increments have no mean; the long-tau rise of flicker, a walk
//     or a slow GM can pass the ADEV's test as a ramp).
//   bend_lr: 2 ln LR of a quadratic trend after the least-squares line is removed: a ramp is a
//     straight line, no curvature may remain beyond what the null makes (a drift that bends,
//     e.g. a walk of the drift rate, has the ramp's ADEV slope without being one).
struct RampChecks {
  double line_lr = 0.0;  // < 0: not computed (no check)
  double bend_lr = 0.0;
};

// regressor (k - (nb - 1) / 2)^power over the test's blocks, its mean removed.
std::vector<double> trend_regressor(std::size_t nb, int power) {
  std::vector<double> u(nb);
  double mean = 0.0;
  for (std::size_t k = 0; k < nb; ++k) {
    const double x = static_cast<double>(k) - 0.5 * (static_cast<double>(nb) - 1.0);
    u[k] = power == 1 ? x : x * x;
    mean += u[k] / static_cast<double>(nb);
  }
  for (auto& v : u) {
    v -= mean;
  }
  return u;
}

// 2 ln LR of the trend regressor of `power` on y's block means (their line removed when
// detrend) against the ramp checks' null; -1 when the null could not be fitted.
double trend_beside_walk_lr(const std::vector<double>& y, double ts, const ModelParams& p,
                            double tb_max, const std::vector<std::uint64_t>& step_at,
                            double transient_thr, bool detrend, int power) {
  ModelParams h0 = p;
  h0.r = 0.0;
  h0.k = 0.0;
  RrwLikelihoodTest t = test_rrw(y, ts, h0, tb_max, detrend, step_at, kAuxBlocks, true);
  if (!t.ok) {
    return -1.0;
  }
  if (t.h1.ok && t.h1.loglik > t.h0.loglik) {
    t.h0 = t.h1;
  }
  const std::vector<double> u = trend_regressor(t.means.size(), power);
  const TransientLr tr = warmup_transient_lr(t, detrend);
  if (!(tr.lr > transient_thr)) {
    return regressor_lr(t, u);
  }
  const std::vector<double> decay =
      decay_regressor(t.means.size(), t.block_s, tr.tau_s, detrend);
  return regressor_lr(t, u, nullptr, &decay);
}

RampChecks ramp_checks(const std::vector<double>& y, double ts, const ModelParams& p,
                       double tb_max, const std::vector<std::uint64_t>& step_at,
                       double transient_thr) {
  RampChecks c;
  if (p.r > 0.0) {
    c.line_lr = trend_beside_walk_lr(y, ts, p, tb_max, step_at, transient_thr, false, 1);
    c.bend_lr = trend_beside_walk_lr(y, ts, p, tb_max, step_at, transient_thr, true, 2);
  }
  return c;
}

// p with the walk k in place of its GMs of tb >= slow_tb.
ModelParams walk_alone(const ModelParams& p, double k, double slow_tb) {
  ModelParams q = p;
  q.k = k;
  q.n_gm = 0;
  for (std::size_t i = 0; i < p.n_gm; ++i) {
    if (p.gm[i].tb_s < slow_tb) {
      q.gm[q.n_gm++] = p.gm[i];
    }
  }
  return q;
}

WalkOnly walk_only_k(const AfterContext& c, const std::vector<double>& y_fit, bool ramp,
                     const std::vector<std::uint64_t>& step_at, const ModelParams& p,
                     std::vector<std::string>& notes) {
  if (!(p.k > 0.0) || p.n_gm == 0 || p.bi > 0.0) {
    return {};  // with bias instability in the model the "walk alone" would not be alone
  }
  const RrwLikelihoodTest lt = test_rrw(y_fit, c.ts, p, std::max(c.tb_max, p.gm[0].tb_s), ramp,
                                        step_at);
  if (!lt.ok || !(lt.h1.model.k > 0.0)) {
    return {};
  }
  // Slow: a GM whose ADEV peak (1.89 Tb) and an octave of its falling side do not fit inside
  // [Ts, T/10] (tb beyond c.tb_max, the search's rule), whose curve there is the walk's. A GM
  // that shows its peak is a term of its own, whatever the block means say.
  const double slow_tb = std::max(2.0 * lt.block_s, 0.95 * c.tb_max);
  bool slow = false;
  double k2_pair = p.k * p.k;  // the pair's walk power at tau << Tb: K^2 + sum Sb (slow GMs)
  for (std::size_t i = 0; i < p.n_gm; ++i) {
    if (p.gm[i].tb_s >= slow_tb) {
      slow = true;
      k2_pair += p.gm[i].sb;
    }
  }
  if (!slow) {
    return {};
  }
  BlockModel walk_only = lt.h1.model;
  walk_only.n_gm = 0;
  const LikelihoodFit f = fit_block_model(lt.means, lt.block_s, walk_only, true, lt.block_s,
                                          slow_tb, lt.resets);
  if (!f.ok || !(f.model.k > 0.0)) {
    return {};
  }
  const double lr = std::max(0.0, 2.0 * (lt.h1.loglik - f.loglik));
  const double thr = chi2_quantile(1.0 - c.o.alpha, 2.0);
  // The walk alone must carry the power the ADEV fit gives the pair (within 1.5 x): else the
  // block means tell a different story than the ADEV, and the ADEV fit's K stays.
  const double ratio = f.model.k / std::sqrt(k2_pair);
  if (lr > thr || ratio < 1.0 / 1.5 || ratio > 1.5) {
    return {};
  }
  // The ADEV must not need the slow GM either: the walk alone may not raise its cost over
  // [Ts, T/10] by more than the search's threshold for a term.
  ErrorStats e_pair;
  ErrorStats e_walk;
  const ModelParams q = walk_alone(p, f.model.k, slow_tb);
  fill_errors(points_for_model(c.clean, p), p, c.o, c.ts, c.tau_max, e_pair);
  fill_errors(points_for_model(c.clean, q), q, c.o, c.ts, c.tau_max, e_walk);
  if (e_walk.cost > e_pair.cost + c.cost_thr) {
    notes.push_back("rate_random_walk: the walk alone (K = " + fmt("%.4g", f.model.k) +
                    ") is not taken for the slow GM + K: the block means do not need the GM "
                    "(2 ln LR = " + fmt("%.1f", lr) + "), the ADEV does (cost " +
                    fmt("%.1f", e_walk.cost) + " against " + fmt("%.1f", e_pair.cost) + ")");
    return {};
  }
  notes.push_back("rate_random_walk: K = " + fmt("%.4g", f.model.k) + " from the record's "
                  "block-mean likelihood of the walk alone: a slow GM beside it is not needed "
                  "(2 ln LR = " + fmt("%.1f", lr) + " <= " + fmt("%.2f", thr) +
                  ", chi-square(2)); the model after takes the walk alone in place of the ADEV fit's "
                  "slow GM + K " + fmt("%.3g", p.k) + ", which share the walk's power there");
  return WalkOnly{f.model.k, slow_tb};
}

// A GM of p that the ADEV shows beside the other terms: its peak (1.89 Tb) inside [Ts, T/10]
// and dominating the model there somewhere (at least half its AVAR, as a named term must). A
// rise at the long taus beyond such a GM is more than the first-order model (white + one GM)
// holds. A GM that shares a bend with the white noise or the walk without dominating anywhere
// (the fit's GMs of Tb 0.01 to 50 s on records of white noise and one GM of Tb ~T/6) is not
// shown: what it carries on the ADEV is judged by the refit without it (slow_gm_for_walk).
bool has_visible_gm(const AfterContext& c, const ModelParams& p) {
  const Points pts = in_range(points_for_model(c.clean, p), c.tau_max);
  for (std::size_t g = 0; g < p.n_gm; ++g) {
    if (!(p.gm[g].sb > 0.0) || kGmPeakTauFactor * p.gm[g].tb_s > c.tau_max) {
      continue;
    }
    for (const AdevPoint& pt : pts) {
      const double total = model_avar(p, pt.tau_s);
      if (total > 0.0 && avar_gauss_markov(p.gm[g].sb, p.gm[g].tb_s, pt.tau_s) >= 0.5 * total) {
        return true;
      }
    }
  }
  return false;
}

// Effects whose term left the model are not reported; the rest take their parameters from the
// final model. A term a refit put at 0 is said in a note (say = false: a trial report whose
// notes join out's, which says it).
void drop_unmodelled_effects(const ModelParams& p, Report& out, bool say = true) {
  std::vector<Effect> kept;
  std::size_t sines = 0;
  for (const Effect& found : out.effects) {
    Effect e = found;  // with the final model's parameters
    double v = 1.0;
    const TermInfo* t = effect_term(e);
    // name_extra_gms (below) makes the gauss_markov effects the model's GMs beyond the first
    if (t != nullptr && t->kind != TermKind::kGaussMarkov) {
      const std::size_t inst = t->kind == TermKind::kSinusoid ? sines++ : 0U;
      for (std::size_t j = 0; j < t->n_params; ++j) {
        if (double Effect::*f = effect_field(t->params[j])) {
          e.*f = term_param(p, t->kind, inst, j);
        }
      }
      v = term_param(p, t->kind, inst, t->main_param);
    }
    if (v > 0.0) {
      kept.push_back(e);
    } else if (say) {
      out.notes.push_back("not named: " + e.type +
                          " (accepted by the search; the refitted model after holds it at 0)");
    }
  }
  out.effects = kept;
  name_extra_gms(p, out.effects);
}

// The residual z of the final model at every checked tau (points in increasing tau).
std::vector<double> final_z(const AfterContext& c, const ModelParams& p, Points& pts) {
  pts = in_range(points_for_model(c.clean, p), c.tau_max);
  const Residual r = residual(pts, p, c.o, c.ts, c.tau_max);
  return r.z;
}

// Runs of >= min_run consecutive taus with |z| > z_run of one sign, or one |z| above the
// Bonferroni level over the checked taus, where the model also misses the data by more than
// unexplained_min_rel somewhere (at the shortest taus the EDF is ~1e6: a 0.3 % misfit of the
// sensor's filter shape is "significant" there and of no use to anyone).
std::vector<UnexplainedRun> unexplained_runs(const AfterContext& c, const ModelParams& p) {
  Points pts;
  const std::vector<double> z = final_z(c, p, pts);
  const double z_single =
      two_sided_normal_threshold(c.o.alpha / static_cast<double>(std::max<std::size_t>(1, z.size())));
  std::vector<UnexplainedRun> out;
  std::size_t i = 0;
  while (i < z.size()) {
    const int sign = z[i] > c.o.z_run ? 1 : (z[i] < -c.o.z_run ? -1 : 0);
    if (sign == 0) {
      ++i;
      continue;
    }
    std::size_t j = i;
    double zmax = 0.0;
    while (j < z.size() && z[j] * sign > c.o.z_run) {
      zmax = std::max(zmax, std::fabs(z[j]));
      ++j;
    }
    double rel = 0.0;  // the run's largest |ADEV_model / ADEV_data - 1|
    for (std::size_t k = i; k < j; ++k) {
      rel = std::max(rel, std::fabs(std::sqrt(model_avar(p, pts[k].tau_s) / pts[k].avar) - 1.0));
    }
    if ((j - i >= c.o.min_run || zmax > z_single) && rel > c.o.unexplained_min_rel) {
      out.push_back(UnexplainedRun{pts[i].tau_s, pts[j - 1].tau_s, zmax, sign, 0.0, 0.0, {}});
    }
    i = j;
  }
  return out;
}

// The term of effect type `type` dominates the model at tau: at least half its AVAR.
bool term_dominates(const std::string& type, const ModelParams& p, double tau) {
  return effect_term_avar(type, p, tau) >= 0.5 * model_avar(p, tau);
}

// Before naming an ADEV term: it must dominate the model (>= half its AVAR) somewhere in
// [Ts, T/10], and the residual must hold no significant run where it dominates; else the term
// stays in the model (it lowers the error) but is not named: the range goes to `unexplained`.
// ramp: the ramp's own checks on the record's likelihood (ramp_checks).
// The model without the term of effect type `type`.
ModelParams without(const ModelParams& p, const std::string& type) {
  ModelParams q = p;
  const TermInfo* t = term_by_name(type.c_str());
  if (t != nullptr) {
    remove_term(q, t->kind, base_instances(t->kind));
  }
  return q;
}

// The term of effect type `type` is one the record's likelihood requires (c.required).
bool required_by_record(const AfterContext& c, const std::string& type) {
  const TermInfo* t = term_by_name(type.c_str());
  return t != nullptr && (analysis_bit(*t) & c.required) != 0U;
}

// The 2 ln LR by which the record requires the term of effect type `type` (0: not required).
double required_lr_of(const AfterContext& c, const std::string& type) {
  const TermInfo* t = term_by_name(type.c_str());
  return t != nullptr ? required_lr_of(c, analysis_bit(*t) & c.required) : 0.0;
}

// A residual run over the taus [lo_s, hi_s] where the model misses the data by up to rel.
struct TauRun {
  double lo_s;
  double hi_s;
  double rel;
};

// A term of effect type `type` that the record's likelihood requires stays named where the
// ADEV residual still runs (run, z over pts): the run is unexplained beside it, with a note.
void keep_required(const AfterContext& c, const Points& pts, const std::vector<double>& z,
                   const std::string& type, const TauRun& run, Report& out) {
  double zrun = 0.0;  // the run's largest |z|, signed
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const bool in = pts[i].tau_s >= run.lo_s && pts[i].tau_s <= run.hi_s;
    zrun = in && std::fabs(z[i]) > std::fabs(zrun) ? z[i] : zrun;
  }
  out.notes.push_back(type + " named: the record's likelihood requires it (2 ln LR = " +
                      fmt("%.1f", required_lr_of(c, type)) +
                      "); where it dominates the model still misses the data at tau " +
                      fmt("%.3g", run.lo_s) + "-" + fmt("%.3g", run.hi_s) + " s, by up to " +
                      fmt("%.0f", 100.0 * run.rel) +
                      " %: reported as unexplained");
  out.unexplained.push_back(
      UnexplainedRun{run.lo_s, run.hi_s, std::fabs(zrun), zrun > 0.0 ? 1 : -1, 0.0, 0.0, {}});
}

void name_check(const AfterContext& c, const ModelParams& p, const RampChecks& ramp,
                Report& out, std::vector<std::string>& dominates_nowhere) {
  Points pts;
  const std::vector<double> z = final_z(c, p, pts);
  std::vector<Effect> kept;
  const double bend_thr = chi2_quantile(1.0 - c.o.alpha, 1.0);
  for (const auto& e : out.effects) {
    if (effect_term_avar(e.type, p, 1.0) < 0.0) {
      kept.push_back(e);
      continue;
    }
    std::size_t dominated = 0;
    std::size_t run = 0;
    std::size_t worst_run = 0;
    double run_rel = 0.0;  // the run's largest |ADEV_model / ADEV_data - 1|
    double worst_rel = 0.0;
    double tau_lo = 0.0;
    double tau_hi = 0.0;
    double run_lo = 0.0;
    double dom_lo = 0.0;
    double dom_hi = 0.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double t = pts[i].tau_s;
      const bool dom = term_dominates(e.type, p, t);
      dominated += dom ? 1U : 0U;
      dom_lo = dom && !(dom_lo > 0.0) ? t : dom_lo;
      dom_hi = dom ? t : dom_hi;
      if (dom && std::fabs(z[i]) > c.o.z_run) {
        run_lo = run == 0 ? t : run_lo;
        run_rel = run == 0 ? 0.0 : run_rel;
        run_rel = std::max(run_rel, std::fabs(std::sqrt(model_avar(p, t) / pts[i].avar) - 1.0));
        ++run;
        // A run counts as unexplained_runs counts one: the model also misses the data there by
        // more than unexplained_min_rel (at the shortest taus the EDF is ~1e6 and a 0.3 %
        // misfit of the sensor's filter shape is "significant").
        if (run > worst_run && run_rel > c.o.unexplained_min_rel) {
          worst_run = run;
          worst_rel = run_rel;
          tau_lo = run_lo;
          tau_hi = t;
        }
      } else {
        run = 0;
      }
    }
    std::string why;
    if (dominated == 0) {
      dominates_nowhere.push_back(e.type);
      out.notes.push_back("not named: " + e.type +
                          " (in the model, but it dominates the model ADEV at no tau)");
      continue;
    }
    if (e.type == "ramp" && ramp.line_lr >= 0.0 && !(ramp.line_lr > bend_thr)) {
      why = "the record does not need the line beside a walk and a decay from the start: "
            "2 ln LR = " + fmt("%.1f", ramp.line_lr) + " <= " + fmt("%.2f", bend_thr);
    } else if (e.type == "ramp" && ramp.bend_lr > bend_thr) {
      why = "after removing the line the record still bends: quadratic 2 ln LR = " +
            fmt("%.1f", ramp.bend_lr) + " > " + fmt("%.2f", bend_thr) +
            "; the drift is not a straight line";
    } else if (worst_run >= c.o.min_run && required_by_record(c, e.type)) {
      // The record's likelihood decided this term (one criterion): it stays named.
      keep_required(c, pts, z, e.type, TauRun{tau_lo, tau_hi, worst_rel}, out);
      kept.push_back(e);
      continue;
    } else if (worst_run >= c.o.min_run && e.type != "gauss_markov") {
      // (A second GM claims no mechanism beyond the base family's own kind, correlated noise of
      // time Tb: where it still misses, the miss is reported as unexplained, the GM kept.)
      why = "where it dominates the residual still runs outside the intervals, tau " +
            fmt("%.3g", tau_lo) + "-" + fmt("%.3g", tau_hi) + " s, missing the data by up to " +
            fmt("%.0f", 100.0 * worst_rel) + " %";
    } else {
      kept.push_back(e);
      continue;
    }
    // Not this term: what it stands in for is unexplained over the taus it dominates, by as
    // much as the model without it misses the data there.
    out.notes.push_back("not named: " + e.type + " (" + why +
                        "); the taus it dominates are reported as unexplained");
    const ModelParams q = without(p, e.type);
    const Residual r0 = residual(pts, q, c.o, c.ts, c.tau_max);
    double zmax = 0.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (pts[i].tau_s >= dom_lo && pts[i].tau_s <= dom_hi) {
        zmax = std::max(zmax, std::fabs(r0.z[i]));
      }
    }
    out.unexplained.push_back(UnexplainedRun{dom_lo, dom_hi, zmax, -1, 0.0, 0.0, {}});
  }
  out.effects = kept;
}

// Every reported effect is real: its main parameter finite and nonzero; a step not within one
// window of either end (the detector's own windows guarantee this; checked again here).
void drop_degenerate_effects(double ts, double n_d, Report& out) {
  std::vector<Effect> kept;
  for (const auto& e : out.effects) {
    double v = effect_size(e);
    if (e.type == "bias_step") {
      v = e.size;
    } else if (e.type == "outliers") {
      v = static_cast<double>(e.count);
    }
    bool ok = std::isfinite(v) && std::fabs(v) > 0.0;
    if (ok && e.type == "bias_step") {
      const double at = e.time_s / ts;
      ok = at >= 2.0 && n_d - at >= 2.0;
    }
    if (ok) {
      kept.push_back(e);
    } else {
      out.notes.push_back("not reported: " + e.type + " (its parameter is " + fmt("%g", v) +
                          ": a degenerate estimate, not an effect)");
    }
  }
  out.effects = kept;
}

std::vector<Effect> without_types(const std::vector<Effect>& effects,
                                  const std::vector<std::string>& types) {
  std::vector<Effect> kept;
  for (const auto& e : effects) {
    if (std::find(types.begin(), types.end(), e.type) == types.end()) {
      kept.push_back(e);
    }
  }
  return kept;
}

std::vector<Effect> without_type(const std::vector<Effect>& effects, const std::string& type) {
  return without_types(effects, {type});
}

bool named_type(const std::vector<Effect>& effects, const std::string& type) {
  return std::any_of(effects.begin(), effects.end(),
                     [&](const Effect& e) { return e.type == type; });
}

// The terms of p beyond the base model (analysis_bit: FitTerm bits, kSineBit) that fewer
// effects of `effects` name than p holds.
std::uint32_t unnamed_terms(const ModelParams& p, const std::vector<Effect>& effects) {
  std::uint32_t bits = 0;
  for (const TermInfo& t : kTermTable) {
    std::size_t named = 0;
    for (const auto& e : effects) {
      named += e.type == t.name ? 1U : 0U;
    }
    if (named + base_instances(t.kind) < term_instances(p, t.kind)) {
      bits |= analysis_bit(t);
    }
  }
  return bits;
}

std::string term_list(std::uint32_t bits) {
  std::string s;
  for (std::uint32_t b = 1; b != 0U; b <<= 1U) {
    if ((bits & b) != 0U) {
      s += (s.empty() ? "" : ", ") + std::string(term_name(b));
    }
  }
  return s;
}

// Terms of the chosen after-model that the report does not name (name_check, degenerate
// estimates) leave it: the model is refitted without them over the same taus (fit_after; its
// parameters become the effects'), or, if that fit fails, they are zeroed. Each removal is a note.
void remove_unnamed_terms(const AfterContext& c, AfterChoice& choice, Report& out) {
  for (int round = 0; round < 8; ++round) {
    const std::uint32_t bits = unnamed_terms(choice.p, out.effects);
    if (bits == 0U) {
      return;
    }
    ModelParams sines = choice.p;
    if ((bits & kSineBit) != 0U) {
      remove_term(sines, TermKind::kSinusoid);
    }
    const std::uint32_t keep = choice.terms & ~bits;
    AfterChoice ch = fit_after(c, keep, sines, sines.sin_a > 0.0);
    if (!ch.ok) {
      ch = choice;
      ch.p = sines;
      for (const TermInfo& t : kTermTable) {
        if ((bits & analysis_bit(t)) != 0U) {
          remove_term(ch.p, t.kind, base_instances(t.kind));
        }
      }
      ch.terms = keep;
      fill_errors(points_for_model(c.clean, ch.p), ch.p, c.o, c.ts, c.tau_max, ch.e);
    }
    out.notes.push_back("removed from the model after: " + term_list(bits) +
                        " (not named, see above); refitted without it: error over [Ts, T/10] RMS " +
                        fmt("%.3f", ch.e.adev_rms_rel) + " / max " + fmt("%.3f", ch.e.adev_max_rel) +
                        " (with it " + fmt("%.3f", choice.e.adev_rms_rel) + " / " +
                        fmt("%.3f", choice.e.adev_max_rel) + ")");
    choice = ch;
    drop_unmodelled_effects(choice.p, out);
  }
}

}  // namespace

namespace {

// Mean of up to `count` finite samples of y walking from `from` in direction `dir` (+1 / -1).
double local_mean(const std::vector<double>& y, std::size_t from, int dir, std::size_t count) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = from; i < y.size() && n < count;
       i = dir > 0 ? i + 1 : (i == 0 ? y.size() : i - 1)) {
    if (std::isfinite(y[i])) {
      sum += y[i];
      ++n;
    }
  }
  return n > 0 ? sum / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

bool fill_gaps(std::vector<double>& y, std::vector<std::uint8_t>& gap, std::uint64_t& samples,
               std::uint64_t& runs) {
  samples = 0;
  runs = 0;
  gap.assign(y.size(), 0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    gap[i] = std::isfinite(y[i]) ? 0 : 1;
    samples += gap[i];
  }
  if (samples == y.size()) {
    return false;
  }
  // Each run [a, b) is filled by the straight line between the means of the finite samples on
  // either side (as many as the run is long, at least 100): a line between two single noisy
  // samples would put a noise-free segment off the local level, which the step detectors see.
  std::size_t i = 0;
  while (i < y.size()) {
    if (gap[i] == 0) {
      ++i;
      continue;
    }
    std::size_t b = i;
    while (b < y.size() && gap[b] != 0) {
      ++b;
    }
    const std::size_t len = b - i;
    const std::size_t w = std::max<std::size_t>(100, len);
    const double before = i > 0 ? local_mean(y, i - 1, -1, w) : local_mean(y, b, 1, w);
    const double after = b < y.size() ? local_mean(y, b, 1, w) : before;
    for (std::size_t j = i; j < b; ++j) {
      const double f = static_cast<double>(j - i + 1) / static_cast<double>(len + 1);
      y[j] = before + f * (after - before);
    }
    ++runs;
    i = b;
  }
  if (samples == 0) {
    gap.clear();
  }
  return true;
}

double derive_lsb(const std::vector<double>& y, std::string& note) {
  std::vector<double> s;
  s.reserve(y.size());
  double amax = 0.0;
  for (const double v : y) {
    if (std::isfinite(v)) {
      s.push_back(v);
      amax = std::max(amax, std::fabs(v));
    }
  }
  sort_finite(s);
  // Distinct levels: values closer than the floating-point residue of the data's magnitude
  // (1e-9 of max |y|, far above double rounding after scaling or differencing) are one level.
  const double resid = 1e-9 * (amax > 0.0 ? amax : 1.0);
  double dmin = 0.0;
  for (std::size_t i = 1; i < s.size(); ++i) {
    const double d = s[i] - s[i - 1];
    if (d > resid && (dmin <= 0.0 || d < dmin)) {
      dmin = d;
    }
  }
  const double spread = s.empty() ? 0.0 : s.back() - s.front();
  if (dmin > 0.0 && spread / dmin < 2e9) {
    // The step from the levels, not from one difference: every distinct level L is y0 + k dmin
    // for an integer k, and the step is the least-squares slope of L - y0 on k. The smallest
    // difference carries the residue of two values (after an offset such as gravity, or a
    // print to a few digits, that can be a few 1e-3 of a step); the slope over the whole span
    // carries it divided by the span's count of steps. Two passes: the first's k are exact
    // for any span the smallest difference resolves, the second's for any span at all.
    const double y0 = s.front();
    double step = dmin;
    for (int pass = 0; pass < 2; ++pass) {
      double skk = 0.0;
      double skl = 0.0;
      double last = y0;
      for (std::size_t i = 1; i < s.size(); ++i) {
        if (s[i] - last <= resid) {
          continue;  // the same level
        }
        last = s[i];
        const double k = std::round((s[i] - y0) / step);
        skk += k * k;
        skl += k * (s[i] - y0);
      }
      if (skk > 0.0 && skl > 0.0) {
        step = skl / skk;
      }
    }
    // Every value on the lattice y0 + k step within 2 % of a step (the residue of an offset
    // added in floating point, or of a print to six digits, is well inside it; values off a
    // lattice, e.g. noise never quantised, are not), and the span inside int32 counts. Every
    // value is checked: one off the lattice is enough to refuse it.
    constexpr double kLatticeTol = 0.02;
    bool multiples = spread / step < 2e9;
    for (std::size_t i = 0; i < y.size() && multiples; ++i) {
      if (std::isfinite(y[i])) {
        const double c = (y[i] - y0) / step;
        multiples = std::fabs(c - std::round(c)) < kLatticeTol;
      }
    }
    if (multiples) {
      note = "LSB derived: the values lie on a lattice of step " + fmt("%.6g", step) +
             " (every value a multiple of it from the smallest, within 2 % of a step)";
      return step;
    }
  }
  if (!s.empty() && !(dmin > 0.0)) {
    // One level only: no step to derive and no noise to scale. The counts are then all 0 at
    // any LSB; 1e-9 of |y| keeps a later value of another record's size inside int32 counts.
    const double lsb = amax > 0.0 ? amax * 1e-9 : 1e-9;
    note = "LSB chosen: every value is " + fmt("%.9g", s.front()) +
           " (no step to derive); 1e-9 of |y| = " + fmt("%.6g", lsb);
    return lsb;
  }
  const double sd = robust_scale(s);
  // Fine against the noise, yet the record's whole span inside int32 counts (2^30 of margin).
  const double fine = sd > 0.0 ? sd / 4096.0 : 0.0;
  const double span_limit = spread / 1073741824.0;
  double lsb = std::max(fine, span_limit);
  if (!(lsb > 0.0)) {
    lsb = amax > 0.0 ? amax * 1e-9 : 1e-9;
  }
  note = std::string("LSB chosen: no common step in the data") +
         (dmin > 0.0 ? " (the smallest difference " + fmt("%.3g", dmin) +
                           " is not a step of every value, or would overflow int32 counts)"
                     : "") +
         "; " + (lsb > fine ? "the record's span / 2^30" : "robust std / 4096") + " = " +
         fmt("%.6g", lsb) + " (quantization to it is far below the noise)";
  return lsb;
}

namespace {

// CPU time of the calling thread: analyze() runs on one thread, and the process's clock would
// also count the other channels or records analysed beside it.
double thread_cpu_s() {
  timespec t{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t) != 0) {
    return 0.0;
  }
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The analysis of one channel: a pipeline of named steps over one shared state (the record as
// it is cleaned step by step, its counts and ADEV, the model as it grows). Each step reads what
// the earlier ones left; analyze() runs them in order.
class Analysis {
 public:
  // The record is taken by value: moved in by the analyze() that consumes it, copied once by
  // the one that does not. It is the analysis' y0, then its y: no other copy of it is kept.
  Analysis(std::vector<double> y_in_, const std::string& channel_, const Options& o_,
           Report& out_, std::string& error_)
      : y0(std::move(y_in_)), channel(channel_), o(o_), out(out_), error(error_) {}

  bool run() {
    if (!prepare() || !fit_before()) {
      return false;
    }
    noise_change = find_noise_level_change(y0, gap, o.alpha);
    // Over [Ts, T/10] the GM must show its ADEV peak (1.89 Tb) and one octave of its falling side
    // inside the range: a GM whose peak lies at or beyond the end is, on these taus, the same curve
    // as a rate random walk (AVAR ~ Sb tau / 3), and the one-parameter RRW is the name for it.
    tb_max = tau_max / (2.0 * kGmPeakTauFactor);
    find_outliers();
    find_steps_by_windows();
    find_steps_by_likelihood();
    if (!select_terms()) {
      return false;
    }
    warmup_transient_check(rrw_by_likelihood());
    settle_unnamed_shifts();
    after_model();
    return true;
  }

 private:
  // A frozen output (find_frozen_runs) is no measurement: each run but its first sample is
  // marked missing, as a non-finite sample is.
  void mark_frozen_runs() {
    std::size_t min_length = 0;
    const std::vector<FrozenRun> runs = find_frozen_runs(y0, o.alpha, &min_length);
    if (runs.empty()) {
      return;
    }
    std::size_t samples = 0;
    for (const FrozenRun& r : runs) {
      for (std::size_t i = r.first + 1; i < r.first + r.length; ++i) {
        y0[i] = std::numeric_limits<double>::quiet_NaN();
      }
      samples += r.length - 1;
    }
    frozen_samples = samples;
    out.notes.push_back(
        std::to_string(runs.size()) + (runs.size() == 1 ? " run" : " runs") +
        " of one repeated value (the longest " + std::to_string(runs[0].length) +
        " samples from t = " + fmt("%.2f", static_cast<double>(runs[0].first) * ts) +
        " s; on this record's own ties a run of " + std::to_string(min_length) +
        " or more has a chance below " + fmt("%g", o.alpha) + "): a frozen output, its " +
        std::to_string(samples) + " repeated samples taken as missing");
  }

  // A clipped output (find_clipping): the noise's tail is cut there, so the ADEV and the model
  // understate it; said as an unexplained time range from the first to the last clipped sample.
  void report_clipping() {
    const Clipping c = find_clipping(y0);
    if (!c.found) {
      return;
    }
    UnexplainedRun u;
    u.t_min_s = static_cast<double>(c.first) * ts;
    u.t_max_s = static_cast<double>(c.last + 1) * ts;
    u.tau_min_s = ts;
    u.tau_max_s = ts;
    u.what = std::to_string(c.count) + " samples at the record's " +
             (c.at_min ? "minimum " : "maximum ") + fmt("%.9g", c.value) + " against " +
             std::to_string(c.next_count) + " at the next value: the output clips there (a range "
             "or converter limit); the noise's tail is cut";
    time_ranges.push_back(u);
    out.notes.push_back("clipped: " + u.what);
  }

  // Inputs checked, gaps marked, the LSB chosen, the counts and the raw ADEV.
  bool prepare() {
    out = Report{};
    out.channel = channel;
    out.fs_hz = o.fs_hz;
    const std::size_t n_in = y0.size();
    out.samples = n_in;
    if (!(o.fs_hz > 0.0) || !std::isfinite(o.fs_hz)) {
      error = "analyze: sample rate must be > 0 (got " + fmt("%g", o.fs_hz) + ")";
      return false;
    }
    if (n_in < 1000) {
      error = "analyze: channel '" + channel + "' has " + std::to_string(n_in) +
              " samples; at least 1000 are needed";
      return false;
    }
    ts = 1.0 / o.fs_hz;
    mark_frozen_runs();
    report_clipping();  // before the gaps are filled (their values are no measurements)
    // Non-finite samples are gaps: the ADEV marks them missing, the filters skip them, and the
    // time-domain steps see them filled by interpolation.
    if (!fill_gaps(y0, gap, out.gap_samples, out.gap_runs)) {
      error = "analyze: channel '" + channel + "' has no finite sample";
      return false;
    }
    if (out.gap_samples > 0) {
      out.notes.push_back(std::to_string(out.gap_samples) +
                          (frozen_samples > 0 ? " missing samples (" +
                                                    std::to_string(frozen_samples) +
                                                    " of them a frozen output's repeats) in "
                                              : std::string(" non-finite samples in ")) +
                          std::to_string(out.gap_runs) +
                          " gaps: marked missing in the ADEV, skipped by the filters");
    }
    if (static_cast<double>(out.gap_samples) > 0.5 * static_cast<double>(n_in)) {
      error = "analyze: channel '" + channel + "' is more than half gaps (" +
              std::to_string(out.gap_samples) + " of " + std::to_string(n_in) +
              " samples are not finite)";
      return false;
    }
    n_d = static_cast<double>(n_in);
    t_rec = n_d * ts;
    tau_max = o.tau_max_fraction * t_rec;
    offset = y0[0];
    out.lsb = o.lsb;
    if (o.lsb > 0.0) {
      out.lsb_note = "LSB given: " + fmt("%.6g", o.lsb);
    } else {
      // From the recorded samples only: the values filled into gaps (local means) are not on
      // the data's lattice.
      std::vector<double> finite;
      if (out.gap_samples > 0) {
        // fill_gaps changed only the samples it marked: the others are the recorded ones.
        finite.reserve(n_in - out.gap_samples);
        for (std::size_t i = 0; i < n_in; ++i) {
          if (gap[i] == 0) {
            finite.push_back(y0[i]);
          }
        }
      }
      out.lsb = derive_lsb(out.gap_samples > 0 ? finite : y0, out.lsb_note);
    }
    lsb = out.lsb;
    counts = to_counts(y0, offset, lsb, sat);  // of y below, kept current
    if (sat > 0) {
      error = "analyze: " + std::to_string(sat) + " samples differ from the first by more than "
              "int32 counts hold at LSB " + fmt("%g", lsb);
      return false;
    }
    raw = adev_of(counts, gap, ts, lsb);
    return true;
  }

  // The first-order model over [Ts, tau_hi]: white + GM; if that fit fails, white noise alone;
  // if that fails too (a record on one level, or too few nonzero ADEV points), white noise at
  // the quantization's level, q / sqrt(12) per sample: all the record can say is that its noise
  // is not above it. The status is kOk only for the white + GM fit.
  FitResult fit_before_model(double tau_hi) {
    FitResult r = fit_terms(raw.by_alpha[2], kFitWhite | kFitGm1, ts, tau_hi);
    if (r.status == FitStatus::kOk) {
      return r;
    }
    const FitStatus gm_status = r.status;
    r.tb_at_bound = false;
    const FitResult w = fit_terms(raw.by_alpha[2], kFitWhite, ts, tau_hi);
    if (w.status == FitStatus::kOk && w.params.n > 0.0) {
      r.params = w.params;
      out.notes.push_back("the white + GM fit over [Ts, " + fmt("%g", tau_hi) + " s] failed (" +
                          fit_status_text(gm_status) + "): the model before is white noise alone");
      return r;
    }
    r.params = ModelParams{};
    r.params.n = lsb / std::sqrt(12.0) * std::sqrt(ts);
    out.notes.push_back("the white + GM and the white-only fits over [Ts, " + fmt("%g", tau_hi) +
                        " s] failed (" + fit_status_text(gm_status) +
                        "): the model before is white noise at the quantization's level, "
                        "N = LSB / sqrt(12) * sqrt(Ts) = " + fmt("%.4g", r.params.n) +
                        " (the record does not resolve its noise at this LSB)");
    return r;
  }

  // The first-order model, its filter and its errors (the "before").
  bool fit_before() {
    // ---- before: the first-order model over [Ts, 100 s]
    const double example_max = std::min(o.example_tau_max_s, tau_max);
    // Finite data always gets a report: a fit that fails falls back to a simpler model, and
    // the note says which and why.
    const FitResult before0 = fit_before_model(example_max);
    const Points raw_pts_b = points_for_model(raw, before0.params);
    const FitResult before = before0.status == FitStatus::kOk
                                 ? fit_terms(raw_pts_b, kFitWhite | kFitGm1, ts, example_max)
                                 : before0;
    out.model_before = before.status == FitStatus::kOk ? before.params : before0.params;
    if (before0.tb_at_bound || before.tb_at_bound) {
      out.notes.emplace_back("before: the GM correlation time is at its search bound (the range "
                             "[Ts, 100 s] does not determine it)");
    }
    out.adev = raw.by_alpha[2];
    const double known_raw = initial_level(y0);
    fb = run_filter(out.model_before, ts, y0, known_raw, gap.empty() ? nullptr : &gap, true);
    fill_errors(raw_pts_b, out.model_before, o, ts, tau_max, out.error_before);
    out.error_before.nis_mean = fb.nis_mean;
    out.error_before.nis_flagged_fraction = fb.nis_flagged;
    out.error_before.whiteness_flagged_fraction = fb.whiteness_flagged;
    out.error_before.filter_states = fb.states;
    out.error_before.cov_ratio = covariance_ratio(out.model_before, ts, y0);
    return true;
  }

  // The record's lattice step normalised by m's white noise std N / sqrt(Ts) (the least of its
  // filter's innovation std).
  double lattice_step(const ModelParams& m) const {
    const double white_sd = m.n / std::sqrt(ts);
    return white_sd > 0.0 ? lsb / white_sd : 0.0;
  }

  void find_outliers() {
    // ---- time domain: outliers on the before filter's innovations (gaps are skipped like them)
    // y0 is not read again: y takes its storage.
    y = std::move(y0);
    y0 = std::vector<double>{};
    const double known_raw = initial_level(y);  // the before filter's known signal
    outlier = gap.empty() ? std::vector<std::uint8_t>(y.size(), 0) : gap;
    bool outliers_replaced = false;
    {
      // The spread on the record's lattice (lattice_gate_scale; the innovations are
      // normalised by the filter's variance, at least the white noise's N^2 / Ts). With a
      // change of the noise level, each part's own spread (else the louder part's samples
      // would be "outliers").
      const std::size_t split = noise_change.found ? noise_change.at : y.size();
      const double step = lattice_step(out.model_before);
      const auto part = [this, step](std::size_t a, std::size_t b) {
        return lattice_gate_scale(
            std::vector<float>(fb.nu.begin() + static_cast<std::ptrdiff_t>(a),
                               fb.nu.begin() + static_cast<std::ptrdiff_t>(b)),
            step);
      };
      const GateScale scale_a = part(0, split);
      const GateScale scale_b = split < y.size() ? part(split, y.size()) : scale_a;
      const double scale = std::min(scale_a.scale, scale_b.scale);
      const double thr = two_sided_normal_threshold(o.alpha / n_d);
      outlier_split = split;
      outlier_guard = noise_change.found ? noise_change.block_len : 0;
      // The gate's limits on |value - prediction|, in the record's units (the innovations are
      // normalised by at least the white noise's std, which the filter's reaches once settled).
      const double white_sd = out.model_before.n / std::sqrt(ts);
      outlier_limit_a = (thr * scale_a.scale + scale_a.half_step) * white_sd;
      outlier_limit_b = (thr * scale_b.scale + scale_b.half_step) * white_sd;
      if (scale > 0.0) {
        outliers_replaced = gate_outliers(scale_a, scale_b, thr, known_raw);
      }
    }

    // The counts and ADEV of the current y: the raw ones until a sample changes (each is a pass
    // over the record, done only when y changed).
    adev_y = raw;
    if (outliers_replaced) {
      refresh_adev();
    }
    // The before filter's per-sample innovations and predictions served the outlier search only.
    fb.nu = std::vector<float>{};
    fb.pred_rel = std::vector<float>{};
  }

  // The before filter's innovations through the outlier gate (|nu| / scale > thr). A flagged
  // sample is an outlier when it stands alone: kShiftRun or more flagged within kShiftGap
  // samples of each other with one sign are a change of the level the filter had not
  // followed yet (a step's first samples), left in the record for the step search. Each
  // outlier is replaced by the filter's prediction; true when any was.
  static constexpr std::size_t kShiftRun = 3;
  static constexpr std::size_t kShiftGap = 2;
  bool gate_outliers(const GateScale& scale_a, const GateScale& scale_b, double thr,
                     double known_raw) {
    OutlierGate gate;
    if (gate.configure(thr) != EffectStatus::kOk) {
      return false;
    }
    std::vector<std::pair<std::size_t, double>> flagged;  // index, nu / scale
    for (std::size_t i = 0; i < y.size(); ++i) {
      const int k = gate_part(i, outlier_split, outlier_guard, scale_a.scale, scale_b.scale);
      const double z = (k == 0 ? scale_a : scale_b).z(fb.nu[i]);
      if ((gap.empty() || gap[i] == 0) && gate.push(z)) {
        flagged.emplace_back(i, z);
      }
    }
    std::vector<double> times;
    std::uint64_t count = 0;
    std::uint64_t shifted = 0;
    double max_abs = 0.0;
    for (std::size_t a = 0; a < flagged.size();) {
      std::size_t b = a + 1;
      while (b < flagged.size() && flagged[b].first - flagged[b - 1].first <= kShiftGap &&
             (flagged[b].second > 0.0) == (flagged[a].second > 0.0)) {
        ++b;
      }
      if (b - a >= kShiftRun) {
        shifted += b - a;
        a = b;
        continue;
      }
      for (; a < b; ++a) {
        const std::size_t i = flagged[a].first;
        outlier[i] = 1;
        const double pred = known_raw + static_cast<double>(fb.pred_rel[i]);
        outlier_delta.emplace_back(i, y[i] - pred);
        y[i] = pred;
        ++count;
        max_abs = std::max(max_abs, std::fabs(flagged[a].second));
        if (times.size() < 100) {
          times.push_back(static_cast<double>(i) * ts);
        }
      }
    }
    if (shifted > 0) {
      out.notes.push_back(std::to_string(shifted) + " samples above the outlier gate (" +
                          fmt("%.2f", thr) + " robust sigma) come in runs of " +
                          std::to_string(kShiftRun) + " or more of one sign: a change of the "
                          "level, not outliers (left to the step search)");
    }
    if (count == 0) {
      return false;
    }
    Effect e;
    e.times_s = times;
    e.type = "outliers";
    e.count = count;
    e.statistic = max_abs;
    e.threshold = thr;
    out.effects.push_back(e);
    return true;
  }

  // The places of the excursions above the threshold at one detector scale, merged where
  // closer than two windows (one level change crosses the threshold more than once).
  struct ShiftPlaces {
    std::size_t places = 0;
    double t_first_s = 0.0;
    double t_last_s = 0.0;
    double median_size = 0.0;     // of |size| over the places, in the record's units
    double median_spacing_s = 0.0;  // 0: not known
  };

  [[nodiscard]] ShiftPlaces shift_places(const StepDetector<16, kStepEvents>& d,
                                         double window) const {
    ShiftPlaces r;
    std::vector<double> at;
    std::vector<double> size;
    // Where the white noise's level changes, the detectors' reference is the record's average:
    // the louder part's own noise crosses the threshold at many places. Those are the noise
    // change's (its own time range), not level shifts, and are not counted.
    const auto change = static_cast<double>(noise_change.at);
    const bool louder_after = noise_change.std_ratio > 1.0;
    const auto in_louder_part = [&](double t) {
      return noise_change.found && (louder_after ? t >= change : t < change);
    };
    for (std::size_t i = 0; i < d.n_events(); ++i) {
      const StepEvent& ev = d.event(i);
      const auto t = static_cast<double>(ev.sample_index);
      const double abs_size = std::fabs(ev.size_counts) * lsb;
      if (in_louder_part(t)) {
        continue;
      }
      if (!at.empty() && t - at.back() < 2.0 * window) {
        size.back() = std::max(size.back(), abs_size);
        continue;
      }
      at.push_back(t);
      size.push_back(abs_size);
    }
    r.places = at.size() + (noise_change.found ? 0U : d.stats().events_dropped);
    if (at.empty()) {
      return r;
    }
    r.t_first_s = at.front() * ts;
    r.t_last_s = at.back() * ts;
    r.median_size = median_of(size);
    std::vector<double> gaps;
    for (std::size_t i = 1; i < at.size(); ++i) {
      gaps.push_back((at[i] - at[i - 1]) * ts);
    }
    r.median_spacing_s = median_of(gaps);
    return r;
  }

  // The strongest excursion of the two-window step detectors over the scales the ADEV gives
  // (windows up to n / 50 samples); false when none passes its threshold thr. places: the
  // separate excursions at the strongest one's scale.
  bool strongest_step(StepEvent& best, double& best_window, double& thr, ShiftPlaces& places) {
    const Points& pts = adev_y.by_alpha[2];
    const std::size_t np = pts.size();
    struct Scale {
      std::uint32_t block;
      double avar_counts2;
    };
    std::vector<Scale> scales;
    double n_eff = 0.0;
    for (std::uint32_t p = 4; p < 24; ++p) {
      const std::uint32_t af = 8U << p;
      if (static_cast<double>(af) > n_d / 50.0) {
        break;
      }
      for (std::size_t i = 0; i < np; ++i) {
        if (pts[i].af == af && pts[i].avar > 0.0) {
          scales.push_back(Scale{1U << p, pts[i].avar / (lsb * lsb)});
          n_eff += 2.0 * n_d / static_cast<double>(af);
        }
      }
    }
    if (scales.empty()) {
      return false;
    }
    thr = two_sided_normal_threshold(o.alpha / n_eff);
    std::vector<StepDetector<16, kStepEvents>> det(scales.size());
    bool ok = true;
    for (std::size_t s = 0; s < scales.size(); ++s) {
      ok = ok && det[s].configure(scales[s].block, 8, scales[s].avar_counts2, thr) ==
                     EffectStatus::kOk;
    }
    if (!ok) {
      return false;
    }
    for (const std::int32_t v : counts) {
      for (auto& d : det) {
        d.push(v);
      }
    }
    bool found = false;
    best_window = 0.0;  // samples on each side of the boundary at the best scale
    std::size_t best_scale = 0;
    for (std::size_t s = 0; s < det.size(); ++s) {
      StepDetector<16, kStepEvents>& d = det[s];
      d.finish();
      for (std::size_t i = 0; i < d.n_events(); ++i) {
        if (!found || std::fabs(d.event(i).z) > std::fabs(best.z)) {
          best = d.event(i);
          best_window = 8.0 * scales[s].block;
          best_scale = s;
          found = true;
        }
      }
    }
    if (found) {
      places = shift_places(det[best_scale], best_window);
    }
    return found;
  }

  // The strongest excursion lies within one window of an end: not a step the windows can
  // place; its window is an unexplained time range.
  void edge_excursion(const StepEvent& best, double best_window) {
    const double at = static_cast<double>(best.sample_index);
    out.notes.push_back("step search stopped: the strongest excursion, at t = " +
                        fmt("%.1f", at * ts) + " s, lies within one window (" +
                        fmt("%.0f", best_window * ts) +
                        " s) of an end of the record: not a step the windows can place");
    UnexplainedRun u;
    const bool start = at < best_window;
    u.t_min_s = start ? 0.0 : (at - best_window) * ts;
    u.t_max_s = start ? (at + best_window) * ts : n_d * ts;
    u.tau_min_s = best_window * ts / 8.0;
    u.tau_max_s = best_window * ts;
    u.max_abs_z = std::fabs(best.z);
    u.what = std::string("a significant level change within one window of the ") +
             (start ? "start (a warm-up transient?)" : "end") + " of the record, z " +
             fmt("%.1f", best.z);
    time_ranges.push_back(u);
  }

  // y from sample `from` on moves by delta (a step taken out of the record, or put back).
  void shift_level(std::size_t from, double delta) {
    for (std::size_t i = from; i < y.size(); ++i) {
      y[i] += delta;
    }
  }

  // The counts and ADEV of y as it now stands (a pass over the record each).
  void refresh_adev() {
    counts = to_counts(y, offset, lsb, sat);
    adev_y = adev_of(counts, gap, ts, lsb);
  }

  // A second "step" within one window of the last one: the other edge of a transient (or the
  // residue of the first estimate), not a new step.
  void near_previous_step(const StepEvent& best, double best_window) {
    const double at = static_cast<double>(best.sample_index);
    // The other edge of a short transient (a blip, not a level change) when it undoes at least
    // half of the step just found: that step is withdrawn. Otherwise it is the residue of
    // the step's estimate. Either way the search ends here.
    const double prev_size = out.effects.back().size;
    const double this_size = best.size_counts * lsb;
    const bool undoes = out.effects.back().type == "bias_step" && this_size * prev_size < 0.0 &&
                        std::fabs(this_size) >= 0.5 * std::fabs(prev_size);
    // At (nearly) the same sample the step is undone where it was found: no step, and no
    // time range either (a blip of the noise the first window took for a step).
    const double dist = std::fabs(at - static_cast<double>(step_at.back()));
    const bool blip = dist < best_window / 8.0;
    if (undoes) {
      const auto from = static_cast<std::size_t>(step_at.back());
      shift_level(from, prev_size);
      out.notes.push_back(std::string(blip ? "not a step" : "transient, not a step") +
                          ": the level shift at t = " +
                          fmt("%.1f", static_cast<double>(from) * ts) + " s is undone at t = " +
                          fmt("%.1f", at * ts) + " s, within one window");
      UnexplainedRun u;
      u.t_min_s = std::min(static_cast<double>(from), at) * ts;
      u.t_max_s = std::max(static_cast<double>(from), at) * ts;
      u.tau_min_s = u.t_max_s - u.t_min_s;
      u.tau_max_s = best_window * ts;
      u.max_abs_z = std::fabs(best.z);
      u.what = "a level shift of " + fmt("%.3g", prev_size) + " undone after " +
               fmt("%.3g", u.t_max_s - u.t_min_s) + " s (a transient, not a step)";
      if (!blip) {
        time_ranges.push_back(u);
      }
      step_at.pop_back();
      out.effects.pop_back();
      refresh_adev();
    } else {
      out.notes.push_back("step search stopped: a further excursion at t = " +
                          fmt("%.1f", at * ts) +
                          " s lies within one window of a step already found (its residue)");
    }
  }

  // Level shifts above the step threshold at kRepeatedShiftPlaces separate places or more (a
  // sawtooth, periodic resets, a square wave): one effect of the record's kind, not a few steps
  // the model could hold. Naming three of them steps would leave the rest unsaid; they are one
  // unexplained time range and no step is searched. A few events stay steps (the shared
  // ADIS16405 accelerometers show 4 to 7 places at the strongest scale: a step and a 20 s
  // excursion on all three axes at once, and single shifts). sp: the places on the record as it
  // stands; steps named before are places too, withdrawn here (withdraw_steps).
  static constexpr std::size_t kRepeatedShiftPlaces = 10;
  void repeated_shifts(ShiftPlaces sp, const StepEvent& best, double best_window) {
    shifts_repeat = true;
    for (const double t : withdraw_steps()) {
      ++sp.places;
      sp.t_first_s = std::min(sp.t_first_s, t);
      sp.t_last_s = std::max(sp.t_last_s, t);
    }
    UnexplainedRun u;
    u.t_min_s = sp.t_first_s;
    u.t_max_s = sp.t_last_s;
    u.tau_min_s = best_window * ts / 8.0;
    u.tau_max_s = best_window * ts;
    u.max_abs_z = std::fabs(best.z);
    u.what = std::to_string(sp.places) + " level shifts of median size " +
             fmt("%.3g", sp.median_size) +
             (sp.median_spacing_s > 0.0 ? " about every " + fmt("%.3g", sp.median_spacing_s) + " s"
                                        : std::string()) +
             " (repeated: resets, stick-slip or telegraph noise, not a bias step)";
    time_ranges.push_back(u);
    out.notes.push_back("step search stopped: level shifts above the threshold at " +
                        std::to_string(sp.places) + " separate places from t = " +
                        fmt("%.1f", sp.t_first_s) + " to " + fmt("%.1f", sp.t_last_s) +
                        " s, more than the " + std::to_string(o.max_steps) +
                        " steps searched: a repeated effect, reported as unexplained");
  }

  // The bias steps named so far are withdrawn (the record takes them back); returns their times.
  std::vector<double> withdraw_steps() {
    std::vector<double> at_s;
    std::size_t j = 0;
    for (auto e = out.effects.begin(); e != out.effects.end();) {
      if (e->type != "bias_step" || j >= step_at.size()) {
        ++e;
        continue;
      }
      shift_level(static_cast<std::size_t>(step_at[j]), e->size);
      at_s.push_back(static_cast<double>(step_at[j++]) * ts);
      e = out.effects.erase(e);
    }
    if (!step_at.empty()) {
      step_at.clear();
      refresh_adev();
    }
    return at_s;
  }

  void find_steps_by_windows() {
    // ---- time domain: bias steps (two-window detector at several scales)
    for (int step_no = 0; step_no < o.max_steps; ++step_no) {
      StepEvent best{};
      double best_window = 0.0;
      double thr = 0.0;
      ShiftPlaces places;
      if (!strongest_step(best, best_window, thr, places)) {
        break;
      }
      if (places.places >= kRepeatedShiftPlaces) {
        repeated_shifts(places, best, best_window);
        break;
      }
      // A second "step" within one window of an earlier one is the other edge of a transient (or
      // the residue of the first estimate), not a new step: stop there and say so.
      bool near_previous = false;
      for (const std::uint64_t prev : step_at) {
        const double dist =
            std::fabs(static_cast<double>(best.sample_index) - static_cast<double>(prev));
        near_previous = near_previous || dist < best_window;
      }
      const double at = static_cast<double>(best.sample_index);
      if (at < best_window || n_d - at < best_window) {
        edge_excursion(best, best_window);
        break;
      }
      if (near_previous) {
        near_previous_step(best, best_window);  // either way the search ends here
        break;
      }
      if (!window_step_beats_decay(best.sample_index)) {
        break;
      }
      const RefinedStep rs = refine_step(best.sample_index, best_window);
      const std::size_t k = rs.sample;
      const double size = window_step_size(k, best_window);
      step_at.push_back(k);
      Effect e;
      e.type = "bias_step";
      e.time_s = static_cast<double>(k) * ts;
      e.time_lo_s = static_cast<double>(rs.first) * ts;
      e.time_hi_s = static_cast<double>(rs.last) * ts;
      e.size = size;
      e.statistic = std::fabs(best.z);
      e.threshold = thr;
      out.effects.push_back(e);
      shift_level(k, -e.size);
      restore_step_outliers(k, best_window / 8.0, size);
      refresh_adev();
    }
  }

  // The record's value at i as measured: an outlier's replacement undone.
  [[nodiscard]] double measured(std::size_t i) const {
    const auto it = std::lower_bound(
        outlier_delta.begin(), outlier_delta.end(), i,
        [](const std::pair<std::size_t, double>& a, std::size_t b) { return a.first < b; });
    return it != outlier_delta.end() && it->first == i ? y[i] + it->second : y[i];
  }

  // The window detector places a step at a block boundary of its scale. The step's sample is
  // the maximum-likelihood change point within one block either side, the levels on each side
  // taken from the detector's windows outside that zone (white noise within the zone; a
  // Gauss-Markov drift is a level over one block): argmax over k of sum_{i<k} (mL - mR)
  // (2 y_i - mL - mR), which is 2 sd^2 times the log-likelihood of k (sd: the white noise's std
  // per sample). Its 95 % set: the k within kChangePointSet95 of the best in 2 ln LR, cut at the
  // zone's ends, and one sample either side (a step between two samples is at either). The zone
  // is read as measured: the before filter's "outliers" right after a large step are the step's
  // first samples.
  struct RefinedStep {
    std::size_t sample = 0;
    std::size_t first = 0;  ///< the 95 % set of `sample`: from
    std::size_t last = 0;   ///< to
  };
  [[nodiscard]] RefinedStep refine_step(std::uint64_t at_u, double window) const {
    const auto at = static_cast<std::size_t>(at_u);
    const auto w = static_cast<std::size_t>(window);
    const std::size_t blk = std::max<std::size_t>(1, w / 8);
    if (at < w || at + w > y.size() || w <= 2 * blk) {
      return RefinedStep{at, at, at};
    }
    double m_l = 0.0;
    double m_r = 0.0;
    for (std::size_t i = at - w; i < at - blk; ++i) {
      m_l += y[i];
    }
    for (std::size_t i = at + blk; i < at + w; ++i) {
      m_r += y[i];
    }
    m_l /= static_cast<double>(w - blk);
    m_r /= static_cast<double>(w - blk);
    std::vector<double> sums(2 * blk + 1, 0.0);  // sums[j]: the step at at - blk + j
    std::size_t best = 0;
    for (std::size_t j = 1; j < sums.size(); ++j) {
      sums[j] = sums[j - 1] + (m_l - m_r) * (2.0 * measured(at - blk + j - 1) - m_l - m_r);
      best = sums[j] > sums[best] ? j : best;
    }
    const double white_var = out.model_before.n * out.model_before.n / ts;
    for (double& v : sums) {
      v = white_var > 0.0 ? v / white_var : 0.0;  // 2 ln L (no white level: the whole zone)
    }
    const PositionRange set = change_point_set(sums, best);
    const std::size_t first = at - blk + set.first;
    return RefinedStep{at - blk + best, first - (first > 0 ? 1 : 0), at - blk + set.last + 1};
  }

  // The step's size at sample k: the difference of the means of the two windows either side,
  // read as measured within one block of k (as refine_step reads them).
  [[nodiscard]] double window_step_size(std::size_t k, double window) const {
    const auto w = std::min({static_cast<std::size_t>(window), k, y.size() - k});
    const std::size_t blk = std::max<std::size_t>(1, static_cast<std::size_t>(window) / 8);
    if (w == 0) {
      return 0.0;
    }
    double before = 0.0;
    double after = 0.0;
    for (std::size_t j = 0; j < w; ++j) {
      before += j < blk ? measured(k - 1 - j) : y[k - 1 - j];
      after += j < blk ? measured(k + j) : y[k + j];
    }
    return (after - before) / static_cast<double>(w);
  }

  // The before filter's outliers within one block after a step it had not seen: at each the
  // filter predicted the old level. With the step removed, the sample as measured is kept where
  // it no longer passes the outlier gate (its innovation less the step); the outliers effect
  // loses it.
  void restore_step_outliers(std::size_t k, double block, double size) {
    const auto end = std::min(y.size(), k + static_cast<std::size_t>(std::max(1.0, block)));
    std::size_t restored = 0;
    for (auto it = outlier_delta.begin(); it != outlier_delta.end();) {
      const std::size_t i = it->first;
      const double limit =
          gate_part(i, outlier_split, outlier_guard, outlier_limit_a, outlier_limit_b) == 0
              ? outlier_limit_a
              : outlier_limit_b;
      if (i >= k && i < end && std::fabs(it->second - size) <= limit) {
        y[i] += it->second;
        outlier[i] = gap.empty() ? 0 : gap[i];
        it = outlier_delta.erase(it);
        ++restored;
      } else {
        ++it;
      }
    }
    if (restored == 0) {
      return;
    }
    for (auto e = out.effects.begin(); e != out.effects.end(); ++e) {
      if (e->type != "outliers") {
        continue;
      }
      e->count = e->count > restored ? e->count - restored : 0;
      std::vector<double> times;
      for (const auto& [i, d] : outlier_delta) {
        if (times.size() < 100) {
          times.push_back(static_cast<double>(i) * ts);
        }
      }
      e->times_s = times;
      if (e->count == 0) {
        out.effects.erase(e);
      }
      break;
    }
    out.notes.push_back(std::to_string(restored) +
                        (restored == 1 ? " outlier" : " outliers") +
                        " of the before-model's innovations within one block after the step at "
                        "t = " + fmt("%.1f", static_cast<double>(k) * ts) + " s " +
                        (restored == 1 ? "is the step's sample" : "are the step's samples"));
  }

  // The alternatives to a significant level shift with one parameter each: a walk (K) and bias
  // instability (B, started from the data's ADEV at T/100 taken as its floor); the step has one
  // parameter more (its time) and must beat them by AIC's penalty of 2 per parameter. When the
  // walk explains the record better, the step is still taken if it is significant beside the
  // walk (the profile again, H0 the walk's model: a walk does not make one increment that
  // stands out at the level over all positions) at the same place, within kSameStepFraction of
  // the record (elsewhere it is another event, e.g. a transient the walk's model leaves at the
  // start); the walk is then tested beside the step.
  // A walk the record's likelihood needs on its own (2 ln LR above the walk test's level) is
  // the rival a step must stand beside, whatever their likelihoods against H0: a walk's wander
  // gathered at one place raises the step's profile as much as a step does (GM + walk records
  // of 1 and 2 h: 2 ln LR 17 to 32 against H0 for the step, 8 to 25 for the walk, 8 to 14 for
  // the step beside the walk; steps of 2 to 3 GM sigmas in 1 to 3 h: 17 to 26, 4 to 20 and 8 to
  // 16). A shift that does not stand beside such a walk is a step or the walk's wander, which
  // the record does not tell apart: it is taken out of the record as a step is (the model is
  // fitted without it; the walk is then tested beside it) but not named: `unnamed`, reported as
  // an unexplained time range (find_steps_by_likelihood).
  // sl: the step taken (its time and size beside the walk in that case); why: what it beat.
  static constexpr double kSameStepFraction = 0.05;

  // The step profile beside a rival (sb: the profile with the rival in H0 or removed from the
  // means) still holds the step sl: significant (> thr) within kSameStepFraction of it.
  [[nodiscard]] bool step_stands_beside(const StepLikelihood& sb, const StepLikelihood& sl,
                                        double thr) const {
    const double moved = std::fabs(static_cast<double>(sb.sample) - static_cast<double>(sl.sample));
    return sb.ok && std::isfinite(sb.size) && sb.lr > thr &&
           moved <= kSameStepFraction * static_cast<double>(y.size());
  }

  // "beside the <rival> it is still significant (2 ln LR = .. > thr at t = .. s)"
  [[nodiscard]] std::string still_significant(const char* rival, const StepLikelihood& sb,
                                              double thr) const {
    return std::string("beside the ") + rival + " it is still significant (2 ln LR = " +
           fmt("%.1f", sb.lr) + " > " + fmt("%.1f", thr) + " at t = " +
           fmt("%.1f", static_cast<double>(sb.sample) * ts) + " s)";
  }
  bool step_beats_alternatives(const RrwLikelihoodTest& lt, const ModelParams& b0, double thr,
                               std::size_t margin, StepLikelihood& sl, std::string& why,
                               unsigned& unnamed_by) {
    RrwLikelihoodTest with_bi;
    const double lr_bi = bias_instability_lr(y, ts, b0, tb_max, step_at, adev_y, lt, &with_bi);
    constexpr double kAicPenalty = 2.0;
    const double lr_alt = std::max(lt.lr, lr_bi) + kAicPenalty;
    const double lr_level = chi2_quantile(1.0 - o.alpha, 1.0);
    // A rival that made an earlier shift unnamed stays needed: the level reset at that shift
    // took part of the wander that was its evidence.
    const bool walk_needed =
        lt.h1.ok && ((lt.lr > lr_level && lt.lr >= lr_bi) || (shift_rivals & kRivalWalk) != 0U);
    // Bias instability the record needs on its own is a rival as the walk is: flicker noise's
    // wander gathers at one place as a walk's does.
    const bool bi_needed =
        with_bi.ok && ((lr_bi > lr_level && lr_bi > lt.lr) || (shift_rivals & kRivalBi) != 0U);
    RrwLikelihoodTest beside_walk = lt;  // the walk in H0
    beside_walk.h0 = lt.h1;
    if (sl.lr > lr_alt) {
      why = "> a walk's or bias instability's " + fmt("%.1f", lr_alt);
      if (walk_needed &&
          !step_beside_needed_rival(beside_walk, "walk", lt.lr, thr, margin, sl, why)) {
        unnamed_by |= kRivalWalk;
      }
      if (bi_needed && !step_beside_needed_rival(with_bi, "bias instability", lr_bi, thr,
                                                 margin, sl, why)) {
        unnamed_by |= kRivalBi;
      }
      return true;
    }
    const std::string at = "a level shift at t = " +
                           fmt("%.1f", static_cast<double>(sl.sample) * ts) +
                           " s is significant (2 ln LR = " + fmt("%.1f", sl.lr) + ") but ";
    if (lt.lr >= lr_bi && lt.h1.ok) {
      const StepLikelihood sw = profile_step(beside_walk, margin);
      if (step_stands_beside(sw, sl, thr)) {
        out.notes.push_back(at + "a walk explains the record better (" + fmt("%.1f", lt.lr) +
                            "); " + still_significant("walk", sw, thr));
        sl = sw;
        why = "beside the walk, above";
        return true;
      }
    }
    // The rivals beside the step: a walk or bias instability of which the record shows no sign
    // once the step is in the model only explained the step, if the step, at its place, is
    // significant beside the walk (2 ln LR > chi-square(1) at 1 - alpha, its place fixed). "No
    // sign": 2 ln LR below the 5 % point of its null distribution (the parameter on its bound:
    // half chi-square(1), half 0; Self and Liang, JASA 82(398), 1987), 2.71. The walk's own
    // test (6.63) is too lax here: on a walk record the step takes the walk's largest excursion
    // and leaves it 3.7 to 6.4; and a walk's excursion the record shows no walk beside is no
    // step where the walk's model, at that place, makes it insignificant (4.6 on one record).
    std::vector<std::uint64_t> with_step = step_at;
    with_step.push_back(sl.sample);
    const RrwLikelihoodTest ls = test_rrw(y, ts, b0, tb_max, false, with_step, kAuxBlocks);
    const double lr_rival_beside =
        std::max(ls.lr, bias_instability_lr(y, ts, b0, tb_max, with_step, adev_y, ls));
    const double no_sign = chi2_quantile(0.90, 1.0);
    const double lr_at_place =
        lt.h1.ok
            ? profile_step(beside_walk, 1, static_cast<std::size_t>(sl.sample / lt.per_block)).lr
            : 0.0;
    if (ls.ok && lr_rival_beside <= no_sign && lr_at_place > lr_level) {
      out.notes.push_back(at + "a walk or bias instability explains the record as well (" +
                          fmt("%.1f", std::max(lt.lr, lr_bi)) + ") only without the step: "
                          "beside the step the record shows no sign of either (2 ln LR " +
                          fmt("%.1f", lr_rival_beside) + " <= " + fmt("%.2f", no_sign) +
                          "), and at its place beside the walk the step is significant (" +
                          fmt("%.1f", lr_at_place) + " > " + fmt("%.2f", lr_level) + ")");
      why = "neither a walk nor bias instability beside it, above";
      if (walk_needed) {  // it does not stand beside the walk (above)
        unnamed_by |= kRivalWalk;
        why = "a walk " + fmt("%.1f", lt.lr) + " beside which it is not significant";
      }
      if (bi_needed && !step_beside_needed_rival(with_bi, "bias instability", lr_bi, thr, margin,
                                                 sl, why)) {
        unnamed_by |= kRivalBi;
      }
      return true;
    }
    out.notes.push_back(at + (lt.lr >= lr_bi ? "a walk" : "bias instability") +
                        " explains the record nearly as well (" +
                        fmt("%.1f", std::max(lt.lr, lr_bi)) + ", + 2 for the step's time):"
                        " not named a step");
    rival_shift = RivalShift{true, sl, lt.block_s,
                             std::string(lt.lr >= lr_bi ? "a walk" : "bias instability") +
                                 " explains the record nearly as well, " +
                                 fmt("%.1f", std::max(lt.lr, lr_bi)),
                             lt.lr >= lr_bi ? kRivalWalk : kRivalBi};
    return false;
  }

  // A shift a walk or bias instability explained nearly as well (step_beats_alternatives: not
  // named a step, left in the record) while the model after holds neither, nor a GM that took
  // a walk's place (slow_gm_for_walk: the same reading of the wander). Tried again against the
  // model after (its GMs, its ramp's line removed, its sinusoids out of the record: a ramp the
  // search takes later bends the record as the shift did): where it is still significant at its
  // place (step_stands_beside, the step search's threshold), nothing in the report accounts for
  // it, and it is an unexplained time range over its 95 % set there, as a shift taken out
  // unnamed is (walk_or_step_range), unless a time range already holds its time.
  void add_rival_shift_range() {
    const ModelParams& m = out.model_after;
    if (!rival_shift.found || m.k > 0.0 || m.bi > 0.0 || slow_gm.tb_s > 0.0) {
      return;
    }
    const double t_s = static_cast<double>(rival_shift.sl.sample) * ts;
    for (const UnexplainedRun& u : out.unexplained) {
      if (u.t_max_s > u.t_min_s && u.t_min_s <= t_s && t_s <= u.t_max_s) {
        return;
      }
    }
    const RrwLikelihoodTest lt =
        test_rrw(fit_record(), ts, m, tb_max, m.r > 0.0, step_at, kAuxBlocks, false);
    if (!lt.ok) {
      return;
    }
    const StepLikelihood sw = profile_step(lt, step_margin(lt));
    if (!step_stands_beside(sw, rival_shift.sl, step_threshold(lt, sw.positions))) {
      return;
    }
    UnexplainedRun u = walk_or_step_range(sw, lt.block_s, rival_shift.why, rival_shift.rivals);
    u.what = u.what.substr(0, u.what.rfind("; the model is fitted without it")) +
             "; the model after holds neither";
    out.unexplained.push_back(u);
    out.notes.push_back("not named: " + u.what);
  }

  // A step sl that beats a rival the record needs on its own (a walk or bias instability, its
  // 2 ln LR lr_rival above its level; beside: the test with the rival in H0): true when it
  // stands beside the rival (why says so; sl, its estimate against H0, is kept).
  bool step_beside_needed_rival(const RrwLikelihoodTest& beside, const char* rival,
                                double lr_rival, double thr, std::size_t margin,
                                const StepLikelihood& sl, std::string& why) {
    const StepLikelihood sw = profile_step(beside, margin);
    if (step_stands_beside(sw, sl, thr)) {
      why += "; " + still_significant(rival, sw, thr);
      return true;
    }
    why = std::string("the ") + rival + " " + fmt("%.1f", lr_rival) + "; beside it the step " +
          fmt("%.1f", sw.ok ? sw.lr : 0.0) + " <= " + fmt("%.1f", thr);
    return false;
  }

  // A level that decays from the start of the record (a warm-up transient, A e^(-t / tau): two
  // parameters, as the step has its size and time) raises the step profile too, at a boundary
  // inside the decay. When the decay explains the record at least as well as the step (and is
  // significant over its tau grid, and the shift lies within three of its time constants), the
  // step is taken only if it stands beside the decay (step_stands_beside; the block means less
  // the fitted decay, H0 unchanged); sl is then the step beside the decay. Otherwise no step is
  // named here and the decay is left to the transient check (an unexplained time range).
  bool step_beats_decay(const RrwLikelihoodTest& lt, double thr, std::size_t margin,
                        StepLikelihood& sl) {
    const TransientLr tr = warmup_transient_lr(lt, false);
    const double tr_thr = transient_threshold();
    // Beyond three time constants the decay has fallen to 5 %: it does not make a shift there.
    // A decay that a walk or a line explains nearly as well (by AIC's 2 for its tau, as in
    // warmup_transient_check) is slow wander, not a transient: the step's rivals above decide.
    const double at_s = static_cast<double>(sl.sample) * ts;
    constexpr double kAicPenalty = 2.0;
    if (!(tr.lr > tr_thr) || tr.lr < sl.lr || at_s > 3.0 * tr.tau_s ||
        !(tr.lr > std::max(lt.lr, line_lr(lt, false)) + kAicPenalty)) {
      return true;
    }
    RrwLikelihoodTest beside = lt;
    const std::vector<double> u = decay_regressor(lt.means.size(), lt.block_s, tr.tau_s, false);
    for (std::size_t k = 0; k < u.size(); ++k) {
      beside.means[k] -= tr.size * u[k];
    }
    const StepLikelihood sd = profile_step(beside, margin);
    const std::string at = "a level shift at t = " + fmt("%.1f", at_s) +
                           " s is significant (2 ln LR = " + fmt("%.1f", sl.lr) +
                           ") but a level decaying from the start of the record (time constant " +
                           fmt("%.3g", tr.tau_s) + " s) explains it as well (" +
                           fmt("%.1f", tr.lr) + ")";
    if (step_stands_beside(sd, sl, thr)) {
      out.notes.push_back(at + "; " + still_significant("decay", sd, thr));
      sl = sd;
      return true;
    }
    out.notes.push_back(at + ": not named a step");
    return false;
  }

  // The blocks a step profile leaves at either end of the test's means.
  [[nodiscard]] static std::size_t step_margin(const RrwLikelihoodTest& lt) {
    return std::max<std::size_t>(2, lt.means.size() / 100);
  }

  // A step's threshold: chi-square(1) at cost_alpha over the effectively independent positions.
  [[nodiscard]] double step_threshold(const RrwLikelihoodTest& lt, std::size_t positions) const {
    return chi2_quantile(1.0 - o.cost_alpha / independent_positions(lt, positions), 1.0);
  }

  // The step profile's positions counted four per slowest correlation time of H0 (see
  // find_steps_by_likelihood).
  [[nodiscard]] static double independent_positions(const RrwLikelihoodTest& lt,
                                                    std::size_t positions) {
    double tb_slow = lt.block_s;
    for (std::size_t g = 0; g < lt.h0.model.n_gm; ++g) {
      tb_slow = std::max(tb_slow, lt.h0.model.gm[g].tb_s);
    }
    return std::max(1.0, 4.0 * static_cast<double>(positions) * lt.block_s / tb_slow);
  }

  // A step the two windows found, against a decay from the start of the record
  // (step_beats_decay), on the record's likelihood at its block boundary; H0 as in
  // find_steps_by_likelihood. True when the step stands (or cannot be tested).
  bool window_step_beats_decay(std::uint64_t sample) {
    const FitResult b0 = step_search_base();
    if (b0.status != FitStatus::kOk) {
      return true;
    }
    const RrwLikelihoodTest lt = test_rrw(y, ts, b0.params, tb_max, false, step_at, kAuxBlocks);
    if (!lt.ok || lt.per_block == 0) {
      return true;
    }
    const std::size_t margin = step_margin(lt);
    // (at its own boundary, also one inside the profile's margin: the windows place it there)
    StepLikelihood sl = profile_step(lt, 1, static_cast<std::size_t>(sample / lt.per_block));
    if (!sl.ok || lt.means.size() <= 2 * margin) {
      return true;
    }
    return step_beats_decay(lt, step_threshold(lt, lt.means.size() - 2 * margin), margin, sl);
  }

  // H0's start for the step search: white + one GM over [Ts, T/10]; where that fit fails (a
  // record whose quantization bends the short taus), white + quantization + one GM.
  [[nodiscard]] FitResult step_search_base() const {
    const FitResult b0 = fit_terms(adev_y.by_alpha[2], kFitWhite | kFitGm1, ts, tau_max, tb_max);
    if (b0.status == FitStatus::kOk) {
      return b0;
    }
    return fit_terms(adev_y.by_alpha[2], kFitWhite | kFitQuantization | kFitGm1, ts, tau_max,
                     tb_max);
  }

  void find_steps_by_likelihood() {
    // ---- bias steps by the record's likelihood: a level shift at the best block boundary
    // (profile over the boundaries) against H0 (white + GMs, tb <= tb_max), taken when it is
    // significant over all the positions tried AND explains the record better than a walk would
    // (a walk also raises the step profile; a step also raises the walk's likelihood).
    while (!shifts_repeat && static_cast<int>(step_at.size()) < o.max_steps) {
      const FitResult b0 = step_search_base();
      if (b0.status != FitStatus::kOk) {
        break;
      }
      const RrwLikelihoodTest lt = test_rrw(y, ts, b0.params, tb_max, false, step_at, kAuxBlocks);
      const std::size_t margin = step_margin(lt);
      StepLikelihood sl = profile_step(lt, margin);
      if (!sl.ok || sl.positions == 0) {
        break;
      }
      // At a step already found the level is reset in the blocks around it and a second step
      // there is not identifiable (its GLS size is ill-conditioned): the residue of that step.
      bool at_previous = !std::isfinite(sl.size);
      for (const std::uint64_t prev : step_at) {
        const double dist = std::fabs(static_cast<double>(sl.sample) - static_cast<double>(prev));
        at_previous = at_previous || dist <= 2.0 * static_cast<double>(lt.per_block);
      }
      if (at_previous) {
        break;
      }
      // Bonferroni over the effectively independent boundaries, counted four per slowest
      // correlation time of H0: the statistics at boundaries closer than that are nearly the
      // same (counting every block boundary made the test blind to a 3-sigma step; one per
      // correlation time gave false steps on 2 of 20 controls); level: the ADEV tests' 1 %.
      const double eff_positions = independent_positions(lt, sl.positions);
      const double thr = step_threshold(lt, sl.positions);
      std::string why;
      unsigned unnamed_by = 0;
      const bool plain_step =
          sl.lr > thr && step_beats_alternatives(lt, b0.params, thr, margin, sl, why, unnamed_by) &&
          step_beats_decay(lt, thr, margin, sl);
      if (!plain_step) {
        if (!step_beside_line(lt, b0.params, margin, sl, why)) {
          break;
        }
        unnamed_by = 0;
        rival_shift = RivalShift{};  // the shift a rival explained is the step beside the line
      }
      step_at.push_back(sl.sample);
      if (unnamed_by != 0U) {
        shift_rivals |= unnamed_by;
        unnamed_shifts.push_back(UnnamedShift{sl, thr, time_ranges.size(), unnamed_by});
        time_ranges.push_back(walk_or_step_range(sl, lt.block_s, why, unnamed_by));
        out.notes.push_back("not named: " + time_ranges.back().what);
        shift_level(sl.sample, -sl.size);
        refresh_adev();
        continue;
      }
      out.effects.push_back(step_effect(sl, thr));
      out.notes.push_back("bias step at t = " + fmt("%.1f", out.effects.back().time_s) +
                          " s from the record's profile likelihood (2 ln LR = " +
                          fmt("%.1f", sl.lr) + " > " + fmt("%.1f", thr) + " over " +
                          fmt("%.0f", eff_positions) + " independent positions, and " +
                          why + ")");
      shift_level(sl.sample, -sl.size);
      refresh_adev();
    }
  }

  // A ramp and a step together: the step's profile with the record's line fitted beside it in
  // both hypotheses (profile_step's nuisance). A ramp tilts the plain profile (its best shift
  // lands mid-ramp, where the line departs most from a level) and a walk explains a line plus
  // a shift better than either alone. The pair (slope, size, time) is taken when the line is
  // significant on its own (2 ln LR above the walk test's level), the step beside it over all
  // positions (thr, the plain search's), together they beat the walk by AIC's 2 for each of
  // their two parameters more, and neither a walk nor bias instability is needed beside them
  // (on the block means less the line and the step). sl and why then hold the step.
  bool step_beside_line(const RrwLikelihoodTest& lt, const ModelParams& b0, std::size_t margin,
                        StepLikelihood& sl, std::string& why) {
    const double lr_level = chi2_quantile(1.0 - o.alpha, 1.0);
    const double lr_line = line_lr(lt, false);
    if (!(lr_line > lr_level)) {
      return false;
    }
    const std::vector<double> line = trend_regressor(lt.means.size(), 1);
    const StepLikelihood sd = profile_step(lt, margin, kEveryBlock, &line);
    const double thr = step_threshold(lt, sd.positions);
    constexpr double kAicTwoMore = 4.0;
    if (!sd.ok || !std::isfinite(sd.size) || !(sd.lr > thr) ||
        !(sd.lr + lr_line > lt.lr + kAicTwoMore)) {
      return false;
    }
    for (const std::uint64_t prev : step_at) {
      if (std::fabs(static_cast<double>(sd.sample) - static_cast<double>(prev)) <=
          2.0 * static_cast<double>(lt.per_block)) {
        return false;
      }
    }
    // The block means less the step and the line (both fitted: GLS size, least-squares line).
    std::vector<double> m = lt.means;
    for (std::size_t k = sd.sample / lt.per_block; k < m.size(); ++k) {
      m[k] -= sd.size;
    }
    remove_mean_and_line(m, true);
    const RrwLikelihoodTest lw = test_rrw_on_means(m, lt.per_block, ts, b0, tb_max, step_at);
    if (!lw.ok) {
      return false;
    }
    const double lr_bi =
        bias_instability_lr(y, ts, b0, tb_max, step_at, adev_y, lw, nullptr, &m);
    if (std::max(lw.lr, lr_bi) > lr_level) {
      return false;
    }
    out.notes.push_back("a level shift at t = " +
                        fmt("%.1f", static_cast<double>(sd.sample) * ts) +
                        " s beside the record's line: 2 ln LR = " + fmt("%.1f", sd.lr) + " > " +
                        fmt("%.1f", thr) + ", with the line's " + fmt("%.1f", lr_line) +
                        " above a walk's " + fmt("%.1f", lt.lr) + " + 4; beside both no walk (" +
                        fmt("%.1f", lw.lr) + ") or bias instability (" + fmt("%.1f", lr_bi) +
                        ") <= " + fmt("%.2f", lr_level));
    sl = sd;
    why = "beside the record's line, above";
    return true;
  }

  // The bias step of a profile's best shift sl that passed the threshold thr.
  [[nodiscard]] Effect step_effect(const StepLikelihood& sl, double thr) const {
    Effect e;
    e.type = "bias_step";
    e.time_s = static_cast<double>(sl.sample) * ts;
    e.time_lo_s = static_cast<double>(sl.first_sample) * ts;
    e.time_hi_s = static_cast<double>(sl.last_sample) * ts;
    e.size = sl.size;
    e.statistic = std::sqrt(sl.lr);  // |z| of the GLS size, as the window detector's
    e.threshold = std::sqrt(thr);
    return e;
  }

  // The rival that made a shift unnamed (a walk, bias instability) was tested against H0 =
  // white + GMs before the model's other terms were found (a sinusoid or ramp the search takes
  // later raises both the rival's 2 ln LR and the noise the step is measured against). With the
  // model as it ends (without that rival), on the record with the shift put back: when it needs
  // no such rival (2 ln LR <= the walk test's level), or the shift stands beside it (as in
  // step_beats_alternatives, with the final model's terms in both hypotheses), it is a step and
  // is named; its time range leaves `unexplained`. (A model that holds the rival keeps the
  // range.)
  void settle_unnamed_shifts() {
    for (auto it = unnamed_shifts.rbegin(); it != unnamed_shifts.rend(); ++it) {
      const StepLikelihood& sl = it->sl;
      const bool walk = (it->rivals & kRivalWalk) != 0U;
      const bool bi = (it->rivals & kRivalBi) != 0U;
      if ((walk && (terms & kFitRrw) != 0U) || (bi && (terms & kFitFlicker) != 0U)) {
        continue;
      }
      // Every shift still unnamed is put back: each held part of the rival's evidence.
      std::vector<double> with_shift = fit_record();
      std::vector<std::uint64_t> others = step_at;
      for (const UnnamedShift& u : unnamed_shifts) {
        if (u.named) {
          continue;
        }
        for (std::size_t i = u.sl.sample; i < with_shift.size(); ++i) {
          with_shift[i] += u.sl.size;
        }
        others.erase(std::remove(others.begin(), others.end(), u.sl.sample), others.end());
      }
      RrwLikelihoodTest lt = test_rrw(with_shift, ts, cur_p, tb_max, (terms & kFitRamp) != 0U,
                                      others, kAuxBlocks);
      if (!lt.ok) {
        continue;
      }
      std::string why;
      if (walk && !settled_beside(lt, "walk", lt.lr, sl, why)) {
        continue;
      }
      if (bi) {
        RrwLikelihoodTest with_bi;
        const double lr_bi =
            bias_instability_lr(with_shift, ts, cur_p, tb_max, others, adev_y, lt, &with_bi);
        if (!with_bi.ok || !settled_beside(with_bi, "bias instability", lr_bi, sl, why)) {
          continue;
        }
      }
      it->named = true;
      out.effects.push_back(step_effect(sl, it->thr));
      time_ranges.erase(time_ranges.begin() + static_cast<std::ptrdiff_t>(it->range));
      out.notes.push_back("bias step at t = " + fmt("%.1f", out.effects.back().time_s) +
                          " s after all: with the model's terms " + why);
    }
  }

  // settle_unnamed_shifts for one rival (lr its 2 ln LR on the record with the shift, rival.h1
  // the model with it): true when the record needs no such rival or the shift stands beside it;
  // why gains the reason.
  bool settled_beside(RrwLikelihoodTest rival, const char* name, double lr,
                      const StepLikelihood& sl, std::string& why) const {
    if (!(lr > lr_thr)) {
      why += std::string(why.empty() ? "" : "; ") + "the record with it needs no " + name +
             " (2 ln LR = " + fmt("%.1f", lr) + " <= " + fmt("%.2f", lr_thr) + ")";
      return true;
    }
    rival.h0 = rival.h1;
    const StepLikelihood sw = profile_step(rival, step_margin(rival));
    const double thr = step_threshold(rival, sw.positions);
    if (!step_stands_beside(sw, sl, thr)) {
      return false;
    }
    why += std::string(why.empty() ? "" : "; ") + still_significant(name, sw, thr);
    return true;
  }

  // A level shift no walk rules in or out (step_beats_alternatives' `unnamed`): an unexplained
  // time range over its 95 % set, from the likelihood test's block up to T/10.
  [[nodiscard]] UnexplainedRun walk_or_step_range(const StepLikelihood& sl, double block_s,
                                                  const std::string& why,
                                                  unsigned rivals) const {
    UnexplainedRun u;
    u.t_min_s = static_cast<double>(sl.first_sample) * ts;
    u.t_max_s = static_cast<double>(sl.last_sample) * ts;
    u.tau_min_s = block_s;
    u.tau_max_s = tau_max;
    u.max_abs_z = std::sqrt(sl.lr);
    u.what = "a level shift of " + fmt("%.3g", sl.size) + " at t = " +
             fmt("%.1f", static_cast<double>(sl.sample) * ts) + " s (2 ln LR = " +
             fmt("%.1f", sl.lr) + ", " + why + "): a bias step or the wander of " +
             ((rivals & kRivalWalk) != 0U
                  ? ((rivals & kRivalBi) != 0U ? "a rate random walk or bias instability"
                                               : "a rate random walk")
                  : "bias instability") +
             ", which the record does not tell apart; the model is fitted without it";
    return u;
  }

  // The greedy ADEV term search over [Ts, T/10] of the cleaned record.
  // The greedy ADEV term search over [Ts, T/10] of the cleaned record: while a significant run
  // of the residual remains, every candidate term is fitted jointly with the terms so far and
  // the best one is taken if its cost drop passes the test.
  bool select_terms() {
    // ---- ADEV residual over [Ts, T/10] of the cleaned record, greedy term selection
    const AdevSet& clean = adev_y;
    const std::uint32_t base_terms = kFitWhite | kFitGm1;
    const FitResult base0 = fit_terms(clean.by_alpha[2], base_terms, ts, tau_max, tb_max);
    if (base0.status != FitStatus::kOk) {
      // Finite data always gets a report: the first-order model fitted before stands, unsearched.
      out.notes.push_back("the white + GM fit over [Ts, T/10] failed (" +
                          std::string(fit_status_text(base0.status)) +
                          "): the model after is the model before, no term searched");
      terms = base_terms;
      cur_p = out.model_before;
      eval = in_range(points_for_model(clean, cur_p), tau_max);
      fit_set = clean;
      fit_pts = eval;
      cur_cost = residual(eval, cur_p, o, ts, tau_max).cost;
      y_minus_sine = std::vector<double>{};  // the record itself
      return true;
    }
    eval = in_range(points_for_model(clean, base0.params), tau_max);
    fit_set = clean;
    fit_pts = eval;
    terms = base_terms;
    FitResult cur = fit_terms(fit_pts, terms, ts, tau_max, tb_max);
    if (cur.status != FitStatus::kOk) {
      cur = base0;
    }
    cost_thr = o.cost_factor * chi2_quantile(1.0 - o.cost_alpha, 1.0);
    cur_p = cur.params;
    cur_cost = residual(eval, cur_p, o, ts, tau_max).cost;
    lr_thr = chi2_quantile(1.0 - o.alpha, 1.0);  // record likelihood: no inflation
    y_minus_sine = std::vector<double>{};  // the record itself
    for (int round = 0; round < 6; ++round) {
      const Residual res = residual(eval, cur_p, o, ts, tau_max);
      if (res.check.n_runs > 0) {
        std::vector<Cand> cands;
        term_candidates(cands);
        sine_candidates(res, cands);
        oscillation_candidates(res, cands);
        if (take_best(cands)) {
          continue;
        }
      }
      // No residual run (say nothing), or none of the terms passed: but for a line of few
      // periods, which the first-order fit takes up without a run (slow_sine_candidate). Only
      // here, once the ADEV's terms are in: a term not yet in H0 (bias instability's excess at
      // low frequencies) would pass for the line.
      std::vector<Cand> slow;
      if (!have_sine) {
        slow_sine_candidate(slow);
      }
      if (slow.empty() || !take_best(slow)) {
        break;
      }
    }
    // The spectra and the sinusoid search's record copies are not needed after the search.
    spectrum_of_y = SpectrumCache{};
    psd_of_y_fit = WelchPsd{};
    return true;
  }

  // One candidate per term not yet in the model, each fitted jointly with the terms so far.
  void term_candidates(std::vector<Cand>& cands) {
    const auto try_term = [&](const char* type, std::uint32_t t) {
      const std::uint32_t own = (t & ~kFitGm2) != 0U ? (t & ~kFitGm2) : t;  // the term tried
      if ((terms & own) != 0U) {
        return;
      }
      const FitResult f =
          fit_terms(fit_pts, terms | t, ts, tau_max, tb_max, &cur_p, white_filter_s);
      if (f.status != FitStatus::kOk) {
        return;
      }
      const ModelParams p = with_sines(f.params, cur_p);
      cands.push_back(Cand{type, terms | t, p, residual(eval, p, o, ts, tau_max).cost, nullptr});
    };
    try_term("quantization", kFitQuantization);
    try_term("rate_random_walk", kFitRrw);
    try_term("ramp", kFitRamp);
    // A second GM is not one of the effects MODELS.md lists; real sensors need it (e.g. the
    // ADIS16405's internal filter correlates the noise below 1 s while the bias wanders over
    // minutes). It competes with the named terms under the same test and, when accepted, is
    // reported in the notes and in model_after, not as an effect.
    // With bias instability in the model a second slow GM would only share its power (two slow
    // GMs imitate flicker): the second GM is then for the short taus alone (both GMs slower than
    // two of the likelihood's blocks: not a candidate).
    try_term("second_gm", kFitGm2);
    if ((terms & kFitFlicker) != 0U && !cands.empty() && cands.back().type == "second_gm" &&
        cands.back().p.n_gm == 2 &&
        cands.back().p.gm[0].tb_s >= 2.0 * t_rec / static_cast<double>(kRrwTestBlocks)) {
      cands.pop_back();
    }
    // Bias instability comes with a second GM free for the short taus: fitted with one GM only,
    // the GM leaves the sensor's filter (the ADIS16405's ~0.1 s) to sit on the flicker's range
    // and the pair mimics neither.
    try_term("bias_instability", kFitFlicker | kFitGm2);
  }

  // A sinusoid candidate: the linear terms refitted to the ADEV of the record without it, the
  // sinusoids of `sines` added analytically.
  void add_sine_cand(const char* type, const SineCand& sc, const ModelParams& sines,
                     std::vector<Cand>& cands) {
    const Points dp = in_range(points_for_model(sc.adev, cur_p), tau_max);
    const FitResult f = fit_terms(dp, terms, ts, tau_max, tb_max, &cur_p, white_filter_s);
    if (f.status != FitStatus::kOk) {
      return;
    }
    const ModelParams p = with_sines(f.params, sines);
    cands.push_back(Cand{type, terms, p, residual(eval, p, o, ts, tau_max).cost, &sc});
  }

  // The ADEV of `from` less a sinusoid. The record without it is a temporary the counts replace
  // before the ADEV's gap-aware sums are built: one record-length double vector fewer at the
  // sinusoid search's peak (8 MB at 2^20 samples).
  AdevSet adev_without_sine(const std::vector<double>& from, const SineFit& fit) {
    std::vector<std::int32_t> c = to_counts(minus_sine(from, ts, fit), offset, lsb, sat);
    return adev_of(c, gap, ts, lsb);
  }

  // A line of few periods in the record (under kSineCyclesByAdev; a thermal cycle): a GM or a
  // walk makes a bump at the same taus and a peak in the periodogram's few low bins, which the
  // ADEV cost cannot tell from a line. The line is proposed only where the record's block means
  // need it beside the model's stationary terms (its GMs, bias instability, a walk if the
  // record's likelihood takes one, one more GM of Tb free; test_rrw, the line removed where the
  // model holds a ramp):
  // the generalized 2 ln LR of the pair cos, sin at the line's frequency (regressor_lr of one,
  // then of the other beside it), compared with chi-square(2) at alpha / M, M the frequencies
  // the periodogram's search window [f_c / 2, 2 f_c] resolves (1.5 f_c T, Bonferroni over the
  // search). H0's parameters fitted to the record with the line in it take up part of it (a
  // GM slower and larger): the pair's statistic is also computed under H0's parameters fitted
  // to the record less the line's least-squares estimate, plus 2 (l(those; means) - l(H0's
  // maximum; means)) <= 0, and the larger of the two taken. Both are lower bounds of the
  // generalized likelihood ratio (H1's maximum is at least its value at either parameter set),
  // so the level holds.
  bool slow_line_stands(const SineFit& fit, double f_c, double& lr_out, double& thr_out) {
    ModelParams h = stochastic_part(cur_p);
    h.k = 0.0;
    const bool detrend = (terms & kFitRamp) != 0U;
    const auto null_of = [&](const std::vector<double>& rec) {
      RrwLikelihoodTest t = test_rrw(rec, ts, h, tb_max, detrend, step_at, kAuxBlocks, true);
      if (t.ok && t.h1.ok && t.h1.loglik > t.h0.loglik) {
        t.h0 = t.h1;
      }
      // One more GM, Tb free up to kSlowGmTbPerRecord x T: low-frequency power of a shape the
      // model's terms do not follow (flicker beyond its bank, a slow GM beside a fast one) is
      // broadband and goes there; a line is one frequency and stays.
      if (t.ok && t.h0.ok && t.h0.model.n_gm < kMaxGmTerms && t.means.size() > 1) {
        BlockModel m = t.h0.model;
        GmParam& g = m.gm[m.n_gm++];
        g.tb_s = 0.25 * t_rec;
        g.sb = 2.0 * 0.1 * sample_variance(t.means) / g.tb_s;  // a tenth of the means' variance
        const LikelihoodFit f = fit_block_model(t.means, t.block_s, m, m.k > 0.0, t.block_s,
                                                kSlowGmTbPerRecord * t_rec, t.resets);
        if (f.ok && f.loglik > t.h0.loglik) {
          t.h0 = f;
        }
      }
      return t;
    };
    const RrwLikelihoodTest t = null_of(fit_record());
    if (!t.ok || !t.h0.ok || t.means.size() < 64) {
      return false;
    }
    const std::size_t nb = t.means.size();
    std::vector<double> uc(nb);
    std::vector<double> us(nb);
    for (std::size_t k = 0; k < nb; ++k) {
      const double w = 2.0 * kPi * fit.f_hz * (static_cast<double>(k) + 0.5) * t.block_s;
      uc[k] = std::cos(w);
      us[k] = std::sin(w);
    }
    remove_mean_and_line(uc, detrend);
    remove_mean_and_line(us, detrend);
    const auto pair_lr = [&](const RrwLikelihoodTest& at) {
      return regressor_lr(at, uc) + regressor_lr(at, us, nullptr, &uc);
    };
    double lr = pair_lr(t);
    const RrwLikelihoodTest without = null_of(minus_sine(fit_record(), ts, fit));
    if (without.ok && without.h0.ok) {
      RrwLikelihoodTest at = t;
      at.h0 = without.h0;
      const double l_max = block_loglik(t.means, t.block_s, t.h0.model, -1.0, t.resets);
      const double l_at = block_loglik(t.means, t.block_s, without.h0.model, -1.0, t.resets);
      if (std::isfinite(l_max) && std::isfinite(l_at)) {
        lr = std::max(lr, pair_lr(at) + 2.0 * std::min(0.0, l_at - l_max));
      }
    }
    const double m = std::max(1.0, 1.5 * f_c * t_rec);
    const double thr = chi2_quantile(1.0 - o.alpha / m, 2.0);
    lr_out = lr;
    thr_out = thr;
    if (!(lr > thr)) {
      out.notes.push_back("not a sinusoid: the line at " + fmt("%.5g", fit.f_hz) + " Hz (" +
                          fmt("%.1f", fit.f_hz * t_rec) +
                          " periods in the record) is not needed beside the model's noise on "
                          "the record's block means (2 ln LR = " +
                          fmt("%.1f", lr) + " <= " + fmt("%.1f", thr) + ")");
      return false;
    }
    return true;
  }

  // A line of kMinSineCycles to kSineCyclesByAdev periods in the record (a thermal cycle): its
  // ADEV bump lies at 0.37 of its period, at or beyond T/10, where the first-order fit's GM
  // takes it up and no residual run shows; the periodogram's low band proposes it instead
  // (estimate_sinusoid over [f_c / 2, 2 f_c], f_c = 10 / T), and the record's likelihood
  // decides (slow_line_stands). Tried once no residual run is left.
  void slow_sine_candidate(std::vector<Cand>& cands) {
    const double f_c = std::sqrt(kMinSineCycles * kSineCyclesByAdev) / t_rec;
    if (f_c >= 0.5 / ts) {
      return;
    }
    constexpr std::size_t kLowBand = static_cast<std::size_t>(-1);  // its sine_cache key
    add_line_cand(line_near(kLowBand, f_c,
                            [&](SineCand& sc) {
                              const double cycles = sc.fit.f_hz * t_rec;
                              return cycles >= kMinSineCycles && cycles < kSineCyclesByAdev &&
                                     slow_line_stands(sc.fit, f_c, sc.lr, sc.lr_thr);
                            }),
                  cands);
  }

  // The line near f_c (estimate_sinusoid) and, where `stands` takes it, the record's ADEV
  // without it; cached under `key` (a bump's tau index): each costs passes over the record.
  template <typename Stands>
  const SineCand& line_near(std::size_t key, double f_c, Stands stands) {
    auto it = sine_cache.find(key);
    if (it == sine_cache.end()) {
      SineCand sc;
      sc.fit = estimate_sinusoid(y, ts, f_c, spectrum_of_y);
      sc.fit.ok = sc.fit.ok && stands(sc);
      if (sc.fit.ok) {
        sc.adev = adev_without_sine(y, sc.fit);
      }
      it = sine_cache.emplace(key, std::move(sc)).first;
    }
    return it->second;
  }

  // A line found (line_near) as the candidate `sinusoid`, of the amplitude of the record's
  // samples.
  void add_line_cand(const SineCand& sc, std::vector<Cand>& cands) {
    if (!sc.fit.ok) {
      return;
    }
    ModelParams sines{};
    sines.sin_a = sc.fit.amplitude;
    sines.sin_f0_hz = sc.fit.f_hz;
    sines.sin_ts_s = ts;
    add_sine_cand("sinusoid", sc, sines, cands);
  }

  // sine_coherence of the line at f_hz, run once per line (two bumps can lead to the same
  // one); a line that fails it is said in a note, once.
  bool coherent_line(double f_hz) {
    const auto seen = line_coherent.find(f_hz);
    if (seen != line_coherent.end()) {
      return seen->second;
    }
    const SineCoherence coh = sine_coherence(y, ts, f_hz, o.alpha);
    const bool coherent = !coh.tested || coh.stat <= coh.thr;
    if (!coherent) {
      out.notes.push_back("not a sinusoid: the line at " + fmt("%.5g", f_hz) +
                          " Hz changes its amplitude or phase over the record (X = " +
                          fmt("%.1f", coh.stat) + " > " + fmt("%.1f", coh.thr) +
                          " over 16 parts): a band narrower than the spectrum resolves");
    }
    line_coherent.emplace(f_hz, coherent);
    return coherent;
  }

  // Sinusoids at the three strongest bumps where the data sit above the model (negative z); once
  // one is in the model, its harmonics 2 and 3.
  void sine_candidates(const Residual& res, std::vector<Cand>& cands) {
    std::vector<AdevRun> bumps;
    for (std::size_t r = 0; r < res.check.n_runs; ++r) {
      if (res.check.runs[r].sign < 0) {
        bumps.push_back(res.check.runs[r]);
      }
    }
    if (!have_sine) {
      // The three strongest bumps (by sum of z) are candidates.
      std::sort(bumps.begin(), bumps.end(),
                [](const AdevRun& a, const AdevRun& b) { return a.sum_z < b.sum_z; });
      if (bumps.size() > 3) {
        bumps.resize(3);
      }
      for (const AdevRun& run : bumps) {
        std::size_t imin = run.first;
        for (std::size_t i = run.first; i < run.first + run.count; ++i) {
          imin = res.z[i] < res.z[imin] ? i : imin;
        }
        const double f_c = 0.371 / eval[imin].tau_s;
        if (f_c >= 0.5 / ts || f_c * t_rec < kSineCyclesByAdev) {
          continue;  // not a resolvable sinusoid (above Nyquist or too few periods)
        }
        add_line_cand(
            line_near(imin, f_c, [&](const SineCand& sc) { return coherent_line(sc.fit.f_hz); }),
            cands);
      }
    } else if (!have_sine2) {
      // Harmonics of the sinusoid found (a periodic disturbance that is not a pure tone, e.g.
      // the ADIS16405's oscillation has a 3rd harmonic): least squares at exactly h f0.
      for (const int h : {2, 3}) {
        const double f_h = h * sine.f_hz;
        if (f_h >= 0.5 / ts) {
          continue;
        }
        auto it = harmonic_cache.find(h);
        if (it == harmonic_cache.end()) {
          SineCand sc;
          sc.fit = sine_ls(fit_record(), ts, f_h);
          if (sc.fit.ok) {
            sc.adev = adev_without_sine(fit_record(), sc.fit);
          }
          it = harmonic_cache.emplace(h, std::move(sc)).first;
        }
        const SineCand& sc = it->second;
        if (!sc.fit.ok || !(sc.fit.amplitude > 0.0)) {
          continue;
        }
        ModelParams sines{};
        sines.sin_a = sine.amplitude;
        sines.sin_f0_hz = sine.f_hz;
        sines.sin2_a = sc.fit.amplitude;
        sines.sin2_f0_hz = sc.fit.f_hz;
        sines.sin_ts_s = ts;
        sines.sin2_ts_s = ts;
        add_sine_cand("sinusoid_harmonic", sc, sines, cands);
      }
    }
  }

  // A narrowband oscillation (a vibration mode or resonance: a band in the spectrum, not a line)
  // at the bumps where the data sit above the model; its shape from the spectrum of the record
  // (estimate_oscillation), its sigma^2 from the joint ADEV fit.
  void oscillation_candidates(const Residual& res, std::vector<Cand>& cands) {
    if ((terms & kFitOscillation) == 0U) {
      for (std::size_t r = 0; r < res.check.n_runs; ++r) {
        const AdevRun& run = res.check.runs[r];
        if (run.sign >= 0) {
          continue;
        }
        std::size_t imin = run.first;
        for (std::size_t i = run.first; i < run.first + run.count; ++i) {
          imin = res.z[i] < res.z[imin] ? i : imin;
        }
        const double f_c = 0.371 / eval[imin].tau_s;
        if (f_c * t_rec < 200.0) {
          continue;  // too few cycles in the record to see a band
        }
        if (psd_of_y_fit.sm.empty()) {
          psd_of_y_fit = welch_psd(fit_record(), ts);
        }
        auto it = osc_cache.find(imin);
        if (it == osc_cache.end()) {
          it = osc_cache.emplace(imin, estimate_oscillation(psd_of_y_fit, f_c)).first;
        }
        if (!it->second.ok) {
          continue;
        }
        // Point samples (the ADEV of sample means: avar_oscillation_sampled) or a sensor that
        // averages over each sample period, as the ADIS16405 does (continuous averages): near
        // fs / 5 the two differ by 14 % in AVAR at short tau, and the lower cost decides.
        for (const double sampled_ts : {ts, 0.0}) {
          ModelParams shape = cur_p;
          shape.osc_f0_hz = it->second.f0_hz;
          shape.osc_beta_per_s = it->second.beta_per_s;
          shape.osc_ts_s = sampled_ts;
          const FitResult f = fit_terms(fit_pts, terms | kFitOscillation, ts, tau_max, tb_max,
                                        &shape, white_filter_s);
          if (f.status != FitStatus::kOk || !(f.params.osc_sigma > 0.0)) {
            continue;
          }
          const ModelParams p = with_sines(f.params, cur_p);
          cands.push_back(Cand{"oscillation", terms | kFitOscillation, p,
                               residual(eval, p, o, ts, tau_max).cost, nullptr});
        }
      }
    }
  }

  // The test a candidate passes to be taken, said in a note where it fails: the ADEV cost drop
  // against cost_thr; for a line of few periods, the record's likelihood (slow_line_stands,
  // its 2 ln LR and level), the ADEV's taus up to T/10 holding little of it, where the ADEV
  // does not get worse with it.
  struct CandTest {
    double statistic = 0.0;
    double threshold = 0.0;
    bool passes = false;
  };
  CandTest test_of(const Cand& c) {
    const double drop = cur_cost - c.cost;
    if (c.sine != nullptr && c.sine->lr_thr > 0.0) {
      const CandTest t{c.sine->lr, c.sine->lr_thr, drop > 0.0};
      out.notes.push_back(
          (t.passes ? "sinusoid at " : "not added: a sinusoid at ") +
          fmt("%.5g", c.sine->fit.f_hz) + " Hz, " + fmt("%.1f", c.sine->fit.f_hz * t_rec) +
          " periods in the record: its statistic the record's block-mean likelihood (2 ln LR "
          "of the line beside the model's noise), the ADEV cost drop " +
          fmt("%.1f", drop) + (t.passes ? "" : " (the ADEV gets worse with it)"));
      return t;
    }
    const CandTest t{drop, cost_thr, drop > cost_thr};
    if (!t.passes) {
      out.notes.push_back("not added: " + c.type + " (cost drop " + fmt("%.1f", drop) +
                          " <= " + fmt("%.1f", cost_thr) + ")");
    }
    return t;
  }

  // The best candidate, checked against its rivals (ramp against a walk, the long-tau family by
  // the record's likelihood, a walk against bias instability), is taken if its cost drop passes
  // the test. Returns false when no candidate is taken (the search ends).
  bool take_best(const std::vector<Cand>& all) {
    std::vector<Cand> cands;  // less the terms the record has ruled out (see ruled_out)
    for (const auto& c : all) {
      if (std::find(ruled_out.begin(), ruled_out.end(), c.type) == ruled_out.end()) {
        cands.push_back(c);
      }
    }
    const Cand* best = nullptr;
    for (const auto& c : cands) {
      if (best == nullptr || c.cost < best->cost) {
        best = &c;
      }
    }
    if (best != nullptr) {
      ramp_or_walk(cands, best);
    }
    // The long-tau family: bias instability, rate random walk, or a second GM slow enough to be
    // seen in the record's block means. Over the taus up to T/10 a flat stretch bent up at the
    // end fits any of them (two GMs and a walk imitate flicker over a decade or two); the
    // record decides. The candidates that pass the ADEV test are compared by their maximised
    // block-mean likelihoods (long_memory.hpp) less their extra parameters (AIC: 1 for B or K,
    // 2 for a GM; 1 more beside a line the model does not hold, and then the walk and flicker
    // are told apart on the record less its line as well).
    bool beside_line = false;
    if (best != nullptr) {
      best = long_tau_choice(LongTauInput{fit_record(), ts, tb_max, (terms & kFitRamp) != 0U,
                                          step_at, cur_p, cur_cost, cost_thr, lr_thr},
                             cands, best, out.notes, beside_line);
    }
    if (best != nullptr && !walk_or_flicker(cands, best, beside_line)) {
      return take_best(cands);
    }
    if (best == nullptr) {
      return false;
    }
    const CandTest test = test_of(*best);
    if (!test.passes) {
      return false;
    }
    {
      Effect e;
      e.type = best->type == "sinusoid_harmonic" ? "sinusoid"
               : best->type == "second_gm"       ? "gauss_markov"
                                                 : best->type;
      e.statistic = test.statistic;
      e.threshold = test.threshold;
      out.effects.push_back(e);
    }
    terms = best->terms;
    cur_p = best->p;
    cur_cost = best->cost;
    if (best->sine != nullptr && best->type == "sinusoid_harmonic") {
      have_sine2 = true;
      y_minus_sine = minus_sine(fit_record(), ts, best->sine->fit);
      psd_of_y_fit = WelchPsd{};
      osc_cache.clear();
      fit_set = best->sine->adev;
      out.notes.push_back("sinusoid at " + fmt("%.5g", cur_p.sin2_f0_hz) + " Hz: harmonic " +
                          fmt("%.0f", cur_p.sin2_f0_hz / cur_p.sin_f0_hz) + " of " +
                          fmt("%.5g", cur_p.sin_f0_hz) + " Hz");
    } else if (best->sine != nullptr) {
      have_sine = true;
      sine = best->sine->fit;
      y_minus_sine = minus_sine(y, ts, sine);
      psd_of_y_fit = WelchPsd{};
      osc_cache.clear();
      fit_set = best->sine->adev;
    }
    fit_pts = in_range(points_for_model(fit_set, cur_p), tau_max);
    return true;
  }

  [[nodiscard]] const Cand* passing(const std::vector<Cand>& cands, const char* type) const {
    const Cand* p = nullptr;
    for (const auto& c : cands) {
      p = c.type == type && cur_cost - c.cost > cost_thr ? &c : p;
    }
    return p;
  }

  // 2 ln LR of a line in the test's block means against its H1 (against_walk) or its H0.
  [[nodiscard]] static double line_lr(RrwLikelihoodTest t, bool against_walk) {
    if (!t.ok) {
      return 0.0;
    }
    if (against_walk) {
      t.h0 = t.h1;
    }
    return regressor_lr(t, trend_regressor(t.means.size(), 1));
  }

  // Ramp or rate random walk: over a record that holds few of its time scales a walk looks like
  // a line on the ADEV, and a line like a walk. When both pass the ADEV test each must be
  // needed beside the other by the record's likelihood: the walk on the record with the line
  // removed (a deterministic ramp leaves no walk there), the line as a regressor against the
  // model with the walk (a walk's increments have no mean). One needed: it is the best, the
  // other is ruled out; both, or neither (the record cannot tell them apart): the ADEV's best.
  void ramp_or_walk(const std::vector<Cand>& cands, const Cand*& best) {
    if (best->type != "ramp" && best->type != "rate_random_walk") {
      return;
    }
    const Cand* ramp = passing(cands, "ramp");
    const Cand* walk = passing(cands, "rate_random_walk");
    if (ramp == nullptr || walk == nullptr) {
      return;
    }
    const std::vector<double> rec = fit_record();
    RrwLikelihoodTest detrended = test_rrw(rec, ts, cur_p, tb_max, true, step_at);
    RrwLikelihoodTest plain = test_rrw(rec, ts, cur_p, tb_max, false, step_at);
    const std::string decay = without_decay(detrended, plain);
    const double lr_walk = detrended.ok ? detrended.lr : 0.0;
    const double lr_line = line_lr(plain, true);
    const bool need_walk = lr_walk > lr_thr;
    const bool need_line = lr_line > lr_thr;
    const std::string why = "(the record's likelihood" + decay +
                            ": the walk beside the line 2 ln LR = " + fmt("%.1f", lr_walk) +
                            ", the line beside the walk " + fmt("%.1f", lr_line) + ", level " +
                            fmt("%.2f", lr_thr) + ")";
    if (need_walk == need_line) {
      if (!need_walk) {
        out.notes.push_back(best->type + " kept by the ADEV: the record cannot tell a ramp from "
                            "a walk " + why);
      }
      return;
    }
    const Cand* keep = need_walk ? walk : ramp;
    if (keep != best) {
      out.notes.push_back(best->type + " rejected for " + keep->type + " " + why);
    }
    ruled_out.emplace_back(need_walk ? "ramp" : "rate_random_walk");
    best = keep;
  }

  // A level decaying from the start (a warm-up transient) bends the record as a walk's wander
  // does, and a line does not: beside a ramp the walk reads the decay. Where the decay is
  // significant beside the walk (on the detrended record, its 2 ln LR with the walk's model in
  // H0 above the transient check's level), it is fitted out of both tests' block means (its
  // GLS size beside the walk, and beside the walk and the line on the plain record) and both are
  // refitted. Returns the note's clause ("" where nothing was removed).
  std::string without_decay(RrwLikelihoodTest& detrended, RrwLikelihoodTest& plain) const {
    if (!detrended.ok || !plain.ok || !detrended.h1.ok || !plain.h1.ok) {
      return "";
    }
    RrwLikelihoodTest walk_d = detrended;
    walk_d.h0 = detrended.h1;
    const TransientLr tr = warmup_transient_lr(walk_d, true);
    if (!(tr.lr > transient_threshold())) {
      return "";
    }
    const std::size_t nb = detrended.means.size();
    std::vector<double> md = detrended.means;
    const std::vector<double> ud = decay_regressor(nb, detrended.block_s, tr.tau_s, true);
    for (std::size_t k = 0; k < nb; ++k) {
      md[k] -= tr.size * ud[k];
    }
    RrwLikelihoodTest walk_p = plain;
    walk_p.h0 = plain.h1;
    const std::vector<double> line = trend_regressor(plain.means.size(), 1);
    const std::vector<double> up =
        decay_regressor(plain.means.size(), plain.block_s, tr.tau_s, false);
    double size_p = 0.0;
    (void)regressor_lr(walk_p, up, &size_p, &line);
    std::vector<double> mp = plain.means;
    for (std::size_t k = 0; k < mp.size(); ++k) {
      mp[k] -= size_p * up[k];
    }
    RrwLikelihoodTest d = test_rrw_on_means(std::move(md), detrended.per_block, ts, cur_p,
                                            tb_max, step_at);
    RrwLikelihoodTest p = test_rrw_on_means(std::move(mp), plain.per_block, ts, cur_p, tb_max,
                                            step_at);
    if (!d.ok || !p.ok) {
      return "";
    }
    detrended = std::move(d);
    plain = std::move(p);
    return " less a level decaying from the start (time constant " + fmt("%.3g", tr.tau_s) +
           " s, 2 ln LR " + fmt("%.1f", tr.lr) + " beside the walk)";
  }

  // A walk and bias instability both raise the ADEV at the long taus: over a record that
  // holds only a few of their time scales either fits the other (a flicker floor whose last
  // estimates scatter upwards, a walk seen over a decade). Each is taken only if the record's
  // likelihood needs it beside the other (long_tau_pair; on the detrended record when a ramp
  // is in the model or the family's choice scored best beside a line: beside_line;
  // ramp_or_walk weighs a trend against the walk). One needed: it
  // is taken, the other ruled out; neither: the record cannot tell them apart. Then the walk
  // is ruled out and bias instability, stationary and the lesser claim, is kept whichever of
  // the two the ADEV and the family's likelihood put first (it is named only where it then
  // dominates the model; ruling both out left the rise to any term that passes the ADEV's
  // test, e.g. a ramp the record does not need). False when `best` was ruled out.
  bool walk_or_flicker(const std::vector<Cand>& cands, const Cand* best, bool beside_line) {
    const bool walk = best->type == "rate_random_walk";
    if ((!walk && best->type != "bias_instability") || !(cur_cost - best->cost > cost_thr)) {
      return true;
    }
    const Cand* other = passing(cands, walk ? "bias_instability" : "rate_random_walk");
    if (other == nullptr) {
      return true;  // no rival on the ADEV: its test is the ADEV's (and the walk's likelihood)
    }
    const bool detrend = (terms & kFitRamp) != 0U || beside_line;
    const LongTauPair lp = long_tau_pair(walk ? &other->p : &best->p, detrend);
    const double need_best = walk ? lp.k_beside_b : lp.b_beside_k;
    const double need_other = walk ? lp.b_beside_k : lp.k_beside_b;
    if (need_best > lr_thr) {
      return true;
    }
    const bool other_needed = need_other > lr_thr;
    if (!other_needed) {
      out.notes.push_back("bias_instability kept, rate_random_walk ruled out: the" +
                          std::string(detrend ? " detrended" : "") +
                          " record cannot tell them apart (2 ln LR of each beside the other " +
                          fmt("%.1f", need_best) + ", " + fmt("%.1f", need_other) + " <= " +
                          fmt("%.2f", lr_thr) + ")");
      ruled_out.emplace_back("rate_random_walk");
      return !walk;
    }
    out.notes.push_back("not added: " + best->type + " (the" + (detrend ? " detrended" : "") +
                        " record's likelihood needs it beside " +
                        (walk ? "bias instability" : "a walk") + " by 2 ln LR = " +
                        fmt("%.1f", need_best) + " <= " + fmt("%.2f", lr_thr) + "); " +
                        other->type + " is needed beside it (" + fmt("%.1f", need_other) + ")");
    ruled_out.push_back(best->type);  // the walk, or bias instability where the walk is needed
    return false;
  }

  struct LongTauPair {
    double k_beside_b = 0.0;  // 2 ln LR of a walk against the model with bias instability
    double b_beside_k = 0.0;  // 2 ln LR of bias instability against the model with a walk
    double b_alone = 0.0;     // 2 ln LR of bias instability against the model without either
  };
  // The record's block-mean likelihoods (long_memory.hpp) of the current model with a walk, with
  // bias instability, and with both (the flicker bank reaching the record's length). B starts
  // from `bi_start`'s, else the model's own, else the data's ADEV at T/100 taken as the flicker
  // floor; B and K are fitted. With `detrend` on the record less its least-squares line. Zeros
  // where a likelihood cannot be computed.
  // with_walk = false: only b_alone (the walk's fits skipped; k_beside_b, b_beside_k stay 0).
  [[nodiscard]] LongTauPair long_tau_pair(const ModelParams* bi_start, bool detrend,
                                          bool with_walk = true) const {
    LongTauPair out_lr;
    ModelParams h0 = cur_p;
    h0.k = 0.0;
    if (bi_start != nullptr && bi_start->bi > 0.0) {
      h0.bi = bi_start->bi;
      h0.bi_tau_lo_s = bi_start->bi_tau_lo_s;
      h0.bi_tau_hi_s = bi_start->bi_tau_hi_s;
    } else if (!(h0.bi > 0.0)) {
      for (const auto& pt : adev_y.by_alpha[2]) {
        h0.bi = pt.tau_s <= t_rec / 100.0 ? pt.adev / kFlickerAdevFactor : h0.bi;
      }
      h0.bi_tau_hi_s = 0.1 * t_rec;
      h0.bi_tau_lo_s = flicker_tau_lo(ts, h0.bi_tau_hi_s, adev_y.by_alpha[2]);
    }
    if (!(h0.bi > 0.0)) {
      return out_lr;
    }
    ModelParams no_b = cur_p;
    no_b.k = 0.0;
    no_b.bi = 0.0;
    const RrwLikelihoodTest with_b =
        test_rrw(fit_record(), ts, h0, tb_max, detrend, step_at, kRrwTestBlocks, with_walk);
    const RrwLikelihoodTest without_b =
        test_rrw(fit_record(), ts, no_b, tb_max, detrend, step_at, kRrwTestBlocks, with_walk);
    if (!with_b.ok || !without_b.ok) {
      return out_lr;
    }
    out_lr.b_alone = std::max(0.0, 2.0 * (with_b.h0.loglik - without_b.h0.loglik));
    if (!with_walk) {
      return out_lr;
    }
    const double l_both = std::max(with_b.h1.loglik, without_b.h1.loglik);
    out_lr.k_beside_b = std::max(0.0, 2.0 * (l_both - with_b.h0.loglik));
    out_lr.b_beside_k = std::max(0.0, 2.0 * (l_both - without_b.h1.loglik));
    return out_lr;
  }

  // The level a decay's best 2 ln LR over its tau grid must pass: chi-square(1) at
  // alpha / kTransientTaus (warmup_transient_lr).
  [[nodiscard]] double transient_threshold() const {
    return chi2_quantile(1.0 - o.alpha / kTransientTaus, 1.0);
  }

  // [0, 3 tau] of a warm-up transient found by its likelihood (tr, against `against`) as an
  // unexplained time range, with its tau range from one block (the test's resolution).
  [[nodiscard]] UnexplainedRun transient_range(const TransientLr& tr, double block_s,
                                               const std::string& against) const {
    UnexplainedRun u;
    u.t_min_s = 0.0;
    u.t_max_s = std::min(3.0 * tr.tau_s, static_cast<double>(y.size()) * ts);
    u.tau_min_s = block_s;
    u.tau_max_s = u.t_max_s;
    u.max_abs_z = std::sqrt(tr.lr);
    u.what = "a level decaying from the start of the record (A = " + fmt("%.3g", tr.size) +
             ", time constant " + fmt("%.3g", tr.tau_s) +
             " s: a warm-up transient), 2 ln LR " + fmt("%.1f", tr.lr) +
             " against " + against;
    return u;
  }

  // A warm-up transient explains the record better than the walk of lt (by AIC's 2 for its
  // second parameter, tau, as a step must beat a walk): reported as an unexplained time range
  // with a note, and true; the walk is then not taken. Otherwise the walk is a term, and the
  // decay is tested beside it (warmup_transient_check).
  bool transient_for_walk(const RrwLikelihoodTest& lt) {
    const TransientLr tr = warmup_transient_lr(lt, (terms & kFitRamp) != 0U);
    const double tr_thr = transient_threshold();
    constexpr double kAicPenalty = 2.0;
    if (!(tr.lr > tr_thr && tr.lr > lt.lr + kAicPenalty)) {
      return false;
    }
    const UnexplainedRun u = transient_range(tr, lt.block_s, "the walk's " + fmt("%.1f", lt.lr));
    time_ranges.push_back(u);
    out.notes.push_back("no rate_random_walk: the record's likelihood finds one (2 ln LR = " +
                        fmt("%.1f", lt.lr) + ") but " + u.what +
                        " explains it better: reported as unexplained");
    return true;
  }

  // A warm-up transient on every record, whether or not its likelihood asks for a walk: the
  // decay's GLS 2 ln LR against the model's own H0 (white, its GMs and bias instability refitted
  // to the block means, with its walk when it holds one, its line removed when it holds a ramp,
  // its steps as level resets), the best of the tau grid above chi-square(1) at
  // alpha / kTransientTaus. A walk or a line the model does not hold bends the record's slow
  // part too: the decay must explain the record better than either (by 2, its tau being a
  // parameter more), or be significant beside the walk (with the walk in H0), else it is not
  // reported. Not a term: the model is unchanged, [0, 3 tau] is unexplained. walk_test: rrw_by_likelihood's test of the model as it stands, reused if ok.
  void warmup_transient_check(const RrwLikelihoodTest& walk_test) {
    for (const auto& u : time_ranges) {
      if (u.t_min_s <= 0.0) {
        return;  // the start of the record is already an unexplained time range
      }
    }
    const bool ramp = (terms & kFitRamp) != 0U;
    const bool walk = (terms & kFitRrw) != 0U;
    RrwLikelihoodTest lt =
        walk_test.ok ? walk_test : test_rrw(fit_record(), ts, cur_p, tb_max, ramp, step_at);
    if (!lt.ok) {
      return;
    }
    const double walk_lr_here = walk ? 0.0 : lt.lr;
    if (walk) {
      lt.h0 = lt.h1;  // the decay against the model with its walk
    }
    const TransientLr tr = warmup_transient_lr(lt, ramp);
    const double thr = transient_threshold();
    if (!(tr.lr > thr)) {
      return;
    }
    const double lr_line = ramp ? 0.0 : line_lr(lt, false);
    constexpr double kAicPenalty = 2.0;
    const double alt_lr = std::max(walk_lr_here, lr_line);
    const UnexplainedRun u = transient_range(tr, lt.block_s,
                                             walk ? "the model's likelihood with a rate random walk"
                                                  : "the model's own likelihood");
    // A decay still significant with the walk in H0 is no walk's wander, whichever explains
    // the record better on its own.
    RrwLikelihoodTest beside_walk = lt;
    beside_walk.h0 = lt.h1;
    const TransientLr tw = walk_lr_here >= lr_line && lt.h1.ok
                               ? warmup_transient_lr(beside_walk, ramp)
                               : TransientLr{};
    if (!(tr.lr > alt_lr + kAicPenalty) && tw.lr > thr) {
      time_ranges.push_back(u);
      out.notes.push_back("warm-up transient: " + u.what + " > " + fmt("%.2f", thr) +
                          "; a walk the model does not hold explains the record nearly as well (" +
                          fmt("%.1f", alt_lr) + ") but beside that walk the decay is still "
                          "significant (2 ln LR " + fmt("%.1f", tw.lr) +
                          "): reported as unexplained");
      return;
    }
    if (!(tr.lr > alt_lr + kAicPenalty)) {
      out.notes.push_back("not reported: " + u.what + " (> " + fmt("%.2f", thr) + "), but " +
                          (walk_lr_here >= lr_line ? "a walk" : "a line") +
                          " the model does not hold explains the record nearly as well (" +
                          fmt("%.1f", alt_lr) + ", + 2 for the decay's tau)");
      return;
    }
    time_ranges.push_back(u);
    out.notes.push_back("warm-up transient: " + u.what + " > " + fmt("%.2f", thr) +
                        " (chi-square(1) at alpha / " + std::to_string(kTransientTaus) +
                        ", the taus tried) and > a walk's or a line's " +
                        fmt("%.1f", alt_lr + kAicPenalty) + ": reported as unexplained");
  }

  // Returns the walk's test of the model as it stands on return (ok = false when the model has
  // changed since, or when nothing was tested): warmup_transient_check reuses it.
  RrwLikelihoodTest rrw_by_likelihood() {
    RrwLikelihoodTest now;
    // ---- rate random walk by the record's likelihood (when the ADEV up to T/10 did not need it).
    // The ADEV of a GM peaking near T/10 is the same curve as an RRW's there; the record itself is
    // not: a walk keeps wandering, a GM with tb <= tb_max reverts many times (long_memory.hpp).
    // H0 = the current model's GMs (tb <= tb_max), H1 = H0 + K (on the detrended record if a ramp
    // was found).
    const bool walk_ruled_out = std::find(ruled_out.begin(), ruled_out.end(),
                                          "rate_random_walk") != ruled_out.end();
    if ((terms & kFitRrw) != 0U) {
      // Found on the ADEV: the record's likelihood says whether the model needs it (then the
      // never-worse rule on the ADEV does not remove it: one criterion decides).
      const RrwLikelihoodTest lt =
          test_rrw(fit_record(), ts, cur_p, tb_max, (terms & kFitRamp) != 0U, step_at);
      now = lt;
      if (lt.ok && lt.lr > lr_thr && transient_for_walk(lt)) {
        const FitResult f = fit_terms(fit_pts, terms & ~kFitRrw, ts, tau_max, tb_max, &cur_p,
                                      white_filter_s);
        if (f.status == FitStatus::kOk) {
          terms &= ~kFitRrw;
          cur_p = with_sines(f.params, cur_p);
          return {};
        }
        time_ranges.pop_back();
        out.notes.pop_back();
      }
      if (lt.ok) {
        walk_lr = lt.lr;
        out.notes.push_back("rate_random_walk in the record's likelihood: 2 ln LR = " +
                            fmt("%.1f", lt.lr) + (lt.lr > lr_thr ? " > " : " <= ") +
                            fmt("%.2f", lr_thr) + (lt.lr > lr_thr ? " (required)" : ""));
        if (!(lt.lr > lr_thr)) {
          if (withdraw_walk("the record's likelihood does not need it beside the model's "
                            "other terms")) {
            return {};
          }
        } else if (walk_is_a_line(lt)) {
          return {};
        } else {
          note_walk_beside_a_cubic(lt);
        }
      }
    } else if (walk_ruled_out) {
      out.notes.emplace_back("no rate_random_walk by the record's likelihood: ruled out above");
    } else {
      const RrwLikelihoodTest lt =
          test_rrw(fit_record(), ts, cur_p, tb_max, (terms & kFitRamp) != 0U, step_at);
      now = lt;
      // With bias instability in the model its flicker bank is in H0: lt is already the walk's
      // test beside it.
      if (lt.ok && lt.lr > lr_thr && transient_for_walk(lt)) {
        // reported as unexplained (transient_for_walk)
      } else if (lt.ok && lt.lr > lr_thr && walk_is_a_line(lt)) {
        // A line explains the rise as well; with the ramp taken in its place the test is stale.
        return (terms & kFitRamp) != 0U ? RrwLikelihoodTest{} : lt;
      } else if (lt.ok && lt.lr > lr_thr) {
        const FitResult f =
            fit_terms(fit_pts, terms | kFitRrw, ts, tau_max, tb_max, &cur_p, white_filter_s);
        if (f.status == FitStatus::kOk && f.params.k > 0.0) {
          note_walk_beside_a_cubic(lt);
          Effect e;
          e.type = "rate_random_walk";
          e.statistic = lt.lr;
          e.threshold = lr_thr;
          out.effects.push_back(e);
          out.notes.push_back(
              "rate_random_walk from the record's likelihood: 2 ln LR = " + fmt("%.1f", lt.lr) +
              " > " + fmt("%.2f", lr_thr) + " (" + std::to_string(lt.blocks) + " block means of " +
              fmt("%.3g", lt.block_s) + " s; GM alone, tb <= " + fmt("%.0f", tb_max) +
              " s, vs GM + K = " + fmt("%.3g", lt.h1.model.k) + ")");
          terms |= kFitRrw;
          walk_lr = lt.lr;
          cur_p = with_sines(f.params, cur_p);
          now = RrwLikelihoodTest{};
        }
      } else if (lt.ok) {
        out.notes.push_back("no rate_random_walk in the record's likelihood: 2 ln LR = " +
                            fmt("%.1f", lt.lr) + " <= " + fmt("%.2f", lr_thr));
      }
    }
    return now;
  }

  // The walk's model without it (the ADEV fit refitted): false when that fit fails.
  bool withdraw_walk(const std::string& why) {
    const FitResult f =
        fit_terms(fit_pts, terms & ~kFitRrw, ts, tau_max, tb_max, &cur_p, white_filter_s);
    if (f.status != FitStatus::kOk) {
      return false;
    }
    terms &= ~kFitRrw;
    cur_p = with_sines(f.params, cur_p);
    walk_lr = -1.0;
    out.notes.push_back("rate_random_walk withdrawn: " + why +
                        "; what it fitted on the ADEV is left to the residual check");
    return true;
  }

  // A walk the record's likelihood needs (lt: the walk against the model without it) must also
  // be needed beside a line: over a record a few of its time scales long, a deterministic ramp
  // raises the block means' likelihood of a walk as much as a walk does. Not needed beside the
  // line: the walk is withdrawn (or not added) and, when the line is needed beside the walk (a
  // walk's increments have no mean; flicker's long excursions look like a line against a model
  // without either), the ramp is taken in its place. A decay from the start that is
  // significant beside the walk is fitted out of both first (without_decay). True when the walk
  // is out of the model.
  bool walk_is_a_line(const RrwLikelihoodTest& lt) {
    if ((terms & kFitRamp) != 0U) {
      return false;  // lt is already the walk beside the line
    }
    // Beside the line the walk must pay for its one parameter (AIC: 2 ln LR > 2); a line that
    // holds the whole rise leaves it near 0. (A walk over a few of its time scales is also
    // partly a line: the test's level alpha would lose walks the record does hold.)
    constexpr double kAicOneParameter = 2.0;
    RrwLikelihoodTest detr = test_rrw(fit_record(), ts, cur_p, tb_max, true, step_at);
    RrwLikelihoodTest plain = lt;
    const std::string decay = without_decay(detr, plain);  // a warm-up the walk would read
    if (!detr.ok || detr.lr > kAicOneParameter) {
      return false;
    }
    const double lr_line = line_lr(plain, true);
    const std::string why = "the walk beside a line" + decay + " 2 ln LR = " +
                            fmt("%.1f", detr.lr) +
                            " <= 2 (AIC's price of its parameter; the line beside the walk " +
                            fmt("%.1f", lr_line) + ")";
    if ((terms & kFitRrw) != 0U) {
      if (!withdraw_walk(why)) {
        return false;
      }
    } else {
      out.notes.push_back("no rate_random_walk: " + why);
    }
    if (!(lr_line > lr_thr)) {
      return true;
    }
    const FitResult f =
        fit_terms(fit_pts, terms | kFitRamp, ts, tau_max, tb_max, &cur_p, white_filter_s);
    if (f.status != FitStatus::kOk || !(std::abs(f.params.r) > 0.0)) {
      return true;
    }
    Effect e;
    e.type = "ramp";
    e.statistic = lr_line;
    e.threshold = lr_thr;
    out.effects.push_back(e);
    terms |= kFitRamp;
    cur_p = with_sines(f.params, cur_p);
    out.notes.push_back("ramp from the record's likelihood, in place of a walk: the line beside "
                        "the walk 2 ln LR = " + fmt("%.1f", lr_line) + " > " + fmt("%.2f", lr_thr));
    return true;
  }

  // A walk the record needs beside a line (lt: the walk against the model without it) may still
  // hold nothing a smooth drift that bends would not: a cubic in time, fitted by least squares to the block means (long_memory's
  // remove_polynomial). A walk's path holds most of its power in the record's lowest few scales
  // (Brownian motion: 95 % of its variance in the first four terms of its Karhunen-Loeve
  // expansion), and over a few hours of an IMU's record that is often all the record shows of
  // it. The walk stays (it is the filter's model for a slow drift, stochastic or not) but the
  // report says so when its 2 ln LR beside the cubic is under AIC's 2. Measured on `imu-sim
  // synth` records of the first-order model and K = 1.4e-4 (1 to 2.8 h, 65 seeds): beside a
  // cubic the walk's 2 ln LR is 0.0 on more than half of those whose likelihood requires it,
  // and the cubic alone scores up to 18 above the walk alone in 2 ln L less twice the
  // parameters; on quadratic drifts in a GM 23 to 64. Neither criterion tells the two apart on
  // such records, so neither decides the name.
  void note_walk_beside_a_cubic(const RrwLikelihoodTest& lt) {
    constexpr double kAicOneParameter = 2.0;
    constexpr std::size_t kCubic = 3;
    if (!lt.ok || !(lt.lr > lr_thr)) {
      return;
    }
    const RrwLikelihoodTest cub = test_rrw(fit_record(), ts, cur_p, tb_max, true, step_at,
                                           kRrwTestBlocks, true, kCubic);
    if (!cub.ok || cub.lr > kAicOneParameter) {
      return;
    }
    out.notes.push_back(
        "rate_random_walk: beside a cubic drift in time its 2 ln LR is " + fmt("%.1f", cub.lr) +
        " <= 2 (against the model without it " + fmt("%.1f", lt.lr) + "): the record shows the "
        "walk only on its longest scales, where a smooth deterministic drift (a temperature "
        "curve) reads the same; a walk is the filter's model for either");
  }

  // One story: a term the report does not name leaves the model (a wrong name is worse than
  // an unexplained range, and a model term without a name contradicts the effect list).
  // Backward elimination: while the name check withdraws a name, the one of those terms whose
  // removal costs least (the model refitted without it) leaves, and the check runs again on
  // the refitted model. withdrawn: the tau ranges of the last check's withdrawn names.
  void name_terms(const AfterContext& ac, AfterChoice& choice,
                  std::vector<UnexplainedRun>& withdrawn) {
    for (int round = 0; round < 8; ++round) {
      Report trial;
      trial.effects = out.effects;
      std::vector<std::string> dominates_nowhere;
      const RampChecks ramp =
          ramp_checks(fit_record(), ts, choice.p, tb_max, step_at, transient_threshold());
      name_check(ac, choice.p, ramp, trial, dominates_nowhere);
      std::vector<std::string> gone;
      for (const auto& e : out.effects) {
        bool kept = false;
        for (const auto& k : trial.effects) {
          kept = kept || k.type == e.type;
        }
        if (!kept && !needed_beside_larger_terms(ac, choice, e, dominates_nowhere, trial)) {
          gone.push_back(e.type);
        }
      }
      check_second_gm(ac, choice, trial, gone);
      trial.effects = without_types(trial.effects, gone);
      if (gone.empty() || round == 7) {
        out.effects = std::move(trial.effects);
        out.notes.insert(out.notes.end(), trial.notes.begin(), trial.notes.end());
        withdrawn = std::move(trial.unexplained);
        return;
      }
      // The least costly removal, kept as refitted (its effects and its removal note).
      AfterChoice best;
      Report best_r;
      std::string removed;
      for (const auto& type : gone) {
        Report r1;
        r1.effects = without_type(out.effects, type);
        AfterChoice ch = choice;
        remove_unnamed_terms(ac, ch, r1);
        if (removed.empty() || ch.e.cost < best.e.cost) {
          best = ch;
          best_r = std::move(r1);
          removed = type;
        }
      }
      rival_second_gm(ac, choice, gone, dominates_nowhere, best, best_r, removed);
      for (const auto& n : trial.notes) {
        if (n.find("not named: " + removed + " ") == 0) {
          out.notes.push_back(n);
        }
      }
      out.notes.insert(out.notes.end(), best_r.notes.begin(), best_r.notes.end());
      out.effects = std::move(best_r.effects);
      choice = best;
    }
  }

  // Bias instability or a walk that dominates the model ADEV nowhere beside a named second GM
  // was fitted together with that GM over the same taus, and the GM may be what stands in for
  // it (a GM's hump over a decade or two reads as flicker's floor or a walk's rise there). The
  // other removal is tried too: the second GM leaves, the rest is refitted, and the name check
  // runs on that model. It replaces `best` when the check then names the long-tau term and
  // the refit costs no more in sum z^2 than the removal chosen by cost (the ADEV cannot prefer
  // the GM then, and the GM claims no mechanism; the long-tau term does).
  void rival_second_gm(const AfterContext& ac, const AfterChoice& choice,
                       const std::vector<std::string>& gone,
                       const std::vector<std::string>& dominates_nowhere, AfterChoice& best,
                       Report& best_r, std::string& removed) {
    const auto listed = [](const std::vector<std::string>& v, const char* type) {
      return std::find(v.begin(), v.end(), type) != v.end();
    };
    if (choice.p.n_gm < 2 || listed(gone, "gauss_markov") ||
        !named_type(out.effects, "gauss_markov")) {
      return;
    }
    std::vector<const char*> hidden;  // the long-tau terms the GM may stand in for
    for (const char* t : {"bias_instability", "rate_random_walk"}) {
      if (listed(gone, t) && listed(dominates_nowhere, t)) {
        hidden.push_back(t);
      }
    }
    if (hidden.empty()) {
      return;
    }
    // One refit without the GM and one name check on it serve every such term.
    Report r1;
    r1.effects = without_type(out.effects, "gauss_markov");
    AfterChoice ch = choice;
    remove_unnamed_terms(ac, ch, r1);
    if (!(ch.e.cost <= best.e.cost)) {
      return;
    }
    Report check;
    check.effects = r1.effects;
    std::vector<std::string> nowhere;
    name_check(ac, ch.p,
               ramp_checks(fit_record(), ts, ch.p, tb_max, step_at, transient_threshold()),
               check, nowhere);
    const auto named_after = std::find_if(hidden.begin(), hidden.end(), [&](const char* t) {
      return named_type(r1.effects, t) && named_type(check.effects, t);
    });
    if (named_after == hidden.end()) {
      return;
    }
    const std::string type = *named_after;
    r1.notes.insert(r1.notes.begin(),
                    "not named: gauss_markov (a second GM beside " + type +
                        ", which dominates the model ADEV nowhere beside it: without the GM " +
                        type + " is named and the refit costs " + fmt("%.1f", ch.e.cost) +
                        " in sum z^2, without " + type + " " + fmt("%.1f", best.e.cost) + ")");
    best = ch;
    best_r = std::move(r1);
    removed = "gauss_markov";
  }

  // A term beside larger ones at every tau is still named when the refit cannot do without it:
  // without it the model is worse than the first-order one, or its ADEV cost rises by more than
  // the search's threshold (the test a second GM passes backwards) and its RMS and max errors
  // both rise (the cost alone can be a fraction of a per cent at the shortest taus, where the
  // EDF is ~1e6, bought with a worse fit elsewhere): put back into trial, said.
  bool needed_beside_larger_terms(const AfterContext& ac, const AfterChoice& choice,
                                  const Effect& e,
                                  const std::vector<std::string>& dominates_nowhere,
                                  Report& trial) {
    if (std::find(dominates_nowhere.begin(), dominates_nowhere.end(), e.type) ==
        dominates_nowhere.end()) {
      return false;
    }
    AfterChoice ch = choice;
    Report r1;
    r1.effects = without_type(out.effects, e.type);
    remove_unnamed_terms(ac, ch, r1);
    const bool worse_than_before =
        not_worse(choice.e, out.error_before) && !not_worse(ch.e, out.error_before);
    const double cost_rise = ch.e.cost - choice.e.cost;
    const bool needed = cost_rise > ac.cost_thr && ch.e.adev_rms_rel > choice.e.adev_rms_rel &&
                        ch.e.adev_max_rel > choice.e.adev_max_rel;
    if (!worse_than_before && !needed) {
      return false;
    }
    trial.effects.push_back(e);
    trial.notes.push_back(
        "named: " + e.type + " (it dominates the model ADEV at no tau, but without it " +
        (worse_than_before ? std::string("the model after is worse than before")
                           : "the ADEV cost rises by " + fmt("%.1f", cost_rise) + " > " +
                                 fmt("%.1f", ac.cost_thr)) +
        ": RMS " + fmt("%.3f", ch.e.adev_rms_rel) + " / max " + fmt("%.3f", ch.e.adev_max_rel) +
        ")");
    return true;
  }

  // A second GM (no mechanism claimed, exempt from the run check) must pass the search's ADEV
  // cost test backwards: the model refitted with one GM costs more than cost_thr more. Nor may
  // it peak where the base GM may not (its ADEV peak and an octave after it inside
  // [Ts, T/10]): beyond that it is the same curve as a walk or flicker over the range. Nor may
  // either GM be immaterial (drop_immaterial_gm).
  void check_second_gm(const AfterContext& ac, AfterChoice& choice, Report& trial,
                       std::vector<std::string>& gone) {
    if (choice.p.n_gm < 2 || std::find(gone.begin(), gone.end(), "gauss_markov") != gone.end()) {
      return;
    }
    bool beyond_bound = false;
    for (std::size_t g = 1; g < choice.p.n_gm; ++g) {
      beyond_bound = beyond_bound || choice.p.gm[g].tb_s > 1.001 * tb_max;
    }
    if (beyond_bound) {
      gone.emplace_back("gauss_markov");
      trial.notes.emplace_back("not named: gauss_markov (its ADEV peak lies beyond T/10 / 2: "
                               "over the taus fitted it is the same curve as a walk or flicker)");
      return;
    }
    AfterChoice ch = choice;
    Report r1;
    r1.effects = without_type(trial.effects, "gauss_markov");
    remove_unnamed_terms(ac, ch, r1);
    const double rise = ch.e.cost - choice.e.cost;
    if (!(rise > cost_thr)) {
      gone.emplace_back("gauss_markov");
      trial.notes.push_back("not named: gauss_markov (the model refitted without it costs only " +
                            fmt("%.1f", rise) + " <= " + fmt("%.1f", cost_thr) +
                            " more in sum z^2)");
      return;
    }
    // The test it passed is its evidence (a GM that came in with bias instability carried that
    // effect's, or none once bias instability left: "statistic 0 > threshold 0").
    for (Effect& e : trial.effects) {
      if (e.type == "gauss_markov") {
        e.statistic = rise;
        e.threshold = cost_thr;
      }
    }
    drop_immaterial_gm(ac, choice, trial);
  }

  // Of a model's two GMs, one whose removal changes the model's ADEV by less than
  // unexplained_min_rel at every tau of [Ts, T/10] is not a term the record shows: the analysis
  // would not report its absence as unexplained. The cost test can still pass it: a GM at a
  // hundredth of the white noise's AVAR near a few tenths of a second buys its cost from the
  // slow wander of the overlapping estimates at the shortest taus (EDF ~1e6, neighbouring taus
  // correlated), and a one-GM refit by that cost then moves the record's own GM there too. It
  // leaves the model; the other GM keeps its Tb and the rest is refitted (fit_after with
  // gm_tb_fixed_s), unless that model is worse than before or its RMS or max error rises by
  // more than unexplained_min_rel (then the other terms lean on it: a GM at the shortest taus
  // can hold what a flicker bank starting at 10 Ts leaves out). Its effect leaves trial and
  // out, said; the others take the refit's parameters.
  void drop_immaterial_gm(const AfterContext& ac, AfterChoice& choice, Report& trial) {
    const ModelParams& p = choice.p;
    const double keep = 1.0 - o.unexplained_min_rel;
    double share[2] = {0.0, 0.0};  // each GM's largest share of the model's AVAR
    for (const AdevPoint& pt : in_range(points_for_model(ac.clean, p), tau_max)) {
      const double total = model_avar(p, pt.tau_s);
      for (std::size_t g = 0; g < 2 && total > 0.0; ++g) {
        share[g] = std::max(share[g],
                            avar_gauss_markov(p.gm[g].sb, p.gm[g].tb_s, pt.tau_s) / total);
      }
    }
    const std::size_t g = share[0] <= share[1] ? 0 : 1;
    if (!(share[g] < 1.0 - keep * keep)) {
      return;
    }
    AfterContext fixed = ac;
    fixed.gm_tb_fixed_s = p.gm[1 - g].tb_s;
    const AfterChoice ch = fit_after(fixed, choice.terms & ~kFitGm2, p, p.sin_a > 0.0);
    const double rel = o.unexplained_min_rel;
    if (!ch.ok || (not_worse(choice.e, out.error_before) && !not_worse(ch.e, out.error_before)) ||
        ch.e.adev_rms_rel > choice.e.adev_rms_rel + rel ||
        ch.e.adev_max_rel > choice.e.adev_max_rel + rel) {
      return;  // the refit needs it: the others move (e.g. a flicker bank's lower end)
    }
    trial.effects = without_type(trial.effects, "gauss_markov");
    out.effects = without_type(out.effects, "gauss_markov");
    out.notes.push_back(
        "not named: gauss_markov (the GM of Tb = " + fmt("%.4g", p.gm[g].tb_s) +
        " s changes the model's ADEV by at most " +
        fmt("%.2g", 100.0 * (1.0 - std::sqrt(1.0 - share[g]))) + " % at any tau, under the " +
        fmt("%.0f", 100.0 * o.unexplained_min_rel) + " % the analysis reports as unexplained; " +
        "removed, the other GM kept at Tb = " + fmt("%.4g", p.gm[1 - g].tb_s) +
        " s: error over [Ts, T/10] RMS " + fmt("%.3f", ch.e.adev_rms_rel) + " / max " +
        fmt("%.3f", ch.e.adev_max_rel) + ", with it " + fmt("%.3f", choice.e.adev_rms_rel) +
        " / " + fmt("%.3f", choice.e.adev_max_rel) + ")");
    choice = ch;
    drop_unmodelled_effects(choice.p, trial, false);  // the effects take the refit's parameters
    drop_unmodelled_effects(choice.p, out);
  }

  // The after-model (never worse), the names checked, the remainder said, the filters run.
  // The sensor's output filter: a first-order low-pass of time constant Tf on the white noise
  // (ModelParams::n_filter_s), the shape of the first ADEV points of a sensor that filters and
  // decimates internally (AVAR N^2 / tau - 1.5 N^2 Tf / tau^2 for tau >> Tf: below the white
  // line, where quantization lies above it). Tested on the model after once its terms are
  // chosen: earlier, a narrowband oscillation or a sinusoid bends the same first points and the
  // filter would imitate it. Tf is searched on a log grid over [Ts / 16, 2 Ts] (shorter, it
  // moves the first ADEV point by under 10 %: not a filter the record can tell) and refined by
  // golden section, each trial the fit of the chosen terms. It is kept when it lowers the ADEV
  // cost by more than the search's test (cost_thr), as a term must: in that fit, in the model
  // after refitted with it (fit_after), and once the terms are named (settle_terms, run with
  // and without it: a filter that makes a term unnamed is not kept).
  // Returns Tf (0: the filter does not pass) and the refitted choice in `choice`; drop: the
  // smaller of the filter's cost drops in the fit of the chosen terms and in the refit.
  double output_filter_fit(const AfterContext& ac, AfterChoice& choice, double& drop) {
    const ModelParams shape = choice.p;
    const bool keep_sines = shape.sin_a > 0.0;
    const Points pts =
        in_range(points_for_model(keep_sines ? ac.fit_set : ac.clean, shape), tau_max);
    const double tb_fixed = ac.gm_tb_fixed_s;
    const auto cost_with = [&](double tf) {
      const FitResult f =
          tb_fixed > 0.0 ? fit_terms(pts, choice.terms, ts, tau_max, tb_fixed * (1.0 + 1e-9),
                                     &shape, tf, tb_fixed * (1.0 - 1e-9))
                         : fit_terms(pts, choice.terms, ts, tau_max, tb_max, &shape, tf);
      if (f.status != FitStatus::kOk || !(f.params.n > 0.0)) {
        return std::numeric_limits<double>::infinity();
      }
      const ModelParams q = keep_sines ? with_sines(f.params, shape) : f.params;
      return residual(in_range(points_for_model(ac.clean, q), tau_max), q, o, ts, tau_max).cost;
    };
    const auto cost_at = [&](double ln_tf) { return cost_with(std::exp(ln_tf)); };
    const double lo = std::log(kMinOutputFilterPerTs * ts);
    const double hi = std::log(kMaxOutputFilterPerTs * ts);
    constexpr int kGrid = 8;
    const double step = (hi - lo) / (kGrid - 1);
    double best_ln = lo;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int i = 0; i < kGrid; ++i) {
      const double c = cost_at(lo + step * i);
      if (c < best_cost) {
        best_cost = c;
        best_ln = lo + step * i;
      }
    }
    const double tf = std::exp(
        golden_min(cost_at, std::max(lo, best_ln - step), std::min(hi, best_ln + step), 10));
    // The filter's own gain: the same fit with and without it (a refit can also land on another
    // optimum of the other terms, which is not the filter's doing).
    drop = cost_with(0.0) - cost_with(tf);
    if (!(drop > cost_thr)) {
      return 0.0;
    }
    AfterContext trial = ac;
    trial.white_filter_s = tf;
    const AfterChoice f = fit_after(trial, choice.terms, shape, keep_sines);
    drop = std::min(drop, f.ok && f.terms == choice.terms ? choice.e.cost - f.e.cost : 0.0);
    if (!(drop > cost_thr)) {
      return 0.0;
    }
    choice = f;
    return tf;
  }

  // The one-GM model that takes a walk's place (slow_gm_for_walk): white + one GM and no K,
  // costing at most cost_thr more than the walk model on the ADEV, and not worse than before
  // where the walk model was not.
  [[nodiscard]] static bool slow_gm_passes(const AfterContext& ac, const AfterChoice& walk,
                                           const AfterChoice& f) {
    return f.ok && f.p.n_gm == 1 && f.p.gm[0].sb > 0.0 && !(f.p.k > 0.0) &&
           f.e.cost <= walk.e.cost + ac.cost_thr &&
           (not_worse(f.e, ac.before) || !not_worse(walk.e, ac.before));
  }

  // The GM with which slow_gm_for_walk would replace the walk model `walk`, given the block
  // means' fit sg over a record of t_rec_s (not checked by slow_gm_passes: the caller does).
  [[nodiscard]] AfterChoice slow_gm_choice(const AfterContext& ac, const AfterChoice& walk,
                                           const SlowGmFit& sg, double t_rec_s) {
    // Tb: the block means' own, where the model with it passes (below); else the ADEV's
    // preferred model (never worse than before first, then the lower cost) over octaves from it
    // either way inside the block means' 95 % set, up to kSlowGmTbPerRecord T. At each Tb two
    // models: the ADEV refit with Tb held, and the walk model as it stands with K read as the
    // GM's drive (Sb = K^2: the same curve where tau << Tb) and its other GMs left out (a
    // K the block means set, as walk_only_k's, is not the ADEV fit's optimum, and a refit by
    // the EDF weights can cost more in sum z^2 than the model it replaces).
    const double tb = sg.fit.model.gm[0].tb_s;
    const double tb_top = std::min(sg.tb_hi_95_s, kSlowGmTbPerRecord * t_rec_s);
    std::vector<double> tbs = {tb};
    for (int i = 1; i < 64 && std::ldexp(tb, -i) >= sg.tb_lo_95_s; ++i) {
      tbs.push_back(std::ldexp(tb, -i));  // octaves down to the set's lower end
    }
    for (int i = 1; i < 64 && std::ldexp(tb, i) <= tb_top; ++i) {
      tbs.push_back(std::ldexp(tb, i));  // and up to its upper end
    }
    const ModelParams& p = walk.p;
    const std::uint32_t one_gm = (walk.terms & ~(kFitRrw | kFitGm2)) | kFitGm1;
    AfterChoice ch;
    for (std::size_t i = 0; i < tbs.size(); ++i) {
      AfterContext fixed = ac;
      fixed.gm_tb_fixed_s = tbs[i];
      AfterChoice read;
      read.terms = one_gm;
      read.p = p;
      read.p.k = 0.0;
      read.p.n_gm = 1;
      read.p.gm[0] = GmParam{p.k * p.k, tbs[i]};
      fill_errors(points_for_model(ac.clean, read.p), read.p, o, ts, tau_max, read.e);
      read.ok = true;
      AfterChoice best_here;
      for (const AfterChoice& f : {fit_after(fixed, one_gm, p, p.sin_a > 0.0), read}) {
        // (at the block means' own Tb, of those that pass)
        if (f.ok && f.p.n_gm == 1 && f.p.gm[0].sb > 0.0 &&
            (i > 0 || slow_gm_passes(ac, walk, f)) && preferred(f, best_here, ac.before)) {
          best_here = f;
        }
      }
      if (i == 0 && best_here.ok) {  // the block means' own Tb
        ch = best_here;
        break;
      }
      if (preferred(best_here, ch, ac.before)) {
        ch = best_here;
      }
    }
    return ch;
  }

  // A walk in the model after beside no GM the ADEV shows (has_visible_gm: the GMs it holds, if
  // any, dominate the model nowhere or peak beyond T/10): the record's only feature beyond the
  // white noise at the long taus is then a rise without a peak, which the first-order model's
  // own GM with a Tb beyond what the record resolves explains as well. On the walk's block
  // means (test_rrw of the model as it stands), the walk model (white + GMs with tb <= tb_max
  // + K) against white + one GM with Tb free up to kSlowGmTbPerRecord x T
  // (slow_gm_against_walk): where the walk does not beat it by the likelihood's level (2 ln LR
  // <= lr_thr), nothing beyond the base model is named. The model after takes that GM in place
  // of K and of its other GMs: Tb from the block means (the ADEV cannot place a peak it does
  // not show), Sb and the rest from the ADEV with Tb held (below); kept when its ADEV cost is
  // within cost_thr of the walk model's and it is not worse than before where the walk model
  // was not (a GM the fit placed beside the walk that the ADEV needs keeps the walk). Its Tb's
  // 95 % interval is the block means' profile likelihood's, open-ended where the record bounds
  // it from below only (attach_slow_gm_interval). A GM that shows its peak with a further rise
  // after it keeps the walk (the demo's GM of Tb = 159 s with a walk). Returns true when the GM
  // took the walk's place (slow_gm set).
  bool slow_gm_for_walk(const AfterContext& ac, AfterChoice& choice) {
    const ModelParams& p = choice.p;
    if (!(p.k > 0.0) || (choice.terms & kFitRrw) == 0U || p.bi > 0.0 ||
        has_visible_gm(ac, p)) {
      return false;
    }
    const bool ramp = (choice.terms & kFitRamp) != 0U;
    const RrwLikelihoodTest lt = test_rrw(fit_record(), ts, p, tb_max, ramp, step_at);
    if (!lt.ok) {
      return false;
    }
    const double t_rec_s = lt.block_s * static_cast<double>(lt.blocks);
    const SlowGmFit sg = slow_gm_against_walk(lt, kSlowGmTbPerRecord * t_rec_s);
    if (!sg.ok) {
      return false;
    }
    const std::string against =
        "on " + std::to_string(lt.blocks) + " block means of " + fmt("%.3g", lt.block_s) +
        " s the walk model (K = " + fmt("%.3g", lt.h1.model.k) + ", GMs with Tb <= " +
        fmt("%.0f", tb_max) + " s) against white + one GM with Tb free up to " +
        fmt("%.0f", kSlowGmTbPerRecord) + " T (its Tb " + fmt("%.4g", sg.fit.model.gm[0].tb_s) +
        " s, 2 ln LR " + fmt("%.1f", sg.lr_reverts) + " against Tb = " +
        fmt("%.0f", kSlowGmTbPerRecord) + " T): 2 ln LR = " + fmt("%.1f", sg.lr_walk);
    if (sg.lr_walk > lr_thr) {
      out.notes.push_back("rate_random_walk beside no GM the ADEV shows: " + against + " > " +
                          fmt("%.2f", lr_thr) + ": more than the first-order model holds");
      return false;
    }
    // A record that bounds the GM's Tb from below only, with every GM it allows peaking (at
    // 1.89 Tb) beyond T / 4: over [Ts, T / 10] each such GM's ADEV stays within 25 % of a +1/2
    // slope, the walk's (a GM with Tb = inf, inside the set), and the walk is that slope's
    // one-parameter term (IEEE Std 952). The GM takes the walk's place only where the record
    // allows a GM that peaks nearer: one that bends inside the analysed taus.
    if (!std::isfinite(sg.tb_hi_95_s) &&
        imu::kGmPeakTauFactor * sg.tb_lo_95_s >= kWalkGmPeakPerRecord * t_rec_s) {
      out.notes.push_back("rate_random_walk beside no GM the ADEV shows: " + against +
                          " <= " + fmt("%.2f", lr_thr) + ", but the record allows only GMs "
                          "with Tb " + tb_set_text(sg.tb_lo_95_s, sg.tb_hi_95_s) +
                          " (95 %), each peaking beyond T/4: over [Ts, T/10] each rises "
                          "as the walk does, and the walk stays");
      return false;
    }
    const AfterChoice ch = slow_gm_choice(ac, choice, sg, t_rec_s);
    if (!slow_gm_passes(ac, choice, ch)) {
      out.notes.push_back(
          "rate_random_walk beside no GM the ADEV shows: " + against + " <= " +
          fmt("%.2f", lr_thr) + ", but that GM (Tb " + tb_set_text(sg.tb_lo_95_s, sg.tb_hi_95_s) +
          ") misses the ADEV over [Ts, T/10]" +
          (ch.ok ? " (cost " + fmt("%.1f", ch.e.cost) + " against the walk model's " +
                       fmt("%.1f", choice.e.cost) + ", RMS " + fmt("%.3f", ch.e.adev_rms_rel) +
                       " / max " + fmt("%.3f", ch.e.adev_max_rel) + ")"
                 : std::string(" (its fit failed)")) +
          ": the walk stays");
      return false;
    }
    out.effects = without_type(out.effects, "rate_random_walk");
    out.effects = without_type(out.effects, "gauss_markov");
    slow_gm = SlowGm{ch.p.gm[0].tb_s, sg.tb_lo_95_s, sg.tb_hi_95_s};
    out.notes.push_back(
        "not named: rate_random_walk (K = " + fmt("%.4g", p.k) + "): the record does not tell a "
        "GM slower than it resolves from a rate random walk; " + against + " <= " +
        fmt("%.2f", lr_thr) + ". The model after holds the first-order model's GM with that Tb "
        "(Sb = " + fmt("%.4g", ch.p.gm[0].sb) + ", Tb = " + fmt("%.4g", ch.p.gm[0].tb_s) +
        " s, 95 %: Tb " + tb_set_text(sg.tb_lo_95_s, sg.tb_hi_95_s) + ") in place of K" +
        (p.n_gm > 0 ? " and of its GMs that the ADEV does not show" : "") +
        ": error over [Ts, T/10] RMS " + fmt("%.3f", ch.e.adev_rms_rel) + " / max " +
        fmt("%.3f", ch.e.adev_max_rel) + " (with K " + fmt("%.3f", choice.e.adev_rms_rel) +
        " / " + fmt("%.3f", choice.e.adev_max_rel) + ")");
    choice = ch;
    return true;
  }

  // "from 1200 s, not bounded above by this record" / "1200 to 5000 s": a Tb's 95 % set.
  [[nodiscard]] static std::string tb_set_text(double lo_s, double hi_s) {
    return std::isfinite(hi_s)
               ? fmt("%.3g", lo_s) + " to " + fmt("%.3g", hi_s) + " s"
               : "from " + fmt("%.3g", lo_s) + " s, not bounded above by this record";
  }

  // The model after's GM that took a walk's place (slow_gm_for_walk): its Tb's interval is the
  // block means' profile likelihood's (the ADEV, over [Ts, T/10], shows no peak to place it
  // by), said in a note where it spans more than two decades or is open-ended.
  void attach_slow_gm_interval() {
    const ModelParams& m = out.model_after;
    if (!(slow_gm.tb_s > 0.0) || m.n_gm == 0 ||
        std::fabs(m.gm[0].tb_s / slow_gm.tb_s - 1.0) > 1e-6) {
      return;
    }
    // With Tb open above, sigma = sqrt(Sb Tb / 2) is too (the walk's power Sb is what the
    // record determines).
    const bool open = !std::isfinite(slow_gm.tb_hi_s);
    for (ParamInterval& iv : out.model_after_ci95) {
      if (iv.name == "gm_tb_s") {
        iv.lo = slow_gm.tb_lo_s;
        iv.hi = slow_gm.tb_hi_s;
      } else if (iv.name == "gm_sigma" && open) {
        iv.lo = 0.0;
        iv.hi = std::numeric_limits<double>::infinity();
      }
    }
    if (!(slow_gm.tb_hi_s <= kDeterminedSpan * slow_gm.tb_lo_s)) {
      out.notes.push_back(std::string("model after, GM ") + (open ? "sigma and tb_s" : "tb_s") +
                          ": not determined by this record (95 % interval of Tb " +
                          tb_set_text(slow_gm.tb_lo_s, slow_gm.tb_hi_s) +
                          ", the block means' profile likelihood; its drive Sb = " +
                          fmt("%.4g", m.gm[0].sb) + " is the walk's K^2 at tau << Tb; a longer "
                          "record narrows it)");
    }
  }

  // The model after's terms named or removed (walk_only_k, slow_gm_for_walk, name_terms,
  // remove_unnamed_terms): changes choice and out's effects and notes, and slow_gm.
  void settle_terms(const AfterContext& ac, AfterChoice& choice,
                    std::vector<UnexplainedRun>& withdrawn) {
    slow_gm = SlowGm{};
    const WalkOnly walk =
        walk_only_k(ac, fit_record(), (terms & kFitRamp) != 0U, step_at, choice.p, out.notes);
    if (walk.k > 0.0) {
      const ModelParams q = walk_alone(choice.p, walk.k, walk.slow_tb_s);
      choice.terms &= q.n_gm < 2 ? ~kFitGm2 : ~0U;
      choice.p = q;
      fill_errors(points_for_model(ac.clean, q), q, o, ts, tau_max, choice.e);
    }
    // After walk_only_k: a slow GM + K whose GM the record does not need is the walk alone,
    // and the walk alone beside no GM the ADEV shows is the base GM, slower than the record
    // resolves, when the record does not tell them apart.
    AfterContext acs = ac;
    if (slow_gm_for_walk(ac, choice)) {
      acs.gm_tb_fixed_s = slow_gm.tb_s;
    }
    drop_unmodelled_effects(choice.p, out);
    name_terms(acs, choice, withdrawn);
    drop_degenerate_effects(ts, n_d, out);
    remove_unnamed_terms(acs, choice, out);
    drop_undetermined_sinusoid(acs, choice);
  }

  // A sinusoid is its period: one whose frequency (or amplitude) the record leaves undetermined
  // (determined(), the report's "not determined" note) names
  // no period the record holds; it is the fit's use of a periodic shape for a slow wander the
  // other terms leave (e.g. bias instability's at a few hundred seconds). It leaves the
  // effects and the model, which is refitted; what it held is then reported as unexplained.
  // Only a model with one sinusoid: the refit keeps a model's sinusoids together or not at all.
  void drop_undetermined_sinusoid(const AfterContext& acs, AfterChoice& choice) {
    if (!(choice.p.sin_a > 0.0) || choice.p.sin2_a > 0.0 || !named_type(out.effects, "sinusoid")) {
      return;
    }
    Report tmp;
    tmp.samples = out.samples;
    tmp.effects = out.effects;
    tmp.model_after = choice.p;
    attach_intervals(points_for_model(acs.clean, choice.p), o, ts, tau_max, tmp);
    for (const Effect& e : tmp.effects) {
      if (e.type != "sinusoid") {
        continue;
      }
      for (const ParamInterval& iv : e.ci95) {
        if (determined(iv)) {
          continue;
        }
        out.notes.push_back("not named: sinusoid (f = " + fmt("%.4g", e.freq_hz) + " Hz: its " +
                            iv.name + " is not determined by this record, 95 % interval " +
                            fmt("%.3g", iv.lo) + " to " + fmt("%.3g", iv.hi) +
                            "; no period the record holds)");
        out.effects = without_type(out.effects, "sinusoid");
        remove_unnamed_terms(acs, choice, out);
        return;
      }
    }
  }

  // settle_terms on the model after with the output filter (if it passes output_filter_fit)
  // and without it; the filter stays when the settled model with it is still better by more
  // than cost_thr. Sets white_filter_s; says which in a note.
  void settle_terms_and_filter(const AfterContext& ac0, AfterChoice& choice,
                               std::vector<UnexplainedRun>& withdrawn) {
    AfterChoice filtered = choice;
    double drop = 0.0;
    const double tf = output_filter_fit(ac0, filtered, drop);
    if (tf > 0.0) {
      const Report plain_start = out;
      AfterContext acf = ac0;
      acf.white_filter_s = tf;
      std::vector<UnexplainedRun> withdrawn_f;
      settle_terms(acf, filtered, withdrawn_f);
      Report with_filter = std::move(out);
      const SlowGm slow_gm_f = slow_gm;
      out = plain_start;
      settle_terms(ac0, choice, withdrawn);
      const double settled_drop = choice.e.cost - filtered.e.cost;
      if (settled_drop > cost_thr) {
        out = std::move(with_filter);
        choice = filtered;
        withdrawn = std::move(withdrawn_f);
        slow_gm = slow_gm_f;
        white_filter_s = tf;
        out.notes.push_back(filter_kept_note(tf, "", settled_drop));
      } else if (!filter_on_settled(ac0, choice)) {
        out.notes.push_back("not added: an output filter on the white noise of Tf = " +
                            fmt("%.3g", 1e3 * tf) + " ms (cost drop " + fmt("%.1f", drop) +
                            " alone, " + fmt("%.1f", settled_drop) +
                            " once the terms are named, <= " + fmt("%.1f", cost_thr) + ")");
      }
    } else {
      settle_terms(ac0, choice, withdrawn);
      if (!filter_on_settled(ac0, choice)) {
        out.notes.push_back(std::isfinite(drop)
                                ? "not added: an output filter on the white noise (cost drop " +
                                      fmt("%.1f", drop) + " <= " + fmt("%.1f", cost_thr) + ")"
                                : std::string("not tried: an output filter on the white noise "
                                              "(no ADEV points to fit it on)"));
      }
    }
  }

  // The output filter on the settled model, its named terms kept as they are: naming with the
  // filter can go another way (a term whose ADEV the filter shares at the first points is then
  // unnamed, and what it carried elsewhere is lost with it), which says nothing about the
  // filter. Kept when the fit of the settled terms with it lowers the ADEV cost by more than
  // cost_thr (output_filter_fit, the same test); the effects take the refit's parameters.
  bool filter_on_settled(const AfterContext& ac0, AfterChoice& choice) {
    AfterChoice filtered = choice;
    double drop = 0.0;
    AfterContext ac = ac0;
    ac.gm_tb_fixed_s = slow_gm.tb_s;  // a GM that took a walk's place keeps its Tb
    const double tf = output_filter_fit(ac, filtered, drop);
    if (!(tf > 0.0) || filtered.terms != choice.terms) {
      return false;
    }
    choice = filtered;
    white_filter_s = tf;
    drop_unmodelled_effects(choice.p, out);
    out.notes.push_back(filter_kept_note(tf, ", fitted with the named terms", drop));
    return true;
  }

  // The note of a kept output filter: Tf, how it was fitted, its cost drop against cost_thr.
  [[nodiscard]] std::string filter_kept_note(double tf, const char* how, double drop) const {
    return "the white noise is seen through the sensor's output filter, a first-order low-pass "
           "of Tf = " + fmt("%.3g", 1e3 * tf) + " ms" + how +
           " (the first ADEV points lie below the white line; cost drop " + fmt("%.1f", drop) +
           " > " + fmt("%.1f", cost_thr) + ")";
  }

  // The parts of the record that are not stationary (noise level, transients), as unexplained
  // time ranges, said in a note.
  void add_time_ranges() {
    if (noise_change.found) {
      const double t_c = static_cast<double>(noise_change.at) * ts;
      const double t_end = static_cast<double>(y.size()) * ts;
      const bool louder_after = noise_change.std_ratio > 1.0;
      UnexplainedRun u;
      u.t_min_s = louder_after ? t_c : 0.0;
      u.t_max_s = louder_after ? t_end : t_c;
      u.tau_min_s = ts;
      u.tau_max_s = static_cast<double>(noise_change.block_len) * ts;
      u.max_abs_z = noise_change.statistic;
      u.what = "the white noise's std changes at t = " + fmt("%.1f", t_c) + " s by x " +
               fmt("%.2f", noise_change.std_ratio) + " (the model's N is the record's average)";
      out.unexplained.push_back(u);
      out.notes.push_back("noise level: " + u.what + "; CUSUM of " +
                          std::to_string(noise_change.blocks) + " blocks' log-levels " +
                          fmt("%.2f", noise_change.statistic) + " > " +
                          fmt("%.2f", noise_change.threshold) +
                          "; outliers judged against each part's own spread");
    }
    out.unexplained.insert(out.unexplained.end(), time_ranges.begin(), time_ranges.end());
  }

  // Stationarity of the named terms: each ADEV term named on the record must also hold on each
  // half of it. The half's ADEV over the taus where the term dominates the model (>= half its
  // AVAR, within [Ts, T_half/10]) is compared with the model fitted to the whole record, with
  // the half's own intervals; a |z| above the Bonferroni level over every tau so tested (both
  // halves, every term) that also misses by more than unexplained_min_rel says the term does
  // not hold there: an unexplained time range over that half. Under a stationary record the
  // halves' deviations from the whole record's model are smaller than from the truth (the
  // whole contains them), so the level is conservative.
  struct PartMiss {
    std::string type;
    std::size_t begin = 0;
    std::size_t end = 0;
    double dom_lo = 0.0;
    double dom_hi = 0.0;
    double zmax = 0.0;
    int sign = 0;
    double rel = 0.0;
  };
  static constexpr std::size_t kMinPartSamples = 4096;

  // The worst tau of each ADEV term in one part (taus tested: added to `tested`).
  void part_misses(std::size_t b, std::size_t e, std::vector<PartMiss>& misses,
                   std::size_t& tested) const {
    const std::vector<std::int32_t> c(counts.begin() + static_cast<std::ptrdiff_t>(b),
                                      counts.begin() + static_cast<std::ptrdiff_t>(e));
    std::vector<std::uint8_t> g;
    if (!gap.empty()) {
      g.assign(gap.begin() + static_cast<std::ptrdiff_t>(b),
               gap.begin() + static_cast<std::ptrdiff_t>(e));
    }
    const double tmax = tau_max * static_cast<double>(e - b) / static_cast<double>(counts.size());
    const Points pts = in_range(points_for_model(adev_of(c, g, ts, lsb), cur_p), tmax);
    const Residual r = residual(pts, cur_p, o, ts, tmax);
    for (const auto& eff : out.effects) {
      if (effect_term_avar(eff.type, cur_p, 1.0) < 0.0) {
        continue;
      }
      PartMiss m{eff.type, b, e, 0.0, 0.0, 0.0, 0, 0.0};
      for (std::size_t i = 0; i < pts.size() && i < r.z.size(); ++i) {
        const double t = pts[i].tau_s;
        if (!term_dominates(eff.type, cur_p, t)) {
          continue;
        }
        ++tested;
        m.dom_lo = m.dom_lo > 0.0 ? m.dom_lo : t;
        m.dom_hi = t;
        if (std::fabs(r.z[i]) > m.zmax) {
          m.zmax = std::fabs(r.z[i]);
          m.sign = r.z[i] > 0.0 ? 1 : -1;
          m.rel = std::fabs(std::sqrt(model_avar(cur_p, t) / pts[i].avar) - 1.0);
        }
      }
      if (m.dom_hi > 0.0) {
        misses.push_back(m);
      }
    }
  }

  // A term that does not hold on a part: its name and the unexplained run said for it.
  struct TermPart {
    std::string type;
    UnexplainedRun run;
  };
  std::vector<TermPart> check_terms_on_halves() {
    std::vector<TermPart> runs;
    const std::size_t n = counts.size();
    if (n < 2 * kMinPartSamples) {
      return runs;
    }
    std::vector<PartMiss> misses;
    std::size_t tested = 0;
    part_misses(0, n / 2, misses, tested);
    part_misses(n / 2, n, misses, tested);
    if (tested == 0) {
      return runs;
    }
    const double z_thr = two_sided_normal_threshold(o.alpha / static_cast<double>(tested));
    for (const auto& m : misses) {
      if (!(m.zmax > z_thr) || !(m.rel > o.unexplained_min_rel)) {
        continue;
      }
      UnexplainedRun u;
      u.tau_min_s = m.dom_lo;
      u.tau_max_s = m.dom_hi;
      u.max_abs_z = m.zmax;
      u.sign = m.sign;
      u.t_min_s = static_cast<double>(m.begin) * ts;
      u.t_max_s = static_cast<double>(m.end) * ts;
      u.what = m.type + " does not hold on the " + (m.begin == 0 ? "first" : "second") +
               " half: there the model (fitted to the whole record) lies " +
               (m.sign > 0 ? "above" : "below") + " the half's ADEV by up to " +
               fmt("%.0f", 100.0 * m.rel) + " % where the term dominates";
      out.unexplained.push_back(u);
      runs.push_back(TermPart{m.type, u});
      out.notes.push_back("stationarity: " + u.what + " (tau " + fmt("%.3g", m.dom_lo) + "-" +
                          fmt("%.3g", m.dom_hi) + " s, |z| " + fmt("%.1f", m.zmax) + " > " +
                          fmt("%.2f", z_thr) + ", the Bonferroni level over " +
                          std::to_string(tested) + " taus of both halves)");
    }
    return runs;
  }

  // The model after, its errors and its unexplained remainder. A walk that does not hold on a
  // half of the record (check_terms_on_halves: the halves' ADEV where the walk dominates miss
  // the whole record's model beyond their intervals) is not named: a walk is stationary in
  // its increments, and a rise at the long taus made by one part of the record (a level shift
  // or a drift there) is what it stands in for. The walk leaves the model, the model after is
  // chosen again, and the half where the rise fails stays unexplained with its time range.
  void after_model() {
    const Report start = out;
    const double white_filter0_s = white_filter_s;
    const std::vector<TermPart> parts = settle_after();
    for (const auto& [type, u] : parts) {
      if (type != "rate_random_walk" || (terms & kFitRrw) == 0U) {
        continue;
      }
      Report settled = std::move(out);
      const double white_filter_settled_s = white_filter_s;
      out = start;
      white_filter_s = white_filter0_s;
      const double k = cur_p.k;
      if (!withdraw_walk("it does not hold on the " +
                         std::string(u.t_min_s <= 0.0 ? "first" : "second") +
                         " half of the record (reported as unexplained over that half)")) {
        out = std::move(settled);
        white_filter_s = white_filter_settled_s;
        break;
      }
      out.effects.erase(std::remove_if(out.effects.begin(), out.effects.end(),
                                       [](const Effect& e) { return e.type == "rate_random_walk"; }),
                        out.effects.end());
      UnexplainedRun w = u;
      w.what = "the rise at the long taus (a walk of K = " + fmt("%.3g", k) +
               " over the whole record) " + u.what.substr(type.size() + 1);
      (void)settle_after();
      out.unexplained.push_back(w);
      break;
    }
    finish_after();
  }

  // A model after that misses the ADEV by RMS > kGrossMisfitRms, or lies far above it
  // (lies_far_above), is replaced by robust_after's refit when that is better on both errors
  // (its effects follow it, said). Returns the taus the refit describes, empty when the choice
  // stands (every tau then).
  Points refit_gross_misfit(const AfterContext& ac, AfterChoice& choice) {
    if (!(choice.e.adev_rms_rel > kGrossMisfitRms) && !lies_far_above(ac, choice.p)) {
      return {};
    }
    EnvelopeFit rb = robust_after(ac, choice);
    if (!rb.choice.ok || !(rb.choice.e.adev_rms_rel < choice.e.adev_rms_rel) ||
        !(rb.choice.e.adev_max_rel < choice.e.adev_max_rel)) {
      return {};
    }
    out.notes.push_back(
        "the model after missed the ADEV by RMS " + fmt("%.3f", choice.e.adev_rms_rel) +
        " / max " + fmt("%.3f", choice.e.adev_max_rel) + " over [Ts, T/10] (its GM bent onto "
        "what no term of the analysis is): white noise and one GM refitted to the ADEV's lower "
        "envelope, the " + std::to_string(rb.agreed.size()) + " taus where the data do not lie "
        "above the model (RMS " + fmt("%.3f", rb.choice.e.adev_rms_rel) + " / max " +
        fmt("%.3f", rb.choice.e.adev_max_rel) + "); the others are unexplained and their "
        "intervals read on those taus");
    choice = rb.choice;
    drop_unmodelled_effects(choice.p, out);
    return std::move(rb.agreed);
  }

  // after_model's choice; returns the stationarity check's runs.
  std::vector<TermPart> settle_after() {
    // ---- after: never worse than before, every named effect real, the remainder said.
    const AdevSet& clean = adev_y;
    out.adev_clean = clean.by_alpha[2];
    // Bias instability in the model: the record's likelihood of it beside the model's other
    // terms (with the walk when the model has one) decides whether it is required, as the
    // walk's test does for K.
    double bi_lr = 0.0;
    if ((terms & kFitFlicker) != 0U && cur_p.bi > 0.0) {
      const bool walk = (terms & kFitRrw) != 0U;
      const LongTauPair lp = long_tau_pair(&cur_p, (terms & kFitRamp) != 0U, walk);
      bi_lr = walk ? lp.b_beside_k : lp.b_alone;
    }
    const std::uint32_t required =
        (walk_lr > lr_thr ? kFitRrw : 0U) | (bi_lr > lr_thr ? kFitFlicker : 0U);
    const AfterContext ac0{o,        ts,       tau_max,  tb_max, clean, fit_set, out.error_before,
                           cost_thr, 0.0,      required, walk_lr, bi_lr};
    // The base family alone (no ADEV term accepted) is refitted over [Ts, T/10] too, under the
    // same never-worse rule: the before-model was fitted over [Ts, 100 s] only.
    AfterChoice choice = choose_after(ac0, terms, cur_p, out.model_before, out.notes);
    std::vector<UnexplainedRun> withdrawn;
    settle_terms_and_filter(ac0, choice, withdrawn);
    const AfterContext ac{o,        ts,       tau_max, tb_max, clean, fit_set, out.error_before,
                          cost_thr, white_filter_s, required, walk_lr, bi_lr, slow_gm.tb_s};
    const Points agreed = refit_gross_misfit(ac, choice);
    if (!agreed.empty()) {
      slow_gm = SlowGm{};  // robust_after's GM is its own
    }
    cur_p = choice.p;
    out.model_after = cur_p;
    out.error_after = choice.e;
    out.unexplained = unexplained_runs(ac, cur_p);
    add_time_ranges();
    std::vector<TermPart> parts = check_terms_on_halves();
    attach_intervals(agreed.empty() ? points_for_model(clean, cur_p) : agreed, o, ts, tau_max,
                     out);
    std::vector<AdevReading> readings =
        short_tau_readings(ac, choice.terms, cur_p, noise_parts(y, gap, noise_change));
    for (AdevReading& rd : long_tau_readings(ac, choice.terms, cur_p)) {
      readings.push_back(std::move(rd));
    }
    widen_for_readings(readings, out);
    attach_slow_gm_interval();
    add_rival_shift_range();
    for (const auto& w : withdrawn) {
      bool covered = false;
      for (const auto& u : out.unexplained) {
        covered = covered || (u.tau_min_s <= w.tau_max_s && w.tau_min_s <= u.tau_max_s);
      }
      if (!covered) {
        out.unexplained.push_back(w);
      }
    }
    return parts;
  }

  void finish_after() {
    if (!not_worse(out.error_after, out.error_before)) {
      out.notes.push_back("the model after is worse than the model before on the ADEV (RMS " +
                          fmt("%.3f", out.error_after.adev_rms_rel) + " / max " +
                          fmt("%.3f", out.error_after.adev_max_rel) + " against " +
                          fmt("%.3f", out.error_before.adev_rms_rel) + " / " +
                          fmt("%.3f", out.error_before.adev_max_rel) +
                          "): it holds only the terms the analysis names");
    }
    if (!out.unexplained.empty()) {
      std::string ranges;
      for (const auto& u : out.unexplained) {
        ranges += (ranges.empty() ? "" : ", ") + fmt("%.3g", u.tau_min_s) + "-" +
                  fmt("%.3g", u.tau_max_s) + " s (max |z| " + fmt("%.1f", u.max_abs_z) + ")";
      }
      out.notes.push_back("unexplained: the final model still misses the data at tau " + ranges +
                          "; no term of the analysis accounts for it");
    }
    // The filter sees the record without the deterministic terms the model holds (their
    // least-squares estimates): sinusoids, and the least-squares line for a ramp.
    // fit_record() is not read again: with a sinusoid, y_det takes its storage.
    std::vector<double> y_det =
        cur_p.sin_a > 0.0 && !y_minus_sine.empty() ? std::move(y_minus_sine) : y;
    y_minus_sine = std::vector<double>{};
    if (cur_p.r > 0.0) {
      remove_line(y_det, ts);
    }
    // The outliers were found on the before-model's innovations; each must also be one on the
    // after-model's (a model that misses the data makes large innovations that are not outliers).
    for (const auto& [i, d] : outlier_delta) {
      y_det[i] += d;
    }
    const double known_clean = initial_level(y_det);
    const FilterRun fa = run_filter(cur_p, ts, y_det, known_clean, &outlier, false);
    y_det = std::vector<double>{};
    confirm_outliers(fa, outlier, outlier_delta, o.alpha, ts, lattice_step(cur_p), outlier_split,
                     outlier_guard, out);
    out.error_after.nis_mean = fa.nis_mean;
    out.error_after.nis_flagged_fraction = fa.nis_flagged;
    out.error_after.whiteness_flagged_fraction = fa.whiteness_flagged;
    out.error_after.filter_states = fa.states;
    out.error_after.cov_ratio = covariance_ratio(cur_p, ts, y);
    if (!fb.ok || !fa.ok) {
      out.notes.emplace_back("a bias filter could not be configured (NIS mean reported as 0)");
    }
    out.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.cpu_seconds = thread_cpu_s() - cpu0_s;
  }

  // prepare
  std::vector<double> y0;  // the record, gaps filled (until find_outliers moves it into y)
  const std::string& channel;
  const Options& o;
  Report& out;
  std::string& error;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  double cpu0_s = thread_cpu_s();
  std::vector<std::uint8_t> gap;   // 1 at a non-finite sample
  double ts = 0.0;
  double n_d = 0.0;
  double t_rec = 0.0;
  double tau_max = 0.0;
  double offset = 0.0;             // counts are taken from the first sample
  double lsb = 0.0;
  std::size_t sat = 0;
  std::vector<std::int32_t> counts;  // of y, kept current
  AdevSet raw;
  // fit_before
  FilterRun fb;
  // find_outliers, steps: the record cleaned of outliers and steps, its ADEV
  std::vector<double> y;
  std::vector<std::uint8_t> outlier;
  std::vector<std::pair<std::size_t, double>> outlier_delta;  // index, value - replacement
  std::size_t outlier_split = 0;   // the outlier gate's limits on |value - prediction| before
  double outlier_limit_a = 0.0;    // and after the noise level's change (the same without one)
  double outlier_limit_b = 0.0;
  std::size_t outlier_guard = 0;   // samples either side of the split judged by the louder part
  AdevSet adev_y;
  std::vector<std::uint64_t> step_at;
  double tb_max = 0.0;
  // select_terms
  Points eval;
  AdevSet fit_set;  // the points the linear terms are fitted to (sinusoid removed)
  Points fit_pts;
  std::uint32_t terms = 0;
  ModelParams cur_p{};
  double cur_cost = 0.0;
  double cost_thr = 0.0;  // the ADEV cost drop a term must make
  double lr_thr = 0.0;    // the record likelihood's level (no inflation)
  double walk_lr = -1.0;  // the walk's 2 ln LR on the record (< 0: not tested)
  NoiseLevelChange noise_change;             // of the white noise's level (find_noise_level_change)
  std::vector<UnexplainedRun> time_ranges;   // transients found by the step search
  bool shifts_repeat = false;                // repeated_shifts: no step is searched
  // Shifts taken out of the record but not named (step_beats_alternatives' `unnamed`): the
  // profile's shift, its threshold, and the index of its range in time_ranges.
  // The rivals of a level shift (step_beats_alternatives), as bits.
  static constexpr unsigned kRivalWalk = 1U;
  static constexpr unsigned kRivalBi = 2U;
  unsigned shift_rivals = 0;  // the rivals that made a shift so far unnamed
  struct UnnamedShift {
    StepLikelihood sl;
    double thr = 0.0;
    std::size_t range = 0;
    unsigned rivals = 0;  // beside which it did not stand
    bool named = false;   // named a step after all (settle_unnamed_shifts)
  };
  std::vector<UnnamedShift> unnamed_shifts;
  // The significant shift that a walk or bias instability explained nearly as well
  // (step_beats_alternatives), left in the record: add_rival_shift_range.
  struct RivalShift {
    bool found = false;
    StepLikelihood sl;
    double block_s = 0.0;
    std::string why;
    unsigned rivals = 0;
  };
  RivalShift rival_shift;
  std::size_t frozen_samples = 0;            // marked missing by mark_frozen_runs
  double white_filter_s = 0.0;  // the sensor's output filter on the white noise (0: none)
  // The model after's GM that took a walk's place (slow_gm_for_walk; tb_s 0: none): its Tb,
  // held in every later refit, and its 95 % set from the block means' profile likelihood.
  struct SlowGm {
    double tb_s = 0.0;
    double tb_lo_s = 0.0;
    double tb_hi_s = 0.0;
  };
  SlowGm slow_gm;
  // Terms the record's likelihood could not tell from a look-alike (ramp_or_walk,
  // walk_or_flicker): not proposed again.
  std::vector<std::string> ruled_out;
  // y minus the accepted sinusoid; empty while none is accepted (then y itself: a record-length
  // copy less)
  std::vector<double> y_minus_sine;
  [[nodiscard]] const std::vector<double>& fit_record() const {
    return y_minus_sine.empty() ? y : y_minus_sine;
  }
  bool have_sine = false;
  bool have_sine2 = false;
  SineFit sine{};
  // Per bump (by its tau index): the sinusoid estimate and the ADEV of y without it. The same
  // bump comes back round after round; each entry costs passes over the record.
  std::map<std::size_t, SineCand> sine_cache;
  std::map<double, bool> line_coherent;  // coherent_line's verdict by the line's frequency
  std::map<int, SineCand> harmonic_cache;   // by harmonic number, of y minus the sinusoid
  std::map<std::size_t, OscFit> osc_cache;  // by bump (tau index), of fit_record()'s PSD
  WelchPsd psd_of_y_fit;                    // empty until needed; reset when fit_record() changes
  SpectrumCache spectrum_of_y;              // of y (the sinusoid search reads y itself)
};

}  // namespace

ErrorStats score_model(const std::vector<AdevPoint>& pts, const ModelParams& m, const Options& o,
                       double tau_min_s, double tau_max_s) {
  ErrorStats e;
  fill_errors(pts, m, o, tau_min_s, tau_max_s, e);
  return e;
}

bool analyze(const std::vector<double>& y_in, const std::string& channel, const Options& o,
             Report& out, std::string& error) {
  Analysis a(y_in, channel, o, out, error);
  return a.run();
}

bool analyze(std::vector<double>&& y_in, const std::string& channel, const Options& o,
             Report& out, std::string& error) {
  Analysis a(std::move(y_in), channel, o, out, error);
  return a.run();
}

}  // namespace imu::analyze

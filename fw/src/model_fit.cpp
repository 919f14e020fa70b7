// Weighted NNLS fit of the model AVAR with a search over the correlation times.
#include "imu/model_fit.hpp"

#include <cmath>

#include "imu/linalg.hpp"

namespace imu {
namespace {

constexpr std::size_t kP = 8;  // slots: white, quantization, gm1, gm2, rrw, ramp, flicker, osc
constexpr std::size_t kSlotWhite = 0;
constexpr std::size_t kSlotQuant = 1;
constexpr std::size_t kSlotGm1 = 2;
constexpr std::size_t kSlotGm2 = 3;
constexpr std::size_t kSlotRrw = 4;
constexpr std::size_t kSlotRamp = 5;
constexpr std::size_t kSlotFlicker = 6;
constexpr std::size_t kSlotOsc = 7;
constexpr std::size_t kGridPoints = 24;
constexpr int kGoldenIterations = 40;
constexpr int kCoordinateRounds = 3;

struct Problem {
  std::size_t n = 0;
  double tau[kMaxFitPoints] = {};
  double avar[kMaxFitPoints] = {};
  double edf[kMaxFitPoints] = {};
  double w[kMaxFitPoints] = {};
  double white[kMaxFitPoints] = {};    // white AVAR at N = 1, through the output filter if any
  double flicker[kMaxFitPoints] = {};  // flicker bank AVAR at B = 1 (independent of Tb)
  double osc[kMaxFitPoints] = {};      // oscillation AVAR at sigma = 1 (shape fixed)
  double osc_f0_hz = 0.0;
  double osc_beta_per_s = 0.0;
  double osc_ts_s = 0.0;
  double flicker_lo_s = 0.0;
  double flicker_hi_s = 0.0;
  double white_filter_s = 0.0;
  bool used[kP] = {};
  double k2_fixed = 0.0;  // > 0: the walk's K^2 held there (FitOptions::k_fixed)
  std::uint32_t evaluations = 0;
};

struct Solution {
  double theta[kP] = {};
  double tb1 = 0.0;
  double tb2 = 0.0;
  double cost = 0.0;
  bool ok = false;
};

// Each term's AVAR at unit parameter (the fit is linear in N^2, Q^2, Sb, K^2, R^2, B^2,
// sigma^2); flicker and oscillation: their AVAR at unit parameter, computed once per point.
void basis(double tau, double tb1, double tb2, double white, double flicker, double osc,
           double (&f)[kP]) {
  f[kSlotWhite] = white;
  f[kSlotQuant] = avar_quantization(1.0, tau);
  f[kSlotGm1] = tb1 > 0.0 ? avar_gauss_markov(1.0, tb1, tau) : 0.0;
  f[kSlotGm2] = tb2 > 0.0 ? avar_gauss_markov(1.0, tb2, tau) : 0.0;
  f[kSlotRrw] = avar_rrw(1.0, tau);
  f[kSlotRamp] = avar_ramp(1.0, tau);
  f[kSlotFlicker] = flicker;
  f[kSlotOsc] = osc;
}

// Lawson-Hanson NNLS on the normal equations G x = h (G symmetric PSD, already scaled to unit
// diagonal on the columns in `cols`). Returns false if no passive set could be solved.
bool nnls_normal(const Mat<double, kP, kP>& g, const double (&h)[kP], const bool (&cols)[kP],
                 double (&x)[kP]) {
  bool passive[kP] = {};
  for (auto& v : x) {
    v = 0.0;
  }
  double hmax = 0.0;
  for (std::size_t j = 0; j < kP; ++j) {
    if (cols[j]) {
      hmax = std::fabs(h[j]) > hmax ? std::fabs(h[j]) : hmax;
    }
  }
  const double tol = 1e-12 * (hmax > 0.0 ? hmax : 1.0);
  bool any_solved = false;
  for (std::size_t outer = 0; outer < 3 * kP; ++outer) {
    std::size_t best = kP;
    double best_grad = tol;
    for (std::size_t j = 0; j < kP; ++j) {
      if (!cols[j] || passive[j]) {
        continue;
      }
      double grad = h[j];
      for (std::size_t k = 0; k < kP; ++k) {
        grad -= g(j, k) * x[k];
      }
      if (grad > best_grad) {
        best_grad = grad;
        best = j;
      }
    }
    if (best == kP) {
      break;  // Kuhn-Tucker conditions hold
    }
    passive[best] = true;
    for (std::size_t inner = 0; inner < 3 * kP; ++inner) {
      std::size_t idx[kP] = {};
      std::size_t m = 0;
      for (std::size_t j = 0; j < kP; ++j) {
        if (passive[j]) {
          idx[m++] = j;
        }
      }
      if (m == 0) {
        break;
      }
      Mat<double, kP, kP> a{};
      Mat<double, kP, 1> b{};
      for (std::size_t r = 0; r < m; ++r) {
        b(r, 0) = h[idx[r]];
        for (std::size_t c = 0; c < m; ++c) {
          a(r, c) = g(idx[r], idx[c]);
        }
      }
      Mat<double, kP, 1> z{};
      if (!lu_solve(a, b, z, m)) {
        passive[best] = false;  // collinear with the passive set: drop it and stop
        return any_solved;
      }
      any_solved = true;
      bool all_pos = true;
      for (std::size_t r = 0; r < m; ++r) {
        all_pos = all_pos && z(r, 0) > 0.0;
      }
      if (all_pos) {
        for (auto& v : x) {
          v = 0.0;
        }
        for (std::size_t r = 0; r < m; ++r) {
          x[idx[r]] = z(r, 0);
        }
        break;
      }
      double alpha = 1.0;
      for (std::size_t r = 0; r < m; ++r) {
        const double zr = z(r, 0);
        const double xr = x[idx[r]];
        if (zr <= 0.0) {
          const double den = xr - zr;
          const double al = den > 0.0 ? xr / den : 0.0;
          alpha = al < alpha ? al : alpha;
        }
      }
      for (std::size_t r = 0; r < m; ++r) {
        const std::size_t j = idx[r];
        x[j] += alpha * (z(r, 0) - x[j]);
        if (x[j] <= 1e-15) {
          x[j] = 0.0;
          passive[j] = false;
        }
      }
    }
  }
  return true;
}

Solution solve_at(Problem& pb, double tb1, double tb2) {
  ++pb.evaluations;
  Solution s;
  s.tb1 = tb1;
  s.tb2 = tb2;
  Mat<double, kP, kP> g{};
  double h[kP] = {};
  for (std::size_t i = 0; i < pb.n; ++i) {
    double f[kP];
    basis(pb.tau[i], tb1, tb2, pb.white[i], pb.flicker[i], pb.osc[i], f);
    const double w = pb.w[i];
    const double target = pb.avar[i] - pb.k2_fixed * f[kSlotRrw];  // less a walk held fixed
    for (std::size_t a = 0; a < kP; ++a) {
      if (!pb.used[a]) {
        continue;
      }
      h[a] += w * f[a] * target;
      for (std::size_t b = 0; b < kP; ++b) {
        if (pb.used[b]) {
          g(a, b) += w * f[a] * f[b];
        }
      }
    }
  }
  double d[kP] = {};
  bool cols[kP] = {};
  for (std::size_t a = 0; a < kP; ++a) {
    const bool held = a == kSlotRrw && pb.k2_fixed > 0.0;
    if (pb.used[a] && !held && g(a, a) > 0.0) {
      d[a] = std::sqrt(g(a, a));
      cols[a] = true;
    }
  }
  Mat<double, kP, kP> gs{};
  double hs[kP] = {};
  for (std::size_t a = 0; a < kP; ++a) {
    if (!cols[a]) {
      continue;
    }
    hs[a] = h[a] / d[a];
    for (std::size_t b = 0; b < kP; ++b) {
      if (cols[b]) {
        gs(a, b) = g(a, b) / (d[a] * d[b]);
      }
    }
  }
  double x[kP] = {};
  if (!nnls_normal(gs, hs, cols, x)) {
    return s;
  }
  for (std::size_t a = 0; a < kP; ++a) {
    s.theta[a] = cols[a] ? x[a] / d[a] : 0.0;
  }
  if (pb.k2_fixed > 0.0) {
    s.theta[kSlotRrw] = pb.k2_fixed;
  }
  // The basis is evaluated again rather than kept from the first loop: keeping it would add
  // kMaxFitPoints x kP doubles (8 kB) of stack, and the fit runs on small targets.
  double cost = 0.0;
  for (std::size_t i = 0; i < pb.n; ++i) {
    double f[kP];
    basis(pb.tau[i], tb1, tb2, pb.white[i], pb.flicker[i], pb.osc[i], f);
    double m = 0.0;
    for (std::size_t a = 0; a < kP; ++a) {
      m += s.theta[a] * f[a];
    }
    const double r = m - pb.avar[i];
    cost += pb.w[i] * r * r;
  }
  s.cost = cost;
  s.ok = true;
  return s;
}

bool better(const Solution& a, const Solution& b) { return a.ok && (!b.ok || a.cost < b.cost); }

// 1-D search of log(Tb) in [lo, hi]: grid, then golden section around the best grid point.
// eval(tb) returns a Solution.
template <typename Eval>
Solution search_tb(double lo, double hi, Eval eval) {
  const double llo = std::log(lo);
  const double lhi = std::log(hi);
  const double step = (lhi - llo) / static_cast<double>(kGridPoints - 1);
  Solution best;
  std::size_t best_i = 0;
  for (std::size_t i = 0; i < kGridPoints; ++i) {
    const Solution s = eval(std::exp(llo + step * static_cast<double>(i)));
    if (better(s, best)) {
      best = s;
      best_i = i;
    }
  }
  if (!best.ok) {
    return best;
  }
  double a = llo + step * static_cast<double>(best_i > 0 ? best_i - 1 : 0);
  double b = llo + step * static_cast<double>(best_i + 1 < kGridPoints ? best_i + 1 : best_i);
  constexpr double kInvPhi = 0.6180339887498949;
  double c = b - kInvPhi * (b - a);
  double d = a + kInvPhi * (b - a);
  Solution sc = eval(std::exp(c));
  Solution sd = eval(std::exp(d));
  for (int it = 0; it < kGoldenIterations; ++it) {
    if (better(sc, sd)) {
      b = d;
      d = c;
      sd = sc;
      c = b - kInvPhi * (b - a);
      sc = eval(std::exp(c));
    } else {
      a = c;
      c = d;
      sc = sd;
      d = a + kInvPhi * (b - a);
      sd = eval(std::exp(d));
    }
  }
  if (better(sc, best)) {
    best = sc;
  }
  if (better(sd, best)) {
    best = sd;
  }
  return best;
}

Solution search(Problem& pb, double tb_lo, double tb_hi) {
  if (!pb.used[kSlotGm1]) {
    return solve_at(pb, 0.0, 0.0);
  }
  if (!pb.used[kSlotGm2]) {
    return search_tb(tb_lo, tb_hi, [&pb](double tb) { return solve_at(pb, tb, 0.0); });
  }
  // Two GM terms: start from the one-GM optimum, then alternate.
  pb.used[kSlotGm2] = false;
  Solution best = search_tb(tb_lo, tb_hi, [&pb](double tb) { return solve_at(pb, tb, 0.0); });
  pb.used[kSlotGm2] = true;
  if (!best.ok) {
    return best;
  }
  for (int round = 0; round < kCoordinateRounds; ++round) {
    const double tb1 = best.tb1;
    const Solution s2 =
        search_tb(tb_lo, tb_hi, [&pb, tb1](double tb) { return solve_at(pb, tb1, tb); });
    if (better(s2, best)) {
      best = s2;
    }
    const double tb2 = best.tb2;
    const Solution s1 =
        search_tb(tb_lo, tb_hi, [&pb, tb2](double tb) { return solve_at(pb, tb, tb2); });
    if (better(s1, best)) {
      best = s1;
    }
  }
  return best;
}

ModelParams to_params(const Problem& pb, const Solution& s) {
  ModelParams p;
  if (s.theta[kSlotFlicker] > 0.0) {
    p.bi = std::sqrt(s.theta[kSlotFlicker]);
    p.bi_tau_lo_s = pb.flicker_lo_s;
    p.bi_tau_hi_s = pb.flicker_hi_s;
  }
  if (s.theta[kSlotOsc] > 0.0) {
    p.osc_sigma = std::sqrt(s.theta[kSlotOsc]);
    p.osc_f0_hz = pb.osc_f0_hz;
    p.osc_beta_per_s = pb.osc_beta_per_s;
    p.osc_ts_s = pb.osc_ts_s;
  }
  p.n = std::sqrt(s.theta[kSlotWhite]);
  p.n_filter_s = p.n > 0.0 ? pb.white_filter_s : 0.0;
  p.q = std::sqrt(s.theta[kSlotQuant]);
  p.k = std::sqrt(s.theta[kSlotRrw]);
  p.r = std::sqrt(s.theta[kSlotRamp]);
  GmParam gm[2] = {{s.theta[kSlotGm1], s.tb1}, {s.theta[kSlotGm2], s.tb2}};
  if (gm[1].sb > 0.0 && gm[0].sb > 0.0 && gm[1].tb_s < gm[0].tb_s) {
    const GmParam t = gm[0];
    gm[0] = gm[1];
    gm[1] = t;
  }
  for (const auto& g : gm) {
    if (g.sb > 0.0 && g.tb_s > 0.0) {
      p.gm[p.n_gm++] = g;
    }
  }
  return p;
}

// The problem's terms and their fixed shapes from the options (kOk, or kBadOptions); tb_lo
// and tb_hi bound the GMs' correlation times.
FitStatus set_up(const FitOptions& o, Problem& pb, double& tb_lo, double& tb_hi) {
  const bool range_ok = std::isfinite(o.tau_min_s) && std::isfinite(o.tau_max_s) &&
                        o.tau_min_s > 0.0 && o.tau_max_s > o.tau_min_s;
  const std::uint32_t known = kFitWhite | kFitQuantization | kFitGm1 | kFitGm2 | kFitRrw |
                              kFitRamp | kFitFlicker | kFitOscillation;
  if (!range_ok || (o.terms & known) == 0 || (o.terms & ~known) != 0 ||
      ((o.terms & kFitGm2) != 0 && (o.terms & kFitGm1) == 0) || o.weight_iterations < 0 ||
      o.weight_iterations > 10 || !(o.edf_cap >= 0.0)) {
    return FitStatus::kBadOptions;
  }
  tb_lo = o.tb_min_s > 0.0 ? o.tb_min_s : o.tau_min_s;
  tb_hi = o.tb_max_s > 0.0 ? o.tb_max_s : 10.0 * o.tau_max_s;
  if (!(tb_hi > tb_lo)) {
    return FitStatus::kBadOptions;
  }
  pb.used[kSlotWhite] = (o.terms & kFitWhite) != 0;
  pb.used[kSlotQuant] = (o.terms & kFitQuantization) != 0;
  pb.used[kSlotGm1] = (o.terms & kFitGm1) != 0;
  pb.used[kSlotGm2] = (o.terms & kFitGm2) != 0;
  pb.used[kSlotRrw] = (o.terms & kFitRrw) != 0;
  if (!(std::isfinite(o.k_fixed) && o.k_fixed >= 0.0)) {
    return FitStatus::kBadOptions;
  }
  pb.k2_fixed = pb.used[kSlotRrw] ? o.k_fixed * o.k_fixed : 0.0;
  pb.used[kSlotRamp] = (o.terms & kFitRamp) != 0;
  pb.used[kSlotFlicker] = (o.terms & kFitFlicker) != 0;
  pb.used[kSlotOsc] = (o.terms & kFitOscillation) != 0;
  if (!(std::isfinite(o.white_filter_s) && o.white_filter_s >= 0.0)) {
    return FitStatus::kBadOptions;
  }
  pb.white_filter_s = o.white_filter_s;
  pb.osc_f0_hz = o.osc_f0_hz;
  pb.osc_beta_per_s = o.osc_beta_per_s;
  pb.osc_ts_s = o.osc_ts_s > 0.0 && std::isfinite(o.osc_ts_s) ? o.osc_ts_s : 0.0;
  if (pb.used[kSlotOsc] && !(std::isfinite(o.osc_f0_hz) && o.osc_f0_hz >= 0.0 &&
                             std::isfinite(o.osc_beta_per_s) && o.osc_beta_per_s > 0.0)) {
    return FitStatus::kBadOptions;
  }
  pb.flicker_lo_s = o.flicker_tau_lo_s > 0.0 ? o.flicker_tau_lo_s : o.tau_min_s;
  pb.flicker_hi_s = o.flicker_tau_hi_s > 0.0 ? o.flicker_tau_hi_s : o.tau_max_s;
  if (pb.used[kSlotFlicker]) {
    GmParam bank[kMaxFlickerGm];
    if (flicker_bank(1.0, pb.flicker_lo_s, pb.flicker_hi_s, bank) == 0) {
      return FitStatus::kBadOptions;
    }
  }
  return FitStatus::kOk;
}

// The points inside [tau_min_s, tau_max_s] with their weights and the fixed shapes' AVAR
// (kOk, or kTooManyPoints).
FitStatus load_points(const AdevPoint* points, std::size_t n, const FitOptions& o, Problem& pb) {
  const double lo = o.tau_min_s * (1.0 - 1e-9);
  const double hi = o.tau_max_s * (1.0 + 1e-9);
  for (std::size_t i = 0; i < n; ++i) {
    const AdevPoint& p = points[i];
    if (!(p.tau_s >= lo && p.tau_s <= hi && p.avar > 0.0 && p.edf > 0.0) ||
        !std::isfinite(p.avar)) {
      continue;
    }
    if (pb.n >= kMaxFitPoints) {
      return FitStatus::kTooManyPoints;
    }
    pb.tau[pb.n] = p.tau_s;
    pb.avar[pb.n] = p.avar;
    const double edf = o.edf_cap > 0.0 && p.edf > o.edf_cap ? o.edf_cap : p.edf;
    pb.edf[pb.n] = edf;
    pb.w[pb.n] = edf / (2.0 * p.avar * p.avar);
    pb.white[pb.n] = avar_white_filtered(1.0, pb.white_filter_s, p.tau_s);
    pb.flicker[pb.n] = pb.used[kSlotFlicker]
                           ? avar_flicker_bank(1.0, pb.flicker_lo_s, pb.flicker_hi_s, p.tau_s)
                           : 0.0;
    pb.osc[pb.n] = pb.used[kSlotOsc]
                       ? avar_oscillation_sampled(1.0, pb.osc_f0_hz, pb.osc_beta_per_s,
                                                  pb.osc_ts_s, p.tau_s)
                       : 0.0;
    ++pb.n;
  }
  return FitStatus::kOk;
}

}  // namespace

FitResult fit(const AdevPoint* points, std::size_t n, const FitOptions& options) {
  FitResult res;
  Problem pb;
  double tb_lo = 0.0;
  double tb_hi = 0.0;
  res.status = points == nullptr && n > 0 ? FitStatus::kBadOptions
                                          : set_up(options, pb, tb_lo, tb_hi);
  if (res.status == FitStatus::kOk) {
    res.status = load_points(points, n, options, pb);
  }
  if (res.status != FitStatus::kOk) {
    return res;
  }
  std::size_t n_params = 0;
  for (const bool u : pb.used) {
    n_params += u ? 1U : 0U;
  }
  res.n_points = pb.n;
  if (pb.n < n_params || pb.n == 0) {
    res.status = FitStatus::kTooFewPoints;
    return res;
  }
  const FitOptions& o = options;
  Solution best = search(pb, tb_lo, tb_hi);
  for (int it = 0; it < o.weight_iterations && best.ok; ++it) {
    const ModelParams prev = to_params(pb, best);
    for (std::size_t i = 0; i < pb.n; ++i) {
      const double m = model_avar(prev, pb.tau[i]);
      const double v = m > 0.0 ? m : pb.avar[i];
      pb.w[i] = pb.edf[i] / (2.0 * v * v);
    }
    best = search(pb, tb_lo, tb_hi);
  }
  res.evaluations = pb.evaluations;
  if (!best.ok) {
    res.status = FitStatus::kSingular;
    return res;
  }
  res.params = to_params(pb, best);
  res.cost = best.cost;
  for (std::size_t i = 0; i < res.params.n_gm; ++i) {
    const double tb = res.params.gm[i].tb_s;
    res.tb_at_bound = res.tb_at_bound || tb < tb_lo * 1.01 || tb > tb_hi / 1.01;
  }
  double ss = 0.0;
  for (std::size_t i = 0; i < pb.n; ++i) {
    const double r = std::sqrt(model_avar(res.params, pb.tau[i]) / pb.avar[i]) - 1.0;
    ss += r * r;
  }
  res.rms_rel = std::sqrt(ss / static_cast<double>(pb.n));
  res.status = FitStatus::kOk;
  return res;
}

}  // namespace imu

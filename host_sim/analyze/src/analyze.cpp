// The analysis pipeline (see analyze.hpp for the method).
#include "imu/analyze/analyze.hpp"
#include "imu/analyze/long_memory.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <ctime>
#include <cstdio>
#include <map>
#include <memory>

#include "imu/bias_kf.hpp"
#include "imu/covariance_check.hpp"
#include "imu/edf.hpp"
#include "imu/effect_monitor.hpp"
#include "imu/model_fit.hpp"
#include "imu/residual_monitor.hpp"

namespace imu::analyze {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Adev = OnlineAdev<8, 22>;
using Points = std::vector<AdevPoint>;

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// ---------------------------------------------------------------- ADEV helpers

std::vector<std::int32_t> to_counts(const std::vector<double>& y, double lsb, std::size_t& sat) {
  std::vector<std::int32_t> c(y.size());
  sat = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const QuantizeResult q = quantize(y[i], lsb);
    c[i] = q.counts;
    sat += q.saturated ? 1U : 0U;
  }
  return c;
}

// Snapshots of one estimator, one per noise exponent alpha = -2..2 (index alpha + 2).
struct AdevSet {
  std::array<Points, 5> by_alpha;
};

AdevSet adev_of(const std::vector<std::int32_t>& counts, double ts, double lsb) {
  auto est = std::make_unique<Adev>(ts, lsb);
  est->push_block(counts.data(), counts.size());
  AdevSet s;
  for (std::size_t i = 0; i < s.by_alpha.size(); ++i) {
    AdevPoint pts[Adev::kMaxPoints];
    const std::size_t n = est->snapshot(pts, Adev::kMaxPoints, static_cast<int>(i) - 2);
    s.by_alpha[i].assign(pts, pts + n);
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

// tb_max_s > 0 bounds the GM correlation time (0: model_fit's default, 10 tau_max).
FitResult fit_terms(const Points& pts, std::uint32_t terms, double tau_min, double tau_max,
                    double tb_max_s = 0.0) {
  FitOptions fo;
  fo.terms = terms;
  fo.tau_min_s = tau_min;
  fo.tau_max_s = tau_max;
  fo.tb_max_s = tb_max_s;
  return fit(pts.data(), pts.size(), fo);
}

// ---------------------------------------------------------------- filters and checks

struct FilterRun {
  bool ok = false;
  double nis_mean = 0.0;
  double nis_flagged = 0.0;        // fraction of NisMonitor blocks outside the band
  double whiteness_flagged = 0.0;  // fraction of WhitenessMonitor blocks above the bound
  std::size_t states = 0;
  std::vector<double> nu;    // normalised innovation per sample (0 when not updated)
  std::vector<double> pred;  // predicted measurement per sample
};

bool discretize_params(const ModelParams& p, double ts, DiscreteModel<6>& d) {
  ContinuousModel<6> c;
  return build_model(p, c) == ModelStatus::kOk && discretize(c, ts, d) == ModelStatus::kOk;
}

template <std::size_t N>
void run_kf(const DiscreteModel<6>& d, const std::vector<double>& y, double known,
            const std::vector<std::uint8_t>* skip, FilterRun& out) {
  auto kf = std::make_unique<KalmanFilter<double, N>>();
  if (kf->configure(d, known) != KfStatus::kOk) {
    return;
  }
  double nis = 0.0;
  std::size_t updates = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const bool use = skip == nullptr || (*skip)[i] == 0;
    const KfStep<double> st = kf->step(y[i], use);
    if (st.updated) {
      nis += st.nis();
      ++updates;
      out.nu[i] = st.innovation / std::sqrt(st.innovation_var);
      out.pred[i] = y[i] - st.innovation;
    } else {
      out.pred[i] = kf->bias() + known;
    }
  }
  out.nis_mean = updates > 0 ? nis / static_cast<double>(updates) : 0.0;
  out.ok = true;
}

FilterRun run_filter(const ModelParams& p, double ts, const std::vector<double>& y, double known,
                     const std::vector<std::uint8_t>* skip) {
  FilterRun out;
  out.nu.assign(y.size(), 0.0);
  out.pred.assign(y.size(), known);
  DiscreteModel<6> d;
  if (!discretize_params(p, ts, d)) {
    return out;
  }
  out.states = d.n_states;
  switch (d.n_states) {
    case 0: {  // white (and quantization) only: the prediction is the known signal
      const double s = d.r_filter();
      double nis = 0.0;
      std::size_t updates = 0;
      for (std::size_t i = 0; i < y.size(); ++i) {
        if (skip == nullptr || (*skip)[i] == 0) {
          const double e = y[i] - known;
          out.nu[i] = e / std::sqrt(s);
          nis += e * e / s;
          ++updates;
        }
      }
      out.nis_mean = updates > 0 ? nis / static_cast<double>(updates) : 0.0;
      out.ok = s > 0.0;
      break;
    }
    case 1: run_kf<1>(d, y, known, skip, out); break;
    case 2: run_kf<2>(d, y, known, skip, out); break;
    case 3: run_kf<3>(d, y, known, skip, out); break;
    case 4: run_kf<4>(d, y, known, skip, out); break;
    case 5: run_kf<5>(d, y, known, skip, out); break;
    case 6: run_kf<6>(d, y, known, skip, out); break;
    default: break;
  }
  // The fw residual monitors over the normalised innovations of the updates.
  NisMonitor nis;
  WhitenessMonitor<4> white;
  if (nis.configure(1000, 0.99) == MonitorStatus::kOk &&
      white.configure(1000, 0.95) == MonitorStatus::kOk) {
    for (std::size_t i = 0; i < y.size(); ++i) {
      if (skip == nullptr || (*skip)[i] == 0) {
        nis.push(static_cast<float>(out.nu[i]));
        white.push(static_cast<float>(out.nu[i]));
      }
    }
    out.nis_flagged = nis.blocks() > 0 ? static_cast<double>(nis.flagged_blocks()) /
                                             static_cast<double>(nis.blocks())
                                       : 0.0;
    out.whiteness_flagged = white.blocks() > 0 ? static_cast<double>(white.flagged_blocks()) /
                                                     static_cast<double>(white.blocks())
                                               : 0.0;
  }
  return out;
}

// Seed's covariance check (T_avg = 10 s, T_int = 20 s, up to 1000 overlapping windows): robust
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
  DiscreteModel<6> d;
  if (!discretize_params(p, ts, d)) {
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

double robust_scale(const std::vector<double>& v) {
  std::vector<double> c(v);
  return robust_std(c.data(), c.size());
}

// ---------------------------------------------------------------- sinusoid estimation

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) {
    s += x;
  }
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}


void fft(std::vector<std::complex<double>>& a) {
  const std::size_t n = a.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {
    std::size_t bit = n >> 1;
    for (; (j & bit) != 0; bit >>= 1) {
      j ^= bit;
    }
    j ^= bit;
    if (i < j) {
      std::swap(a[i], a[j]);
    }
  }
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const double ang = -2.0 * kPi / static_cast<double>(len);
    const std::complex<double> wl(std::cos(ang), std::sin(ang));
    for (std::size_t i = 0; i < n; i += len) {
      std::complex<double> w(1.0, 0.0);
      for (std::size_t j = 0; j < len / 2; ++j) {
        const std::complex<double> u = a[i + j];
        const std::complex<double> v = a[i + j + len / 2] * w;
        a[i + j] = u + v;
        a[i + j + len / 2] = u - v;
        w *= wl;
      }
    }
  }
}

// |DTFT|^2 of Hann-windowed x at frequency f (cycles per sample).
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

// Frequency near f_c (from the ADEV bump): periodogram of Hann-windowed block means in
// [f_c / 2, 2 f_c], golden-section refinement of the DTFT peak, then the full-rate LS amplitude.
SineFit estimate_sinusoid(const std::vector<double>& y, double ts, double f_c) {
  const double fs = 1.0 / ts;
  const auto dec = static_cast<std::size_t>(std::max(1.0, std::floor(fs / (8.0 * f_c))));
  const std::size_t nd = y.size() / dec;
  SineFit none;
  if (nd < 64) {
    return none;
  }
  std::vector<double> x = block_means(y, dec);
  const double mean = mean_of(x);
  for (std::size_t j = 0; j < nd; ++j) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * kPi * static_cast<double>(j) /
                                          static_cast<double>(nd - 1));
    x[j] = (x[j] - mean) * w;
  }
  std::size_t nfft = 1;
  while (nfft < 2 * nd) {
    nfft <<= 1;
  }
  std::vector<std::complex<double>> a(nfft);
  for (std::size_t j = 0; j < nd; ++j) {
    a[j] = x[j];
  }
  fft(a);
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
    const double p = std::norm(a[k]);
    if (p > pbest) {
      pbest = p;
      kbest = k;
    }
  }
  // Golden section on [kbest - 1, kbest + 1] bins (unimodal near the main-lobe peak).
  double lo = (static_cast<double>(kbest) - 1.0) * df / fsd;
  double hi = (static_cast<double>(kbest) + 1.0) * df / fsd;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = hi - g * (hi - lo);
  double d = lo + g * (hi - lo);
  double pc = dtft_power(x, c);
  double pd = dtft_power(x, d);
  for (int it = 0; it < 22; ++it) {  // 2 bins * 0.618^22 = 5e-5 bin
    if (pc > pd) {
      hi = d;
      d = c;
      pd = pc;
      c = hi - g * (hi - lo);
      pc = dtft_power(x, c);
    } else {
      lo = c;
      c = d;
      pc = pd;
      d = lo + g * (hi - lo);
      pd = dtft_power(x, d);
    }
  }
  const double f_hz = 0.5 * (lo + hi) * fsd;
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

// ---------------------------------------------------------------- error statistics

void fill_errors(const Points& pts, const ModelParams& m, const Options& o, double ts,
                 double tau_max, ErrorStats& e) {
  const Residual all = residual(pts, m, o, ts, tau_max);
  const Residual seed = residual(pts, m, o, ts, o.seed_tau_max_s);
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
  e.seed_rms_rel = seed.check.rms_rel;
  e.seed_max_rel = seed.check.max_rel;
  e.seed_tau_max_s = std::min(o.seed_tau_max_s, e.tau_max_s);
}

}  // namespace

double derive_lsb(const std::vector<double>& y, std::string& note) {
  std::vector<double> s(y);
  std::sort(s.begin(), s.end());
  double dmin = 0.0;
  for (std::size_t i = 1; i < s.size(); ++i) {
    const double d = s[i] - s[i - 1];
    if (d > 0.0 && (dmin <= 0.0 || d < dmin)) {
      dmin = d;
    }
  }
  if (dmin > 0.0) {
    bool multiples = true;
    for (std::size_t i = 0; i < y.size() && multiples; i += 97) {  // a sparse check suffices
      const double c = y[i] / dmin;
      multiples = std::fabs(c - std::round(c)) < 1e-6 && std::fabs(c) < 2e9;
    }
    if (multiples) {
      note = "LSB derived: smallest nonzero difference of the sorted values (" +
             fmt("%.6g", dmin) + "); every checked value is a multiple of it";
      return dmin;
    }
  }
  const double sd = robust_scale(y);
  const double lsb = sd > 0.0 ? sd / 4096.0 : 1e-9;
  note = "LSB chosen: no common step in the data; robust std / 4096 = " + fmt("%.6g", lsb) +
         " (quantization to it is far below the noise)";
  return lsb;
}

bool analyze(const std::vector<double>& y_in, const std::string& channel, const Options& o,
             Report& out, std::string& error) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  out = Report{};
  out.channel = channel;
  out.fs_hz = o.fs_hz;
  out.samples = y_in.size();
  if (!(o.fs_hz > 0.0) || !std::isfinite(o.fs_hz)) {
    error = "analyze: sample rate must be > 0 (got " + fmt("%g", o.fs_hz) + ")";
    return false;
  }
  if (y_in.size() < 1000) {
    error = "analyze: channel '" + channel + "' has " + std::to_string(y_in.size()) +
            " samples; at least 1000 are needed";
    return false;
  }
  for (std::size_t i = 0; i < y_in.size(); ++i) {
    if (!std::isfinite(y_in[i])) {
      error = "analyze: channel '" + channel + "' sample " + std::to_string(i) + " is not finite";
      return false;
    }
  }
  const double ts = 1.0 / o.fs_hz;
  const double n_d = static_cast<double>(y_in.size());
  const double t_rec = n_d * ts;
  const double tau_max = o.tau_max_fraction * t_rec;
  out.lsb = o.lsb;
  if (o.lsb > 0.0) {
    out.lsb_note = "LSB given: " + fmt("%.6g", o.lsb);
  } else {
    out.lsb = derive_lsb(y_in, out.lsb_note);
  }
  const double lsb = out.lsb;
  std::size_t sat = 0;
  std::vector<std::int32_t> counts = to_counts(y_in, lsb, sat);  // of y below, kept current
  if (sat > 0) {
    error = "analyze: " + std::to_string(sat) + " samples do not fit in int32 counts at LSB " +
            fmt("%g", lsb);
    return false;
  }
  const AdevSet raw = adev_of(counts, ts, lsb);

  // ---- before: the seed's first-order model over [Ts, 100 s]
  const double seed_max = std::min(o.seed_tau_max_s, tau_max);
  const FitResult before0 = fit_terms(raw.by_alpha[2], kFitWhite | kFitGm1, ts, seed_max);
  if (before0.status != FitStatus::kOk) {
    error = "analyze: the first-order fit over [Ts, 100 s] failed (status " +
            std::to_string(static_cast<int>(before0.status)) + ")";
    return false;
  }
  const Points raw_pts_b = points_for_model(raw, before0.params);
  const FitResult before = fit_terms(raw_pts_b, kFitWhite | kFitGm1, ts, seed_max);
  out.model_before = before.status == FitStatus::kOk ? before.params : before0.params;
  if (before0.tb_at_bound || before.tb_at_bound) {
    out.notes.emplace_back("before: the GM correlation time is at its search bound (the range "
                           "[Ts, 100 s] does not determine it)");
  }
  out.adev = raw.by_alpha[2];
  const double known_raw = mean_of(y_in);
  const FilterRun fb = run_filter(out.model_before, ts, y_in, known_raw, nullptr);
  fill_errors(raw_pts_b, out.model_before, o, ts, tau_max, out.error_before);
  out.error_before.nis_mean = fb.nis_mean;
  out.error_before.nis_flagged_fraction = fb.nis_flagged;
  out.error_before.whiteness_flagged_fraction = fb.whiteness_flagged;
  out.error_before.filter_states = fb.states;
  out.error_before.cov_ratio = covariance_ratio(out.model_before, ts, y_in);

  // ---- time domain: outliers on the before filter's innovations
  std::vector<double> y = y_in;
  std::vector<std::uint8_t> outlier(y.size(), 0);
  bool outliers_replaced = false;
  {
    const double scale = robust_scale(fb.nu);
    const double thr = two_sided_normal_threshold(o.alpha / n_d);
    OutlierGate gate;
    std::vector<double> times;
    if (scale > 0.0 && gate.configure(thr) == EffectStatus::kOk) {
      for (std::size_t i = 0; i < y.size(); ++i) {
        if (gate.push(fb.nu[i] / scale)) {
          outlier[i] = 1;
          y[i] = fb.pred[i];
          outliers_replaced = true;
          if (times.size() < 100) {
            times.push_back(static_cast<double>(i) * ts);
          }
        }
      }
      if (gate.stats().outliers > 0) {
        Effect e;
        e.times_s = times;
        e.type = "outliers";
        e.count = gate.stats().outliers;
        e.statistic = gate.stats().max_abs;
        e.threshold = thr;
        out.effects.push_back(e);
      }
    }
  }

  // The counts and ADEV of the current y: the raw ones until a sample changes (each is a pass
  // over the record, done only when y changed).
  AdevSet adev_y = raw;
  if (outliers_replaced) {
    counts = to_counts(y, lsb, sat);
    adev_y = adev_of(counts, ts, lsb);
  }

  // ---- time domain: bias steps (two-window detector at several scales)
  std::vector<std::uint64_t> step_at;
  for (int step_no = 0; step_no < o.max_steps; ++step_no) {
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
      break;
    }
    const double thr = two_sided_normal_threshold(o.alpha / n_eff);
    std::vector<StepDetector<16, 4>> det(scales.size());
    bool ok = true;
    for (std::size_t s = 0; s < scales.size(); ++s) {
      ok = ok && det[s].configure(scales[s].block, 8, scales[s].avar_counts2, thr) ==
                     EffectStatus::kOk;
    }
    if (!ok) {
      break;
    }
    for (const std::int32_t v : counts) {
      for (auto& d : det) {
        d.push(v);
      }
    }
    StepEvent best{};
    bool found = false;
    double best_window = 0.0;  // samples on each side of the boundary at the best scale
    for (std::size_t s = 0; s < det.size(); ++s) {
      StepDetector<16, 4>& d = det[s];
      d.finish();
      for (std::size_t i = 0; i < d.n_events(); ++i) {
        if (!found || std::fabs(d.event(i).z) > std::fabs(best.z)) {
          best = d.event(i);
          best_window = 8.0 * scales[s].block;
          found = true;
        }
      }
    }
    if (!found) {
      break;
    }
    // A second "step" within one window of an earlier one is the other edge of a transient (or
    // the residue of the first estimate), not a new step: stop there and say so.
    bool near_previous = false;
    for (const std::uint64_t prev : step_at) {
      const double gap = std::fabs(static_cast<double>(best.sample_index) - static_cast<double>(prev));
      near_previous = near_previous || gap < best_window;
    }
    if (near_previous) {
      out.notes.push_back("step search stopped: a further excursion at t = " +
                          fmt("%.1f", static_cast<double>(best.sample_index) * ts) +
                          " s lies within one window of a step already found (a transient)");
      break;
    }
    step_at.push_back(best.sample_index);
    Effect e;
    e.type = "bias_step";
    e.time_s = static_cast<double>(best.sample_index) * ts;
    e.size = best.size_counts * lsb;
    e.statistic = std::fabs(best.z);
    e.threshold = thr;
    out.effects.push_back(e);
    for (std::size_t i = best.sample_index; i < y.size(); ++i) {
      y[i] -= e.size;
    }
    counts = to_counts(y, lsb, sat);
    adev_y = adev_of(counts, ts, lsb);
  }

  // ---- ADEV residual over [Ts, T/10] of the cleaned record, greedy term selection
  const AdevSet& clean = adev_y;
  const std::uint32_t base_terms = kFitWhite | kFitGm1;
  // Over [Ts, T/10] the GM must show its ADEV peak (1.89 Tb) and one octave of its falling side
  // inside the range: a GM whose peak lies at or beyond the end is, on these taus, the same curve
  // as a rate random walk (AVAR ~ Sb tau / 3), and the one-parameter RRW is the name for it.
  const double tb_max = tau_max / (2.0 * kGmPeakTauFactor);
  const FitResult base0 = fit_terms(clean.by_alpha[2], base_terms, ts, tau_max, tb_max);
  if (base0.status != FitStatus::kOk) {
    error = "analyze: the white + GM fit over [Ts, T/10] failed";
    return false;
  }
  const Points eval = in_range(points_for_model(clean, base0.params), tau_max);
  AdevSet fit_set = clean;  // the points the linear terms are fitted to (sinusoid removed)
  Points fit_pts = eval;
  std::uint32_t terms = base_terms;
  FitResult cur = fit_terms(fit_pts, terms, ts, tau_max, tb_max);
  if (cur.status != FitStatus::kOk) {
    cur = base0;
  }
  ModelParams cur_p = cur.params;
  double cur_cost = residual(eval, cur_p, o, ts, tau_max).cost;
  const double cost_thr = o.cost_factor * chi2_quantile(1.0 - o.alpha, 1.0);
  const double lr_thr = chi2_quantile(1.0 - o.alpha, 1.0);  // record likelihood: no inflation
  bool have_sine = false;
  SineFit sine{};
  std::vector<double> y_fit = y;  // y minus the accepted sinusoid
  // Per bump (by its tau index): the sinusoid estimate and the ADEV of y without it. The same
  // bump comes back round after round; each entry costs passes over the record.
  struct SineCand {
    SineFit fit;
    AdevSet adev;
  };
  std::map<std::size_t, SineCand> sine_cache;

  for (int round = 0; round < 6; ++round) {
    const Residual res = residual(eval, cur_p, o, ts, tau_max);
    // Candidate sinusoids: bumps where the data sit above the model (negative z).
    std::vector<AdevRun> bumps;
    for (std::size_t r = 0; r < res.check.n_runs; ++r) {
      if (res.check.runs[r].sign < 0) {
        bumps.push_back(res.check.runs[r]);
      }
    }
    if (res.check.n_runs == 0) {
      break;  // every residual is within the intervals: say nothing
    }
    struct Cand {
      std::string type;
      std::uint32_t terms;
      ModelParams p;
      double cost;
      const SineCand* sine;  // the sinusoid candidate's estimate and ADEV, else null
    };
    std::vector<Cand> cands;
    const auto try_term = [&](const char* type, std::uint32_t t) {
      if ((terms & t) != 0U) {
        return;
      }
      const FitResult f = fit_terms(fit_pts, terms | t, ts, tau_max, tb_max);
      if (f.status != FitStatus::kOk) {
        return;
      }
      ModelParams p = f.params;
      if (have_sine) {
        p.sin_a = sine.amplitude;
        p.sin_f0_hz = sine.f_hz;
      }
      cands.push_back(Cand{type, terms | t, p, residual(eval, p, o, ts, tau_max).cost, nullptr});
    };
    try_term("quantization", kFitQuantization);
    try_term("rate_random_walk", kFitRrw);
    try_term("ramp", kFitRamp);
    // A second GM is not one of the effects the issue names; real sensors need it (e.g. the
    // ADIS16405's internal filter correlates the noise below 1 s while the bias wanders over
    // minutes). It competes with the named terms under the same test and, when accepted, is
    // reported in the notes and in model_after, not as an effect.
    try_term("second_gm", kFitGm2);
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
        if (f_c >= 0.5 / ts || f_c * t_rec < 20.0) {
          continue;  // not a resolvable sinusoid (above Nyquist or < 20 periods)
        }
        auto it = sine_cache.find(imin);
        if (it == sine_cache.end()) {
          SineCand sc;
          sc.fit = estimate_sinusoid(y, ts, f_c);
          if (sc.fit.ok) {
            sc.adev = adev_of(to_counts(minus_sine(y, ts, sc.fit), lsb, sat), ts, lsb);
          }
          it = sine_cache.emplace(imin, std::move(sc)).first;
        }
        const SineCand& sc = it->second;
        if (!sc.fit.ok) {
          continue;
        }
        const SineFit& s = sc.fit;
        const Points dp = in_range(points_for_model(sc.adev, cur_p), tau_max);
        const FitResult f = fit_terms(dp, terms, ts, tau_max, tb_max);
        if (f.status != FitStatus::kOk) {
          continue;
        }
        ModelParams p = f.params;
        p.sin_a = s.amplitude;
        p.sin_f0_hz = s.f_hz;
        cands.push_back(Cand{"sinusoid", terms, p, residual(eval, p, o, ts, tau_max).cost, &sc});
      }
    }
    const Cand* best = nullptr;
    for (const auto& c : cands) {
      if (best == nullptr || c.cost < best->cost) {
        best = &c;
      }
    }
    // Ramp or rate random walk: one realisation of a random walk can look like a ramp on the
    // ADEV. A deterministic ramp leaves no walk once the least-squares line is removed from the
    // record; a random walk still wanders. So when the ramp wins, the record's likelihood test
    // (long_memory.hpp) runs on the detrended record and the RRW is preferred if it passes.
    if (best != nullptr && best->type == "ramp") {
      const Cand* rrw = nullptr;
      for (const auto& c : cands) {
        rrw = c.type == "rate_random_walk" ? &c : rrw;
      }
      if (rrw != nullptr && cur_cost - rrw->cost > cost_thr) {
        const RrwLikelihoodTest lt = test_rrw(y_fit, ts, cur_p, tb_max, true, step_at);
        if (lt.ok && lt.lr > lr_thr) {
          out.notes.push_back("ramp rejected for rate_random_walk: after removing the line the "
                              "record still holds a walk (2 ln LR = " + fmt("%.1f", lt.lr) +
                              " > " + fmt("%.2f", lr_thr) + ")");
          best = rrw;
        }
      }
    }
    if (best == nullptr || cur_cost - best->cost <= cost_thr) {
      if (best != nullptr) {
        out.notes.push_back("not added: " + best->type + " (cost drop " +
                            fmt("%.1f", cur_cost - best->cost) + " <= " + fmt("%.1f", cost_thr) +
                            ")");
      }
      break;
    }
    if (best->type == "second_gm") {
      out.notes.push_back("a second Gauss-Markov term was needed (cost drop " +
                          fmt("%.1f", cur_cost - best->cost) + " > " + fmt("%.1f", cost_thr) +
                          "); see model_after.gm");
    } else {
      Effect e;
      e.type = best->type;
      e.statistic = cur_cost - best->cost;
      e.threshold = cost_thr;
      out.effects.push_back(e);
    }
    terms = best->terms;
    cur_p = best->p;
    cur_cost = best->cost;
    if (best->sine != nullptr) {
      have_sine = true;
      sine = best->sine->fit;
      y_fit = minus_sine(y, ts, sine);
      fit_set = best->sine->adev;
    }
    fit_pts = in_range(points_for_model(fit_set, cur_p), tau_max);
  }

  // ---- rate random walk by the record's likelihood (when the ADEV up to T/10 did not need it).
  // The ADEV of a GM peaking near T/10 is the same curve as an RRW's there; the record itself is
  // not: a walk keeps wandering, a GM with tb <= tb_max reverts many times (long_memory.hpp).
  // H0 = the current model's GMs (tb <= tb_max), H1 = H0 + K (on the detrended record if a ramp
  // was found).
  if ((terms & kFitRrw) == 0U) {
    const RrwLikelihoodTest lt =
        test_rrw(y_fit, ts, cur_p, tb_max, (terms & kFitRamp) != 0U, step_at);
    if (lt.ok && lt.lr > lr_thr) {
      const FitResult f = fit_terms(fit_pts, terms | kFitRrw, ts, tau_max, tb_max);
      if (f.status == FitStatus::kOk && f.params.k > 0.0) {
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
        cur_p = f.params;
        cur_p.sin_a = sine.amplitude;
        cur_p.sin_f0_hz = sine.f_hz;
        cur_cost = residual(eval, cur_p, o, ts, tau_max).cost;
      }
    } else if (lt.ok) {
      out.notes.push_back("no rate_random_walk in the record's likelihood: 2 ln LR = " +
                          fmt("%.1f", lt.lr) + " <= " + fmt("%.2f", lr_thr));
    }
  }

  // ---- after: joint refit with the accepted terms (EDF from the current model), checks.
  // No ADEV term accepted: the first-order model explains the ADEV, and "after" is "before"
  // (checked on the cleaned record when steps or outliers were removed).
  if (terms == base_terms && !have_sine) {
    cur_p = out.model_before;
  } else {
    // The joint fit (its own IRLS weights on AVAR), kept if it lowers sum(z^2) on the checked
    // taus. The GM stays bounded as in the search (peak and one octave inside [Ts, T/10]), also
    // next to a rate random walk or ramp: an unbounded GM there takes over K's rise (K fell to
    // half its true value, or to 0, on some synthetic seeds). Every effect found stays in the
    // model: the NNLS may zero a term whose evidence (e.g. the likelihood test) it does not see.
    fit_pts = in_range(points_for_model(fit_set, cur_p), tau_max);
    const FitResult f = fit_terms(fit_pts, terms, ts, tau_max, tb_max);
    if (f.status == FitStatus::kOk) {
      ModelParams p = f.params;
      p.sin_a = cur_p.sin_a;
      p.sin_f0_hz = cur_p.sin_f0_hz;
      const bool keeps_terms = ((terms & kFitQuantization) == 0U || p.q > 0.0) &&
                               ((terms & kFitRrw) == 0U || p.k > 0.0) &&
                               ((terms & kFitRamp) == 0U || p.r > 0.0);
      const double c = residual(eval, p, o, ts, tau_max).cost;
      if (keeps_terms && c < cur_cost) {
        cur_p = p;
      }
    }
  }
  out.model_after = cur_p;
  for (auto& e : out.effects) {
    if (e.type == "quantization") {
      e.q = cur_p.q;
    } else if (e.type == "rate_random_walk") {
      e.k = cur_p.k;
    } else if (e.type == "ramp") {
      e.r = cur_p.r;
    } else if (e.type == "sinusoid") {
      e.freq_hz = cur_p.sin_f0_hz;
      e.amplitude = cur_p.sin_a;
    }
  }
  out.adev_clean = clean.by_alpha[2];
  const Points eval_after = points_for_model(clean, cur_p);
  fill_errors(eval_after, cur_p, o, ts, tau_max, out.error_after);
  const double known_clean = mean_of(y);
  const FilterRun fa = run_filter(cur_p, ts, y, known_clean, &outlier);
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
  out.cpu_seconds = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  return true;
}

}  // namespace imu::analyze

// Error model: the first-order conversion from ASD parameters, term AVARs, model building and Van Loan discretisation.
// The templates are defined here and instantiated for kMaxStates = 1, 2, 4, 6, 16 (the sizes the
// project uses); add a line at the bottom for another size.
#include "imu/error_model.hpp"
#include "imu/terms.hpp"

#include <cmath>

namespace imu {
namespace {

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }
bool nonneg_finite(double v) { return std::isfinite(v) && v >= 0.0; }
constexpr double kPi = 3.14159265358979323846;

// One first-order GM state (the term's bookkeeping in params is the caller's).
template <std::size_t kMaxStates>
void put_gm_state(ContinuousModel<kMaxStates>& m, double sb, double tb_s) {
  const std::size_t i = m.n_states;
  m.f(i, i) = -1.0 / tb_s;
  m.qc(i, i) = sb;
  m.p0(i, i) = sb * tb_s / 2.0;
  m.h(0, i) = 1.0;
  ++m.n_states;
}

}  // namespace

ModelStatus first_order_gm_from_asd(double n, double b, double tp_s, double fs_hz,
                                    FirstOrderGm& out) {
  if (!positive_finite(n) || !positive_finite(b) || !positive_finite(tp_s) ||
      !positive_finite(fs_hz)) {
    return ModelStatus::kBadParameter;
  }
  FirstOrderGm m{};
  m.n = n;
  m.b = b;
  m.tp_s = tp_s;
  m.fs_hz = fs_hz;
  m.tb_s = tp_s / kGmPeakTauFactor;
  m.mu_per_s = 1.0 / m.tb_s;
  m.sn = n * n;
  m.sb = b * b / (kGmPeakAdevFactor * kGmPeakAdevFactor * m.tb_s);
  m.pss = m.sb / (2.0 * m.mu_per_s);
  m.ts_s = 1.0 / fs_hz;
  ContinuousModel<1> c;
  if (c.add_gauss_markov(m.sb, m.tb_s) != ModelStatus::kOk) {
    return ModelStatus::kBadParameter;
  }
  DiscreteModel<1> d;
  const ModelStatus st = discretize(c, m.ts_s, d);
  if (st != ModelStatus::kOk) {
    return st;
  }
  m.phi = d.phi(0, 0);
  m.qn = m.sn * fs_hz;
  m.qw = d.qd(0, 0);
  m.pss_d = m.qw / (1.0 - m.phi * m.phi);
  // Finite positive inputs can still give a useless model: Tp = 1e300 gives phi = 1 and
  // Qw = 0 (pss_d = 0/0), Tp = 1e-300 overflows the matrix exponential, N = 1e300 gives an
  // infinite Qn. Every derived quantity a filter uses must be finite, phi in [0, 1), Qw > 0.
  if (!(m.phi >= 0.0 && m.phi < 1.0) || !positive_finite(m.qw) || !positive_finite(m.qn) ||
      !positive_finite(m.pss_d) || !positive_finite(m.sb) || !positive_finite(m.pss)) {
    return ModelStatus::kBadParameter;
  }
  out = m;
  return ModelStatus::kOk;
}

double avar_white(double n, double tau_s) { return n * n / tau_s; }

double avar_quantization(double q, double tau_s) { return 3.0 * q * q / (tau_s * tau_s); }

double avar_white_filtered(double n, double tf_s, double tau_s) {
  if (!(tf_s > 0.0)) {
    return avar_white(n, tau_s);
  }
  return avar_gauss_markov(n * n / (tf_s * tf_s), tf_s, tau_s);
}

double avar_gauss_markov(double sb, double tb_s, double tau_s) {
  const double x = tau_s / tb_s;
  double bracket = 0.0;
  if (x < 1e-3) {
    // 1 - (3 - 4 e^-x + e^-2x) / (2x) = x^2/3 - x^3/4 + 7 x^4/60 - O(x^5): avoids cancellation.
    bracket = x * x * (1.0 / 3.0 - x / 4.0 + 7.0 * x * x / 60.0);
  } else {
    const double num = -4.0 * std::expm1(-x) + std::expm1(-2.0 * x);  // 3 - 4e^-x + e^-2x
    bracket = 1.0 - num / (2.0 * x);
  }
  return sb * tb_s * tb_s / tau_s * bracket;
}

double avar_rrw(double k, double tau_s) { return k * k * tau_s / 3.0; }

double avar_ramp(double r, double tau_s) { return r * r * tau_s * tau_s / 2.0; }

double avar_sinusoid(double a, double f0_hz, double tau_s) {
  const double x = kPi * f0_hz * tau_s;
  if (x < 1e-8) {
    return a * a * x * x;  // sin^4(x)/x^2 -> x^2
  }
  const double s = std::sin(x);
  return a * a * s * s * s * s / (x * x);
}

namespace {

// The number of samples m with tau = m Ts when tau lies on the sample grid (to 1e-6 m), else
// 0: the sampled AVAR forms hold only there.
double samples_per_tau(double ts_s, double tau_s) {
  const double m_real = ts_s > 0.0 ? tau_s / ts_s : 0.0;
  const double m_round = std::round(m_real);
  return m_round >= 1.0 && std::fabs(m_real - m_round) <= 1e-6 * m_round ? m_round : 0.0;
}

}  // namespace

double avar_sinusoid_sampled(double a, double f0_hz, double ts_s, double tau_s) {
  const double x = kPi * f0_hz * ts_s;
  const double s = std::sin(x);
  if (!(samples_per_tau(ts_s, tau_s) >= 1.0) || !(x > 1e-8) || !(s > 0.0)) {
    return avar_sinusoid(a, f0_hz, tau_s);  // off the sample grid, or no sampling period
  }
  return avar_sinusoid(a, f0_hz, tau_s) * (x / s) * (x / s);
}

namespace {

// Complex arithmetic on two doubles (<complex> would pull stream headers into fw).
struct Cx {
  double re;
  double im;
};
Cx cmul(Cx a, Cx b) { return Cx{a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }
Cx cdiv(Cx a, Cx b) {
  const double d = b.re * b.re + b.im * b.im;
  return Cx{(a.re * b.re + a.im * b.im) / d, (a.im * b.re - a.re * b.im) / d};
}
Cx cexp_neg(Cx x) {  // e^-x
  const double m = std::exp(-x.re);
  return Cx{m * std::cos(x.im), -m * std::sin(x.im)};
}

}  // namespace

double avar_oscillation(double sigma, double f0_hz, double beta_per_s, double tau_s) {
  const Cx x{beta_per_s * tau_s, -2.0 * kPi * f0_hz * tau_s};
  const double ax = std::sqrt(x.re * x.re + x.im * x.im);
  Cx g_over_x{};
  if (ax < 0.5) {
    // g(x)/x = -sum_{n>=3} (-1)^n (2^n - 4) x^(n-2) / (2 n!) (x/3 - x^2/4 + 7 x^3/60 - ...):
    // the closed form loses eps/|x|^2 to cancellation below |x| ~ 0.5; 20 terms reach 1e-17.
    Cx xp = x;            // x^(n-2)
    double pow2 = 8.0;    // 2^n
    double fact = 6.0;    // n!
    double sign = 1.0;    // -(-1)^n
    for (int n = 3; n <= 22; ++n) {
      const double c = sign * (pow2 - 4.0) / (2.0 * fact);
      g_over_x.re += c * xp.re;
      g_over_x.im += c * xp.im;
      xp = cmul(xp, x);
      pow2 *= 2.0;
      fact *= static_cast<double>(n + 1);
      sign = -sign;
    }
  } else {
    const Cx e1 = cexp_neg(x);
    const Cx e2 = cmul(e1, e1);
    const Cx num{3.0 - 4.0 * e1.re + e2.re, -4.0 * e1.im + e2.im};
    const Cx x2 = cmul(x, x);
    const Cx t = cdiv(num, Cx{2.0 * x2.re, 2.0 * x2.im});
    const Cx inv = cdiv(Cx{1.0, 0.0}, x);
    g_over_x = Cx{inv.re - t.re, inv.im - t.im};
  }
  const double v = 2.0 * sigma * sigma * g_over_x.re;
  return v > 0.0 ? v : 0.0;
}

double avar_oscillation_sampled(double sigma, double f0_hz, double beta_per_s, double ts_s,
                                double tau_s) {
  const double m_round = samples_per_tau(ts_s, tau_s);
  if (!(m_round >= 1.0) || !(beta_per_s > 0.0)) {
    return avar_oscillation(sigma, f0_hz, beta_per_s, tau_s);
  }
  // R(d) = sigma^2 Re z^d, z = e^(-beta Ts) e^(i 2 pi f0 Ts). V(n) = var(sum of n samples) =
  // sigma^2 (n + 2 Re sum_{d=1}^{n-1} (n - d) z^d), the sum = (n - (n + 1) z + z^(n+1)) /
  // (1 - z)^2 - n. Adjacent sums S1, S2 of m samples: E (S2 - S1)^2 = 4 V(m) - V(2m).
  const double rho = std::exp(-beta_per_s * ts_s);
  const double th = 2.0 * kPi * f0_hz * ts_s;
  const Cx z{rho * std::cos(th), rho * std::sin(th)};
  const Cx one_minus_z{1.0 - z.re, -z.im};
  const Cx den = cmul(one_minus_z, one_minus_z);
  const auto v_of = [&](double n) {
    const Cx zn1 = cexp_neg(Cx{beta_per_s * ts_s * (n + 1.0), -th * (n + 1.0)});  // z^(n+1)
    const Cx num{n - (n + 1.0) * z.re + zn1.re, -(n + 1.0) * z.im + zn1.im};
    const double g = cdiv(num, den).re - n;
    return n + 2.0 * g;
  };
  const double v = (4.0 * v_of(m_round) - v_of(2.0 * m_round)) / (2.0 * m_round * m_round);
  return v > 0.0 ? sigma * sigma * v : 0.0;
}

std::size_t flicker_bank(double b, double tau_lo_s, double tau_hi_s,
                         GmParam (&out)[kMaxFlickerGm]) {
  if (!positive_finite(b) || !positive_finite(tau_lo_s) || !std::isfinite(tau_hi_s) ||
      !(tau_hi_s > tau_lo_s)) {
    return 0;
  }
  const double scale = 2.0 * std::log(kFlickerTbRatio) * b * b / kPi;
  double tb = tau_lo_s / kFlickerFirstTbDivisor;
  std::size_t n = 0;
  while (n < kMaxFlickerGm) {
    out[n++] = GmParam{scale / tb, tb};
    if (tb >= tau_hi_s) {
      return n;
    }
    tb *= kFlickerTbRatio;
  }
  return 0;  // the range needs more than kMaxFlickerGm members
}

double avar_flicker_ideal(double b) { return 2.0 * std::log(2.0) / kPi * b * b; }

double avar_flicker_bank(double b, double tau_lo_s, double tau_hi_s, double tau_s) {
  GmParam bank[kMaxFlickerGm];
  const std::size_t n = flicker_bank(b, tau_lo_s, tau_hi_s, bank);
  double v = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    v += avar_gauss_markov(bank[i].sb, bank[i].tb_s, tau_s);
  }
  return v;
}

double model_avar(const ModelParams& p, double tau_s) {
  double v = 0.0;
  for (const TermInfo& t : kTermTable) {
    for (std::size_t i = 0; i < t.max_instances; ++i) {
      v += term_avar(p, t.kind, i, tau_s);
    }
  }
  return v;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_white(double n) {
  if (!nonneg_finite(n)) {
    return ModelStatus::kBadParameter;
  }
  sn += n * n;
  params.n = std::sqrt(sn);
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_filtered_white(double n, double tf_s) {
  if (!positive_finite(n) || !positive_finite(tf_s) || params.n > 0.0) {
    return ModelStatus::kBadParameter;  // one white term per model
  }
  if (n_states + 1 > kMaxStates) {
    return ModelStatus::kCapacity;
  }
  put_gm_state(*this, n * n / (tf_s * tf_s), tf_s);
  params.n = n;
  params.n_filter_s = tf_s;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_quantization(double q_units_s) {
  if (!nonneg_finite(q_units_s)) {
    return ModelStatus::kBadParameter;
  }
  q = std::sqrt(q * q + q_units_s * q_units_s);
  params.q = q;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_gauss_markov(double sb, double tb_s) {
  if (!positive_finite(sb) || !positive_finite(tb_s)) {
    return ModelStatus::kBadParameter;
  }
  if (n_states + 1 > kMaxStates || params.n_gm >= kMaxGmTerms) {
    return ModelStatus::kCapacity;
  }
  put_gm_state(*this, sb, tb_s);
  params.gm[params.n_gm] = GmParam{sb, tb_s};
  ++params.n_gm;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_flicker(double b, double tau_lo_s,
                                                     double tau_hi_s) {
  GmParam bank[kMaxFlickerGm];
  const std::size_t n = flicker_bank(b, tau_lo_s, tau_hi_s, bank);
  if (n == 0) {
    return ModelStatus::kBadParameter;
  }
  if (n_states + n > kMaxStates || params.bi > 0.0) {
    return ModelStatus::kCapacity;
  }
  for (std::size_t i = 0; i < n; ++i) {
    put_gm_state(*this, bank[i].sb, bank[i].tb_s);
  }
  params.bi = b;
  params.bi_tau_lo_s = tau_lo_s;
  params.bi_tau_hi_s = tau_hi_s;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_rrw(double k, double prior_var) {
  if (!positive_finite(k) || !nonneg_finite(prior_var)) {
    return ModelStatus::kBadParameter;
  }
  if (n_states + 1 > kMaxStates || params.k > 0.0) {
    return ModelStatus::kCapacity;
  }
  const std::size_t i = n_states;
  qc(i, i) = k * k;
  p0(i, i) = prior_var;
  h(0, i) = 1.0;
  params.k = k;
  ++n_states;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_ramp(double r, double slope_drive) {
  if constexpr (kMaxStates < 2) {  // a 2-state term never fits (also silences -Warray-bounds)
    return ModelStatus::kCapacity;
  }
  const double r_abs = std::fabs(r);
  if (!positive_finite(r_abs) || !nonneg_finite(slope_drive)) {
    return ModelStatus::kBadParameter;
  }
  if (n_states + 2 > kMaxStates || params.r > 0.0 || params.r < 0.0) {
    return ModelStatus::kCapacity;
  }
  const std::size_t i = n_states;
  f(i, i + 1) = 1.0;  // d' = s
  qc(i + 1, i + 1) = slope_drive;
  p0(i + 1, i + 1) = r_abs * r_abs;
  h(0, i) = 1.0;
  params.r = r;
  n_states += 2;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_sinusoid(double a, double f0_hz,
                                                       double beta_per_s) {
  if constexpr (kMaxStates < 2) {  // a 2-state term never fits (also silences -Warray-bounds)
    return ModelStatus::kCapacity;
  }
  if (!positive_finite(a) || !positive_finite(f0_hz) || !nonneg_finite(beta_per_s)) {
    return ModelStatus::kBadParameter;
  }
  if (n_states + 2 > kMaxStates || params.sin2_a > 0.0) {
    return ModelStatus::kCapacity;
  }
  const std::size_t i = n_states;
  const double w = 2.0 * kPi * f0_hz;
  const double var = a * a / 2.0;
  f(i, i + 1) = w;
  f(i + 1, i) = -w;
  f(i, i) = -beta_per_s;
  f(i + 1, i + 1) = -beta_per_s;
  qc(i, i) = 2.0 * beta_per_s * var;  // stationary variance var per state (add_oscillation)
  qc(i + 1, i + 1) = 2.0 * beta_per_s * var;
  p0(i, i) = var;
  p0(i + 1, i + 1) = var;
  h(0, i) = 1.0;
  if (params.sin_a > 0.0) {
    params.sin2_a = a;
    params.sin2_f0_hz = f0_hz;
  } else {
    params.sin_a = a;
    params.sin_f0_hz = f0_hz;
  }
  n_states += 2;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus ContinuousModel<kMaxStates>::add_oscillation(double sigma, double f0_hz,
                                                         double beta_per_s) {
  if constexpr (kMaxStates < 2) {  // a 2-state term never fits (also silences -Warray-bounds)
    return ModelStatus::kCapacity;
  }
  if (!positive_finite(sigma) || !positive_finite(beta_per_s) || !std::isfinite(f0_hz) ||
      f0_hz < 0.0) {
    return ModelStatus::kBadParameter;
  }
  if (n_states + 2 > kMaxStates || params.osc_sigma > 0.0) {
    return ModelStatus::kCapacity;
  }
  const std::size_t i = n_states;
  const double w = 2.0 * kPi * f0_hz;
  f(i, i) = -beta_per_s;
  f(i + 1, i + 1) = -beta_per_s;
  f(i, i + 1) = -w;
  f(i + 1, i) = w;
  qc(i, i) = 2.0 * beta_per_s * sigma * sigma;
  qc(i + 1, i + 1) = 2.0 * beta_per_s * sigma * sigma;
  p0(i, i) = sigma * sigma;
  p0(i + 1, i + 1) = sigma * sigma;
  h(0, i) = 1.0;
  params.osc_sigma = sigma;
  params.osc_f0_hz = f0_hz;
  params.osc_beta_per_s = beta_per_s;
  n_states += 2;
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus build_model(const ModelParams& p, ContinuousModel<kMaxStates>& out) {
  ContinuousModel<kMaxStates> m;
  ModelStatus st = ModelStatus::kOk;
  if (p.n > 0.0) {
    st = p.n_filter_s > 0.0 ? m.add_filtered_white(p.n, p.n_filter_s) : m.add_white(p.n);
  }
  if (st == ModelStatus::kOk && p.q > 0.0) {
    st = m.add_quantization(p.q);
  }
  for (std::size_t i = 0; st == ModelStatus::kOk && i < p.n_gm; ++i) {
    if (i >= kMaxGmTerms) {
      st = ModelStatus::kCapacity;
    } else if (p.gm[i].sb > 0.0) {
      st = m.add_gauss_markov(p.gm[i].sb, p.gm[i].tb_s);
    }
  }
  if (st == ModelStatus::kOk && p.bi > 0.0) {
    st = m.add_flicker(p.bi, p.bi_tau_lo_s, p.bi_tau_hi_s);
  }
  if (st == ModelStatus::kOk && p.k > 0.0) {
    st = m.add_rrw(p.k);
  }
  // The deterministic terms as the filter realises them (ModelParams::signal_memory_s).
  const bool memory = p.signal_memory_s > 0.0;
  if (memory && !positive_finite(p.signal_memory_s)) {
    st = ModelStatus::kBadParameter;
  }
  const double beta = memory ? 1.0 / p.signal_memory_s : 0.0;
  if (st == ModelStatus::kOk && (p.r > 0.0 || p.r < 0.0)) {
    st = m.add_ramp(p.r, p.r * p.r * beta);
  }
  if (st == ModelStatus::kOk && p.sin_a > 0.0) {
    st = m.add_sinusoid(p.sin_a, p.sin_f0_hz, beta);
  }
  if (st == ModelStatus::kOk && p.sin2_a > 0.0) {
    st = m.add_sinusoid(p.sin2_a, p.sin2_f0_hz, beta);
  }
  m.params.signal_memory_s = p.signal_memory_s;
  if (st == ModelStatus::kOk && p.osc_sigma > 0.0) {
    st = m.add_oscillation(p.osc_sigma, p.osc_f0_hz, p.osc_beta_per_s);
  }
  if (st == ModelStatus::kOk) {
    out = m;
  }
  return st;
}

namespace {

// Van Loan on the leading n states of (f, qc): expm([[-F, Qc], [0, F^T]] Ts) =
// [[., M12], [0, M22]], Phi = M22^T, Qd = Phi M12. False if expm fails.
template <std::size_t kS>
bool van_loan(const Mat<double, kS, kS>& f, const Mat<double, kS, kS>& qc, std::size_t n,
              double ts_s, Mat<double, kS, kS>& phi, Mat<double, kS, kS>& qd) {
  Mat<double, 2 * kS, 2 * kS> a{};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      a(i, j) = -f(i, j) * ts_s;
      a(i, n + j) = qc(i, j) * ts_s;
      a(n + i, n + j) = f(j, i) * ts_s;
    }
  }
  Mat<double, 2 * kS, 2 * kS> e{};
  if (!expm(a, e, 2 * n)) {
    return false;
  }
  Mat<double, kS, kS> m12{};
  phi = Mat<double, kS, kS>{};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      phi(i, j) = e(n + j, n + i);  // M22^T
      m12(i, j) = e(i, n + j);
    }
  }
  qd = phi * m12;
  symmetrize(qd);
  return true;
}

// Terms are independent: F and Qc are block diagonal up to a permutation. A block is a set of
// states coupled through F or Qc (a term: 1 state, or 2 for a ramp, a sinusoid, an oscillation).
// Van Loan on each block alone is exact and needs matrices of 2 (kBlockStates + 1) rows (the
// block and the sample mean) instead of 2 (n + 1): on the Cortex-M4 that is the difference
// between a 23 kB stack frame and a 2 kB one.
constexpr std::size_t kBlockStates = 2;
using BlockMat = Mat<double, kBlockStates + 1, kBlockStates + 1>;

struct Blocks {
  std::size_t label[kModelMaxStates + 1] = {};  // label[i]: smallest state index of i's block
  std::size_t largest = 0;                      // states in the largest block
};

template <std::size_t kMaxStates>
Blocks find_blocks(const ContinuousModel<kMaxStates>& c) {
  Blocks b;
  const std::size_t n = c.n_states;
  for (std::size_t i = 0; i < n; ++i) {
    b.label[i] = i;
  }
  for (bool changed = true; changed;) {  // propagate the smallest label along couplings
    changed = false;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        const bool coupled = std::fabs(c.f(i, j)) + std::fabs(c.f(j, i)) + std::fabs(c.qc(i, j)) +
                                 std::fabs(c.qc(j, i)) > 0.0;
        if (coupled && b.label[j] < b.label[i]) {
          b.label[i] = b.label[j];
          changed = true;
        }
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t size = 0;
    for (std::size_t j = 0; j < n; ++j) {
      size += b.label[j] == b.label[i] ? 1U : 0U;
    }
    b.largest = size > b.largest ? size : b.largest;
  }
  return b;
}

// Phi and Qd of block `root` (states idx[0..m)), with the sample mean J appended when
// `averaged` (J' = H x / Ts), scattered into d: J's row and column go to index j_index (its
// Qd(J, J) is the sum over blocks; J does not feed the states).
template <std::size_t kMaxStates>
bool discretize_block(const ContinuousModel<kMaxStates>& c, const Blocks& b, std::size_t root,
                      bool averaged, std::size_t j_index, DiscreteModel<kMaxStates>& d) {
  std::size_t idx[kBlockStates] = {};
  std::size_t m = 0;
  for (std::size_t i = 0; i < c.n_states; ++i) {
    if (b.label[i] == root) {
      idx[m++] = i;
    }
  }
  BlockMat f{};
  BlockMat qc{};
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      f(i, j) = c.f(idx[i], idx[j]);
      qc(i, j) = c.qc(idx[i], idx[j]);
    }
    if (averaged) {
      f(m, i) = c.h(0, idx[i]) / d.ts_s;
    }
  }
  const std::size_t mb = averaged ? m + 1 : m;
  BlockMat phi{};
  BlockMat qd{};
  if (!van_loan(f, qc, mb, d.ts_s, phi, qd)) {
    return false;
  }
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      d.phi(idx[i], idx[j]) = phi(i, j);
      d.qd(idx[i], idx[j]) = qd(i, j);
    }
    if (averaged) {
      d.phi(j_index, idx[i]) = phi(m, i);
      d.qd(idx[i], j_index) = d.qd(j_index, idx[i]) = qd(i, m);
    }
  }
  if (averaged) {
    d.qd(j_index, j_index) += qd(m, m);
  }
  return true;
}

// Van Loan on the whole model at once (a block larger than kBlockStates). Not inlined: its
// 2 (n + 1)-row matrices would otherwise be in the caller's stack frame on every call.
template <std::size_t kMaxStates>
[[gnu::noinline]] bool discretize_whole(const ContinuousModel<kMaxStates>& c, bool averaged,
                                        DiscreteModel<kMaxStates>& d) {
  const std::size_t n = c.n_states;
  typename DiscreteModel<kMaxStates>::Square f = c.f;
  for (std::size_t j = 0; averaged && j < n; ++j) {
    f(n, j) = c.h(0, j) / d.ts_s;
  }
  return van_loan(f, c.qc, averaged ? n + 1 : n, d.ts_s, d.phi, d.qd);
}

// Phi and Qd of c (and of its sample mean at index n when averaged) into d, block by block,
// or on the whole model when a block is larger than kBlockStates (no term built here is).
template <std::size_t kMaxStates>
bool discretize_dynamics(const ContinuousModel<kMaxStates>& c, bool averaged,
                         DiscreteModel<kMaxStates>& d) {
  const std::size_t n = c.n_states;
  if (n == 0 || n > kMaxStates || (averaged && n >= kMaxStates)) {
    return false;
  }
  const Blocks b = find_blocks(c);
  if (b.largest <= kBlockStates) {
    for (std::size_t i = 0; i < n; ++i) {
      if (b.label[i] == i && !discretize_block(c, b, i, averaged, n, d)) {
        return false;
      }
    }
    return true;
  }
  return discretize_whole(c, averaged, d);
}

// The fields both discretisations take from c as they are, everything else zero.
template <std::size_t kMaxStates>
void start_discrete(const ContinuousModel<kMaxStates>& c, double ts_s, std::size_t n_states,
                    DiscreteModel<kMaxStates>& out) {
  out = DiscreteModel<kMaxStates>{};
  out.n_states = n_states;
  out.ts_s = ts_s;
  out.r_white = c.sn / ts_s;
  out.q = c.q;
  out.params = c.params;
}

}  // namespace

template <std::size_t kMaxStates>
ModelStatus discretize(const ContinuousModel<kMaxStates>& c, double ts_s,
                       DiscreteModel<kMaxStates>& out) {
  if (!positive_finite(ts_s)) {
    return ModelStatus::kBadParameter;
  }
  start_discrete(c, ts_s, c.n_states, out);
  out.p0 = c.p0;
  out.h = c.h;
  if (c.n_states > 0 && !discretize_dynamics(c, false, out)) {
    out.n_states = 0;
    return ModelStatus::kNumerical;
  }
  return ModelStatus::kOk;
}

template <std::size_t kMaxStates>
ModelStatus discretize_averaged(const ContinuousModel<kMaxStates>& c, double ts_s,
                                DiscreteModel<kMaxStates>& out) {
  const std::size_t n = c.n_states;
  if (!positive_finite(ts_s) || n == 0) {
    return ModelStatus::kBadParameter;
  }
  if (n >= kMaxStates) {  // no room for the sample mean
    return ModelStatus::kCapacity;
  }
  start_discrete(c, ts_s, n + 1, out);
  out.h(0, n) = 1.0;
  if (!discretize_dynamics(c, true, out)) {
    out.n_states = 0;
    return ModelStatus::kNumerical;
  }
  out.phi(n, n) = 0.0;  // reset: the next sample's mean starts from zero
  if (!(out.r_white + out.q > 0.0)) {
    out.r_white = 1e-4 * out.qd(n, n);
  }
  // P0 = Phi diag(P0, 0) Phi^T + Qd: the state and the first sample's mean after one step.
  for (std::size_t i = 0; i <= n; ++i) {
    for (std::size_t j = 0; j <= i; ++j) {
      double s = out.qd(i, j);
      for (std::size_t k = 0; k < n; ++k) {
        for (std::size_t l = 0; l < n; ++l) {
          s += out.phi(i, k) * c.p0(k, l) * out.phi(j, l);
        }
      }
      out.p0(i, j) = out.p0(j, i) = s;
    }
  }
  return ModelStatus::kOk;
}

#define IMU_INSTANTIATE_MODEL(N)                                                              \
  template struct ContinuousModel<N>;                                                         \
  template struct DiscreteModel<N>;                                                           \
  template ModelStatus build_model<N>(const ModelParams&, ContinuousModel<N>&);               \
  template ModelStatus discretize<N>(const ContinuousModel<N>&, double, DiscreteModel<N>&); \
  template ModelStatus discretize_averaged<N>(const ContinuousModel<N>&, double,             \
                                              DiscreteModel<N>&);

// NOLINTBEGIN(cppcoreguidelines-macro-usage)
IMU_INSTANTIATE_MODEL(1)
IMU_INSTANTIATE_MODEL(2)
IMU_INSTANTIATE_MODEL(4)
IMU_INSTANTIATE_MODEL(6)
IMU_INSTANTIATE_MODEL(8)
IMU_INSTANTIATE_MODEL(9)
IMU_INSTANTIATE_MODEL(16)
// NOLINTEND(cppcoreguidelines-macro-usage)
#undef IMU_INSTANTIATE_MODEL

}  // namespace imu

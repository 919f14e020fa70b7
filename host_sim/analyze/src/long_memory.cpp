// Block-mean likelihood of white + GMs + random walk, and the RRW test (see long_memory.hpp).
#include "imu/analyze/long_memory.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

namespace imu::analyze {
namespace {

// The flicker bank of the likelihood: as error_model.hpp's flicker_bank, with members at
// half-decade spacing (the decade bank's PSD ripple is visible to 2048 block means, and a walk
// then takes up the slow part of the flicker).
constexpr double kBankRatio = 3.1622776601683795;
constexpr std::size_t kMaxBankGm = 2 * kMaxFlickerGm;
constexpr std::size_t kMaxStates = kMaxGmTerms + kMaxBankGm + 1;

std::size_t likelihood_bank(double b, double tau_lo_s, double tau_hi_s,
                            GmParam (&out)[kMaxBankGm]) {
  if (!(b > 0.0) || !(tau_lo_s > 0.0) || !(tau_hi_s > tau_lo_s) || !std::isfinite(tau_hi_s)) {
    return 0;
  }
  const double scale = 2.0 * std::log(kBankRatio) * b * b / 3.14159265358979323846;
  double tb = tau_lo_s / kFlickerFirstTbDivisor;
  std::size_t n = 0;
  while (n < kMaxBankGm) {
    out[n++] = GmParam{scale / tb, tb};
    if (tb >= tau_hi_s) {
      return n;
    }
    tb *= kBankRatio;
  }
  return 0;
}

// One independent state of the block model: x' = f x + w, block integral / h = hm x + u,
// Var(w) = q, Var(u) = ru, Cov(w, u) = s.
struct Component {
  double f = 0.0;
  double q = 0.0;
  double hm = 0.0;
  double ru = 0.0;
  double s = 0.0;
  double p0 = 0.0;  // initial variance
};

// First-order GM of drive PSD sb and time tb over a block of length h (closed forms; x = h/tb):
// Var(w) = sigma^2 (1 - e^2), hm = (1 - e) tb / h, Var(u) = sb tb^3 (x - 2 (1 - e) + (1 - e^2) / 2)
// / h^2, Cov = sb tb^2 (1 - e)^2 / (2 h), sigma^2 = sb tb / 2, e = exp(-x).
Component gm_component(double sb, double tb, double h) {
  const double x = h / tb;
  const double om = -std::expm1(-x);       // 1 - e
  const double om2 = -std::expm1(-2.0 * x);  // 1 - e^2
  const double var = 0.5 * sb * tb;
  Component c;
  c.f = 1.0 - om;
  c.q = var * om2;
  c.hm = om * tb / h;
  c.ru = sb * tb * tb * tb * (x - 2.0 * om + 0.5 * om2) / (h * h);
  c.s = sb * tb * tb * om * om / (2.0 * h);
  c.p0 = var;
  return c;
}

// Random walk of intensity k^2: Var(w) = k^2 h, hm = 1, Var(u) = k^2 h / 3, Cov = k^2 h / 2.
Component walk_component(double k, double h, double p0) {
  const double k2 = k * k;
  Component c;
  c.f = 1.0;
  c.q = k2 * h;
  c.hm = 1.0;
  c.ru = k2 * h / 3.0;
  c.s = k2 * h / 2.0;
  c.p0 = p0;
  return c;
}

}  // namespace

double sample_variance(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) {
    m += x;
  }
  m /= static_cast<double>(v.size());
  double s = 0.0;
  for (double x : v) {
    s += (x - m) * (x - m);
  }
  return v.size() > 1 ? s / static_cast<double>(v.size() - 1) : 0.0;
}

// Nelder-Mead: long_memory.hpp.
std::vector<double> nelder_mead(const std::function<double(const std::vector<double>&)>& f,
                                std::vector<double> x0, double step, int max_iterations) {
  const std::size_t n = x0.size();
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::vector<double>> xs(n + 1, x0);
    std::vector<double> fs(n + 1);
    for (std::size_t i = 0; i < n; ++i) {
      xs[i + 1][i] += step;
    }
    for (std::size_t i = 0; i <= n; ++i) {
      fs[i] = f(xs[i]);
    }
    std::vector<std::size_t> idx(n + 1);
    for (int it = 0; it < max_iterations; ++it) {
      for (std::size_t i = 0; i <= n; ++i) {
        idx[i] = i;
      }
      std::sort(idx.begin(), idx.end(),
                [&](std::size_t a, std::size_t b) { return fs[a] < fs[b]; });
      const std::size_t best = idx[0];
      const std::size_t worst = idx[n];
      const std::size_t second = idx[n - 1];
      double size = 0.0;
      for (std::size_t i = 0; i <= n; ++i) {
        for (std::size_t j = 0; j < n; ++j) {
          size = std::max(size, std::fabs(xs[i][j] - xs[best][j]));
        }
      }
      // Converged: log-likelihoods within 1e-4 (the tests compare 2 ln LR against thresholds
      // of a few units) and log parameters within 1e-3 (0.1 %, far inside their intervals).
      if (fs[worst] - fs[best] < 1e-4 && size < 1e-3) {
        break;
      }
      std::vector<double> c(n, 0.0);
      for (std::size_t i = 0; i <= n; ++i) {
        if (i != worst) {
          for (std::size_t j = 0; j < n; ++j) {
            c[j] += xs[i][j] / static_cast<double>(n);
          }
        }
      }
      const auto along = [&](double t) {
        std::vector<double> p(n);
        for (std::size_t j = 0; j < n; ++j) {
          p[j] = c[j] + t * (xs[worst][j] - c[j]);
        }
        return p;
      };
      const std::vector<double> xr = along(-1.0);
      const double fr = f(xr);
      if (fr < fs[best]) {
        const std::vector<double> xe = along(-2.0);
        const double fe = f(xe);
        if (fe < fr) {
          xs[worst] = xe;
          fs[worst] = fe;
        } else {
          xs[worst] = xr;
          fs[worst] = fr;
        }
      } else if (fr < fs[second]) {
        xs[worst] = xr;
        fs[worst] = fr;
      } else {
        const bool outside = fr < fs[worst];
        const std::vector<double> xc = along(outside ? -0.5 : 0.5);
        const double fc = f(xc);
        if (fc < (outside ? fr : fs[worst])) {
          xs[worst] = xc;
          fs[worst] = fc;
        } else {  // shrink towards the best
          for (std::size_t i = 0; i <= n; ++i) {
            if (i != best) {
              for (std::size_t j = 0; j < n; ++j) {
                xs[i][j] = xs[best][j] + 0.5 * (xs[i][j] - xs[best][j]);
              }
              fs[i] = f(xs[i]);
            }
          }
        }
      }
    }
    std::size_t b = 0;
    for (std::size_t i = 1; i <= n; ++i) {
      b = fs[i] < fs[b] ? i : b;
    }
    x0 = xs[b];
    step *= 0.25;  // the restart explores a smaller simplex around the optimum
  }
  return x0;
}

namespace {

// Log-parameter vector <-> model. tb is mapped into [tb_min, tb_max] by a logistic.
struct Packing {
  std::size_t n_gm = 0;
  bool fit_k = false;
  bool fit_bi = false;
  double k_fixed = 0.0;
  double bi_lo_s = 0.0;
  double bi_hi_s = 0.0;
  double ln_tb_min = 0.0;
  double ln_tb_span = 0.0;

  [[nodiscard]] std::size_t size() const {
    return 1 + 2 * n_gm + (fit_k ? 1 : 0) + (fit_bi ? 1 : 0);
  }

  [[nodiscard]] BlockModel unpack(const std::vector<double>& v) const {
    BlockModel m;
    m.white_var = std::exp(v[0]);
    m.n_gm = n_gm;
    for (std::size_t i = 0; i < n_gm; ++i) {
      const double u = v[1 + 2 * i + 1];
      m.gm[i].sb = std::exp(v[1 + 2 * i]);
      m.gm[i].tb_s = std::exp(ln_tb_min + ln_tb_span / (1.0 + std::exp(-u)));
    }
    m.k = fit_k ? std::exp(v[1 + 2 * n_gm]) : k_fixed;
    if (fit_bi) {
      m.bi = std::exp(v[size() - 1]);
      m.bi_tau_lo_s = bi_lo_s;
      m.bi_tau_hi_s = bi_hi_s;
    }
    return m;
  }

  [[nodiscard]] std::vector<double> pack(const BlockModel& m) const {
    // Built from a one-element list, so GCC (aarch64, -O3) sees v[0] exists (it warned of a
    // null dereference for a vector sized by size()).
    std::vector<double> v{std::log(m.white_var)};
    v.resize(size());
    for (std::size_t i = 0; i < n_gm; ++i) {
      v[1 + 2 * i] = std::log(m.gm[i].sb);
      double frac = ln_tb_span > 0.0 ? (std::log(m.gm[i].tb_s) - ln_tb_min) / ln_tb_span : 0.5;
      frac = std::clamp(frac, 0.02, 0.98);
      v[1 + 2 * i + 1] = std::log(frac / (1.0 - frac));
    }
    if (fit_k) {
      v[1 + 2 * n_gm] = std::log(m.k);
    }
    if (fit_bi) {
      v[size() - 1] = std::log(m.bi);
    }
    return v;
  }
};

}  // namespace

std::vector<double> block_means(const std::vector<double>& y, std::size_t per_block) {
  const std::size_t nb = per_block > 0 ? y.size() / per_block : 0;
  std::vector<double> out(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    double s = 0.0;
    for (std::size_t i = 0; i < per_block; ++i) {
      s += y[b * per_block + i];
    }
    out[b] = s / static_cast<double>(per_block);
  }
  return out;
}

namespace {

// The model's independent states as arrays (one per field) for the Kalman pass.
struct StateSet {
  std::size_t d = 0;  // states; the walk is the last
  double r = 0.0;     // variance of the block mean's own noise (white + each state's ru)
  std::array<double, kMaxStates> f{};
  std::array<double, kMaxStates> q{};
  std::array<double, kMaxStates> hm{};
  std::array<double, kMaxStates> s{};
  std::array<double, kMaxStates> p0{};

  void add(const Component& c) {
    f[d] = c.f;
    q[d] = c.q;
    hm[d] = c.hm;
    s[d] = c.s;
    p0[d] = c.p0;
    r += c.ru;
    ++d;
  }
};

// sum log(s) as the log of a running product, mantissa and binary exponent kept apart: one log
// per record instead of one per block. A factor outside [1e-150, 1e150] gives its exponent up
// before the multiply, and the product is renormalised only when it leaves that range (exactly,
// by powers of two), so the product stays within [1e-300, 1e300] and most blocks cost one
// multiply.
class LogSum {
 public:
  void add(double s) {
    int e = 0;
    if (!(s >= 1e-150 && s <= 1e150)) {
      s = std::frexp(s, &e);
      exp_ += e;
    }
    prod_ *= s;
    if (!(prod_ >= 1e-150 && prod_ <= 1e150)) {
      prod_ = std::frexp(prod_, &e);
      exp_ += e;
    }
  }
  [[nodiscard]] double value() const {
    return std::log(prod_) + static_cast<double>(exp_) * std::log(2.0);
  }

 private:
  double prod_ = 1.0;
  long exp_ = 0;
};

struct PassInput {
  const std::vector<double>* means = nullptr;
  const StateSet* c = nullptr;
  bool diffuse = false;
  double big = 0.0;  // the diffuse variance, added to the walk's at a reset
  const std::vector<std::size_t>* resets = nullptr;
  std::vector<double>* whitened = nullptr;
};

// The Kalman pass over the block means for D states, D known at compile time so that the small
// loops unroll. P is kept exactly symmetric (each element's update is symmetric in i, j) and only
// its upper triangle computed.
template <std::size_t D>
double kalman_pass(const PassInput& in) {
  constexpr double kInvalid = -std::numeric_limits<double>::infinity();
  constexpr std::size_t iw = D - 1;  // the walk's state
  const std::vector<double>& means = *in.means;
  const StateSet& c = *in.c;
  std::array<double, D> x{};
  std::array<std::array<double, D>, D> p{};
  for (std::size_t i = 0; i < D; ++i) {
    p[i][i] = c.p0[i];
  }
  x[iw] = in.diffuse ? means[0] : 0.0;
  double ll = 0.0;
  LogSum log_s;
  std::size_t next_reset = 0;
  // Steady state: the model is time-invariant, so P (and with it s and the gain) converges;
  // once s repeats to 1e-14 relative, P is a fixed point of its recursion and is no longer
  // updated (O(D) per block instead of O(D^2), one log for the whole stretch) until a reset
  // disturbs it.
  bool steady = false;
  double s_prev = -1.0;
  double steady_s = 0.0;
  double steady_inv_s = 0.0;
  double steady_log_s = 0.0;
  std::array<double, D> g{};
  for (std::size_t k = 0; k < means.size(); ++k) {
    bool reset = false;
    while (next_reset < in.resets->size() && (*in.resets)[next_reset] <= k) {
      reset = reset || (*in.resets)[next_reset] == k;
      ++next_reset;
    }
    if (reset && k > 0) {  // the walk's level is unknown again
      p[iw][iw] += in.big;
      steady = false;
      s_prev = -1.0;
    }
    double pred = 0.0;
    for (std::size_t i = 0; i < D; ++i) {
      pred += c.hm[i] * x[i];
    }
    const double nu = means[k] - pred;
    if (steady) {
      ll -= 0.5 * (steady_log_s + nu * nu * steady_inv_s);
      if (in.whitened != nullptr) {
        (*in.whitened)[k] = nu / std::sqrt(steady_s);
      }
      for (std::size_t i = 0; i < D; ++i) {
        x[i] = c.f[i] * x[i] + g[i] * nu;
      }
      continue;
    }
    std::array<double, D> ph{};  // P hm
    for (std::size_t i = 0; i < D; ++i) {
      for (std::size_t j = 0; j < D; ++j) {
        ph[i] += p[i][j] * c.hm[j];
      }
    }
    double s = c.r;
    for (std::size_t i = 0; i < D; ++i) {
      s += c.hm[i] * ph[i];
    }
    if (!(s > 0.0)) {
      return kInvalid;
    }
    const double inv_s = 1.0 / s;  // one division per block
    if ((!in.diffuse || k > 0) && !reset) {
      log_s.add(s);
      ll -= 0.5 * (nu * nu * inv_s);
      if (in.whitened != nullptr) {
        (*in.whitened)[k] = nu / std::sqrt(s);
      }
    }
    // Predictor form with correlated noise: G = (F P hm + S) / s; x = F x + G nu;
    // P = F P F + Q - G G s.
    for (std::size_t i = 0; i < D; ++i) {
      g[i] = (c.f[i] * ph[i] + c.s[i]) * inv_s;
      x[i] = c.f[i] * x[i] + g[i] * nu;
    }
    if (k > 0 && !reset && std::fabs(s - s_prev) <= 1e-14 * s) {
      steady = true;
      steady_s = s;
      steady_inv_s = inv_s;
      steady_log_s = std::log(s);
      continue;  // P is at its fixed point
    }
    s_prev = s;
    for (std::size_t i = 0; i < D; ++i) {
      for (std::size_t j = i; j < D; ++j) {
        const double v = p[i][j] * (c.f[i] * c.f[j]) - (g[i] * g[j]) * s;
        p[i][j] = v;
        p[j][i] = v;
      }
      p[i][i] += c.q[i];
    }
  }
  return ll - 0.5 * log_s.value();
}

using Pass = double (*)(const PassInput&);

template <std::size_t... I>
constexpr std::array<Pass, sizeof...(I)> make_passes(std::index_sequence<I...> /*unused*/) {
  return {&kalman_pass<I + 1>...};
}

constexpr std::array<Pass, kMaxStates> kPasses =
    make_passes(std::make_index_sequence<kMaxStates>{});

// block_loglik with the sample variance of the means given (fit_block_model evaluates thousands of
// models on one record: the variance is one pass over it, computed once there).
// whitened (optional): nu_k / sqrt(s_k) per block, 0 where the term is left out.
double loglik_impl(const std::vector<double>& means, double means_var, double block_s,
                   const BlockModel& m, double w0_var, const std::vector<std::size_t>& resets,
                   std::vector<double>* whitened = nullptr) {
  constexpr double kInvalid = -std::numeric_limits<double>::infinity();
  if (!(m.white_var > 0.0) || !(block_s > 0.0) || means.empty() || m.n_gm > kMaxGmTerms ||
      !(m.k >= 0.0) || !(m.bi >= 0.0)) {
    return kInvalid;
  }
  if (whitened != nullptr) {
    whitened->assign(means.size(), 0.0);
  }
  PassInput in;
  in.means = &means;
  in.diffuse = w0_var < 0.0;
  // Diffuse start: a variance far above anything in the data (the limit is reached to ~1e-8).
  in.big = 1e8 * (means_var + m.white_var);
  in.resets = &resets;
  in.whitened = whitened;
  StateSet c;
  c.r = m.white_var;
  // GM states: the model's and the flicker bank's long members
  for (std::size_t i = 0; i < m.n_gm; ++i) {
    if (!(m.gm[i].sb > 0.0) || !(m.gm[i].tb_s > 0.0)) {
      return kInvalid;
    }
    c.add(gm_component(m.gm[i].sb, m.gm[i].tb_s, block_s));
  }
  if (m.bi > 0.0) {
    GmParam bank[kMaxBankGm];
    const std::size_t nb = likelihood_bank(m.bi, m.bi_tau_lo_s, m.bi_tau_hi_s, bank);
    if (nb == 0) {
      return kInvalid;
    }
    for (std::size_t i = 0; i < nb; ++i) {
      if (bank[i].tb_s < 0.5 * block_s) {  // white at this scale: AVAR ~ sb tb^2 / tau
        c.r += bank[i].sb * bank[i].tb_s * bank[i].tb_s / block_s;
      } else {
        c.add(gm_component(bank[i].sb, bank[i].tb_s, block_s));
      }
    }
  }
  c.add(walk_component(m.k, block_s, in.diffuse ? in.big : w0_var));
  in.c = &c;
  return kPasses[c.d - 1](in);
}

}  // namespace

double block_loglik(const std::vector<double>& means, double block_s, const BlockModel& m,
                    double w0_var, const std::vector<std::size_t>& resets) {
  return loglik_impl(means, sample_variance(means), block_s, m, w0_var, resets);
}

LikelihoodFit fit_block_model(const std::vector<double>& means, double block_s,
                              const BlockModel& start, bool fit_k, double tb_min_s,
                              double tb_max_s, const std::vector<std::size_t>& resets) {
  LikelihoodFit out;
  if (means.size() < 16 || !(tb_min_s > 0.0) || start.n_gm > kMaxGmTerms ||
      !(start.white_var > 0.0) || (fit_k && !(start.k > 0.0))) {
    return out;
  }
  Packing pk;
  pk.n_gm = start.n_gm;
  pk.fit_k = fit_k;
  pk.k_fixed = start.k;
  pk.fit_bi = start.bi > 0.0;
  pk.bi_lo_s = start.bi_tau_lo_s;
  pk.bi_hi_s = start.bi_tau_hi_s;
  pk.ln_tb_min = std::log(tb_min_s);
  pk.ln_tb_span = std::max(0.0, std::log(tb_max_s) - pk.ln_tb_min);
  for (std::size_t i = 0; i < start.n_gm; ++i) {
    if (!(start.gm[i].sb > 0.0) || !(start.gm[i].tb_s > 0.0)) {
      return out;
    }
  }
  const double means_var = sample_variance(means);
  const auto cost = [&](const std::vector<double>& v) {
    const double ll = loglik_impl(means, means_var, block_s, pk.unpack(v), -1.0, resets);
    return std::isfinite(ll) ? -ll : 1e300;
  };
  const std::vector<double> best = nelder_mead(cost, pk.pack(start), 1.0, 3000);
  out.model = pk.unpack(best);
  out.loglik = block_loglik(means, block_s, out.model, -1.0, resets);
  out.ok = std::isfinite(out.loglik);
  return out;
}

void remove_mean_and_line(std::vector<double>& v, bool detrend) {
  const double nb = static_cast<double>(v.size());
  double sy = 0.0;
  double sty = 0.0;
  double stt = 0.0;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double t = static_cast<double>(k) - 0.5 * (nb - 1.0);
    sy += v[k];
    sty += t * v[k];
    stt += t * t;
  }
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double t = static_cast<double>(k) - 0.5 * (nb - 1.0);
    v[k] -= sy / nb + (detrend && stt > 0.0 ? sty / stt : 0.0) * t;
  }
}

void remove_polynomial(std::vector<double>& v, std::size_t degree) {
  if (degree <= 1) {
    remove_mean_and_line(v, degree == 1);  // the closed form
    return;
  }
  const std::size_t n = v.size();
  if (n == 0) {
    return;
  }
  const double half = 0.5 * static_cast<double>(n - 1);
  std::vector<std::vector<double>> basis;
  for (std::size_t d = 0; d <= degree && d < n; ++d) {
    std::vector<double> b(n);
    for (std::size_t k = 0; k < n; ++k) {
      const double t = half > 0.0 ? (static_cast<double>(k) - half) / half : 0.0;
      b[k] = std::pow(t, static_cast<double>(d));
    }
    for (int pass = 0; pass < 2; ++pass) {
      for (const std::vector<double>& q : basis) {
        double dot = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
          dot += q[k] * b[k];
        }
        for (std::size_t k = 0; k < n; ++k) {
          b[k] -= dot * q[k];
        }
      }
    }
    double norm = 0.0;
    for (const double x : b) {
      norm += x * x;
    }
    if (!(norm > 0.0)) {
      break;
    }
    const double inv = 1.0 / std::sqrt(norm);
    for (double& x : b) {
      x *= inv;
    }
    double dot = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      dot += b[k] * v[k];
    }
    for (std::size_t k = 0; k < n; ++k) {
      v[k] -= dot * b[k];
    }
    basis.push_back(std::move(b));
  }
}

RrwLikelihoodTest test_rrw(const std::vector<double>& y, double ts_s, const ModelParams& start,
                           double tb_max_s, bool detrend,
                           const std::vector<std::uint64_t>& step_samples,
                           std::size_t target_blocks, bool with_walk, std::size_t trend_degree) {
  RrwLikelihoodTest out;
  if (!(ts_s > 0.0) || target_blocks < 64 || y.size() < 64) {
    return out;
  }
  const std::size_t per_block = std::max<std::size_t>(1, y.size() / target_blocks);
  std::vector<double> m = block_means(y, per_block);
  remove_polynomial(m, detrend ? trend_degree : 0);
  return test_rrw_on_means(std::move(m), per_block, ts_s, start, tb_max_s, step_samples,
                           with_walk);
}

RrwLikelihoodTest test_rrw_on_means(std::vector<double> m, std::size_t per_block, double ts_s,
                                    const ModelParams& start, double tb_max_s,
                                    const std::vector<std::uint64_t>& step_samples,
                                    bool with_walk) {
  RrwLikelihoodTest out;
  if (!(ts_s > 0.0) || per_block == 0 || m.size() < 64) {
    return out;
  }
  const double h = static_cast<double>(per_block) * ts_s;
  const double nb = static_cast<double>(m.size());
  // A step inside block b mixes two levels there: the level is reset before b and b + 1.
  std::vector<std::size_t> resets;
  for (const std::uint64_t i : step_samples) {
    const std::size_t b = static_cast<std::size_t>(i / per_block);
    resets.push_back(b);
    resets.push_back(b + 1);
  }
  std::sort(resets.begin(), resets.end());
  const double tb_min = h;
  const double tb_max = std::max(tb_max_s, 2.0 * h);
  // Start: white (and quantization, and GMs shorter than two blocks, which are white at this
  // scale: AVAR ~ sb tb^2 / tau) from the ADEV fit; longer GMs kept (at least one).
  BlockModel s0;
  s0.bi = start.bi;
  s0.bi_tau_lo_s = start.bi_tau_lo_s;
  // Flicker has memory at every scale: over the record's block means the bank reaches the
  // record's length, not only the taus the ADEV fit saw (else a walk takes up its slow part).
  s0.bi_tau_hi_s = std::max(start.bi_tau_hi_s, nb * h);
  double white_psd = start.n * start.n + 3.0 * start.q * start.q / h;
  for (std::size_t i = 0; i < start.n_gm; ++i) {
    const GmParam g = start.gm[i];
    if (g.tb_s < 2.0 * h) {
      white_psd += g.sb * g.tb_s * g.tb_s;
    } else if (s0.n_gm < kMaxGmTerms) {
      s0.gm[s0.n_gm++] = GmParam{g.sb, std::clamp(g.tb_s, tb_min, tb_max)};
    }
  }
  const double var_m = sample_variance(m);
  s0.white_var = std::max(white_psd / h, 1e-3 * var_m);
  if (s0.n_gm == 0) {  // a GM holding half the variance, tb in the middle of its range
    const double tb = std::sqrt(tb_min * tb_max);
    s0.gm[0] = GmParam{std::max(var_m, 1e-30) / tb, tb};
    s0.n_gm = 1;
  }
  if (!(var_m > 0.0)) {
    return out;
  }
  out.block_s = h;
  out.blocks = m.size();
  // H0 from the ADEV start and from a GM at the longest allowed time.
  BlockModel s0b = s0;
  s0b.gm[s0b.n_gm - 1].tb_s = 0.5 * tb_max;
  for (const BlockModel& st : {s0, s0b}) {
    const LikelihoodFit f = fit_block_model(m, h, st, false, tb_min, tb_max, resets);
    if (f.ok && (!out.h0.ok || f.loglik > out.h0.loglik)) {
      out.h0 = f;
    }
  }
  if (!out.h0.ok) {
    return out;
  }
  out.h1 = out.h0;  // K -> 0 reproduces H0
  if (!with_walk) {
    out.per_block = per_block;
    out.means = std::move(m);
    out.resets = std::move(resets);
    out.ok = true;
    return out;
  }
  // H1 from H0's optimum with K from the ADEV fit, and with a walk holding all / a tenth of
  // the record's variance (K^2 T / 6 ~ var for a walk over T).
  const double t_rec = nb * h;
  std::vector<double> k_starts = {std::sqrt(6.0 * var_m / t_rec), std::sqrt(0.6 * var_m / t_rec)};
  if (start.k > 0.0) {
    k_starts.push_back(start.k);
  }
  out.h1 = out.h0;  // K -> 0 reproduces H0
  for (const double k : k_starts) {
    BlockModel st = out.h0.model;
    st.k = k;
    const LikelihoodFit f = fit_block_model(m, h, st, true, tb_min, tb_max, resets);
    if (f.ok && f.loglik > out.h1.loglik) {
      out.h1 = f;
    }
  }
  out.lr = std::max(0.0, 2.0 * (out.h1.loglik - out.h0.loglik));
  out.per_block = per_block;
  out.means = std::move(m);
  out.resets = std::move(resets);
  out.ok = true;
  return out;
}

namespace {

// v less its least-squares projection on f (Frisch-Waugh-Lovell); false when f is zero.
bool project_out(const std::vector<double>& f, std::vector<double>& v) {
  double ff = 0.0;
  double fv = 0.0;
  for (std::size_t k = 0; k < f.size(); ++k) {
    ff += f[k] * f[k];
    fv += f[k] * v[k];
  }
  if (!(ff > 0.0)) {
    return false;
  }
  for (std::size_t k = 0; k < f.size(); ++k) {
    v[k] -= fv / ff * f[k];
  }
  return true;
}

// GLS size and lr of a level shift at block b, given the whitened innovations a of the data
// (f, if not empty: a whitened nuisance regressor, already projected out of a).
bool gls_step(const RrwLikelihoodTest& test, double var, const std::vector<double>& a,
              const std::vector<double>& f, std::size_t b, std::vector<double>& u, double& lr,
              double& size) {
  std::fill(u.begin(), u.end(), 0.0);
  std::fill(u.begin() + static_cast<std::ptrdiff_t>(b), u.end(), 1.0);
  std::vector<double> e;
  if (!std::isfinite(loglik_impl(u, var, test.block_s, test.h0.model, -1.0, test.resets, &e))) {
    return false;
  }
  if (!f.empty()) {
    project_out(f, e);
  }
  double ae = 0.0;
  double ee = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ae += a[k] * e[k];
    ee += e[k] * e[k];
  }
  if (!(ee > 0.0)) {
    return false;
  }
  lr = ae * ae / ee;
  size = ae / ee;
  return true;
}

}  // namespace

StepLikelihood profile_step(const RrwLikelihoodTest& test, std::size_t margin_blocks,
                            std::size_t only_block, const std::vector<double>* nuisance) {
  StepLikelihood out;
  const std::vector<double>& m = test.means;
  const std::size_t nb = m.size();
  if (!test.ok || !test.h0.ok || nb < 2 * margin_blocks + 4 ||
      (nuisance != nullptr && nuisance->size() != nb)) {
    return out;
  }
  const double var = sample_variance(m);
  std::vector<double> a;
  if (!std::isfinite(loglik_impl(m, var, test.block_s, test.h0.model, -1.0, test.resets, &a))) {
    return out;
  }
  std::vector<double> f;  // the whitened nuisance, fitted beside the step in both hypotheses
  if (nuisance != nullptr) {
    if (!std::isfinite(
            loglik_impl(*nuisance, var, test.block_s, test.h0.model, -1.0, test.resets, &f)) ||
        !project_out(f, a)) {
      return out;
    }
  }
  std::vector<double> u(nb, 0.0);
  std::vector<double> lr_at(nb, std::numeric_limits<double>::quiet_NaN());
  std::size_t best_b = 0;
  const std::size_t first = std::max<std::size_t>(margin_blocks, 1);
  for (std::size_t b = first; b + margin_blocks < nb; ++b) {
    if (only_block != kEveryBlock && b != only_block) {
      continue;
    }
    double lr = 0.0;
    double size = 0.0;
    if (!gls_step(test, var, a, f, b, u, lr, size)) {
      continue;
    }
    ++out.positions;
    lr_at[b] = lr;
    if (lr > out.lr || !out.ok) {
      best_b = b;
      out.lr = lr;
      out.size = size;
      out.sample = static_cast<std::uint64_t>(b) * test.per_block;
      out.ok = true;
    }
  }
  if (out.ok) {
    // (a step inside block b - 1 or b peaks at boundary b; boundaries start at 1)
    const PositionRange r = change_point_set(lr_at, best_b);
    out.first_sample = static_cast<std::uint64_t>(r.first - 1) * test.per_block;
    out.last_sample = static_cast<std::uint64_t>(r.last + 1) * test.per_block;
  }
  return out;
}

PositionRange change_point_set(const std::vector<double>& two_ln_l, std::size_t best) {
  PositionRange r{best, best};
  for (std::size_t i = 0; i < two_ln_l.size(); ++i) {
    if (two_ln_l[i] >= two_ln_l[best] - kChangePointSet95) {
      r.first = std::min(r.first, i);
      r.last = std::max(r.last, i);
    }
  }
  return r;
}

double regressor_lr(const RrwLikelihoodTest& test, const std::vector<double>& u, double* size,
                    const std::vector<double>* nuisance) {
  if (size != nullptr) {
    *size = 0.0;
  }
  if (!test.ok || !test.h0.ok || u.size() != test.means.size() ||
      (nuisance != nullptr && nuisance->size() != u.size())) {
    return 0.0;
  }
  const double var = sample_variance(test.means);
  std::vector<double> a;
  std::vector<double> e;
  if (!std::isfinite(
          loglik_impl(test.means, var, test.block_s, test.h0.model, -1.0, test.resets, &a)) ||
      !std::isfinite(loglik_impl(u, var, test.block_s, test.h0.model, -1.0, test.resets, &e))) {
    return 0.0;
  }
  if (nuisance != nullptr) {
    // Both the whitened data and the whitened regressor less their projection on the whitened
    // nuisance (Frisch-Waugh-Lovell: u's coefficient and its statistic with the nuisance fitted).
    std::vector<double> f;
    if (!std::isfinite(
            loglik_impl(*nuisance, var, test.block_s, test.h0.model, -1.0, test.resets, &f))) {
      return 0.0;
    }
    if (project_out(f, a)) {
      project_out(f, e);
    }
  }
  double ae = 0.0;
  double ee = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ae += a[k] * e[k];
    ee += e[k] * e[k];
  }
  if (!(ee > 0.0)) {
    return 0.0;
  }
  if (size != nullptr) {
    *size = ae / ee;
  }
  return ae * ae / ee;
}

SlowGmFit slow_gm_against_walk(const RrwLikelihoodTest& test, double tb_hi_s) {
  SlowGmFit out;
  if (!test.ok || !test.h0.ok || !test.h1.ok || test.means.size() < 16 ||
      !(test.block_s > 0.0)) {
    return out;
  }
  const double h = test.block_s;
  const double t_rec = h * static_cast<double>(test.means.size());
  const double tb_lo = h;
  const double tb_hi = std::max(tb_hi_s, 2.0 * h);
  std::vector<BlockModel> starts;
  BlockModel s0 = test.h0.model;  // its slowest GM alone
  std::size_t slowest = 0;
  for (std::size_t i = 1; i < s0.n_gm; ++i) {
    slowest = s0.gm[i].tb_s > s0.gm[slowest].tb_s ? i : slowest;
  }
  if (s0.n_gm > 0) {
    s0.gm[0] = s0.gm[slowest];
    s0.n_gm = 1;
    s0.k = 0.0;
    starts.push_back(s0);
  }
  const double k = test.h1.model.k;
  if (k > 0.0) {
    for (const double tb : {0.25 * t_rec, t_rec, 10.0 * t_rec}) {
      BlockModel w = test.h1.model;
      w.k = 0.0;
      w.n_gm = 1;
      w.gm[0] = GmParam{k * k, std::clamp(tb, tb_lo, 0.5 * tb_hi)};
      starts.push_back(w);
    }
  }
  for (const BlockModel& st : starts) {
    const LikelihoodFit f = fit_block_model(test.means, h, st, false, tb_lo, tb_hi, test.resets);
    if (f.ok && (!out.fit.ok || f.loglik > out.fit.loglik)) {
      out.fit = f;
    }
  }
  if (!out.fit.ok) {
    return out;
  }
  // The profile over Tb: the GM's Tb held, white and sb refitted (sigma^2 = sb tb / 2 kept as
  // a start below the optimum's Tb, the walk's power sb above it).
  const double tb_best = out.fit.model.gm[0].tb_s;
  double l_max = out.fit.loglik;
  LikelihoodFit better;  // a profile point above the fit's optimum (Nelder-Mead stopped short)
  const auto profile = [&](double tb) {
    BlockModel st = out.fit.model;
    st.gm[0].tb_s = tb;
    st.gm[0].sb *= tb < tb_best ? tb_best / tb : 1.0;
    const LikelihoodFit f =
        fit_block_model(test.means, h, st, false, tb * (1.0 - 1e-6), tb * (1.0 + 1e-6),
                        test.resets);
    if (!f.ok) {
      return -std::numeric_limits<double>::infinity();
    }
    if (f.loglik > l_max) {
      l_max = f.loglik;
      better = f;
    }
    return f.loglik;
  };
  constexpr double kHalfChi2One95 = 0.5 * 3.841458820694124;  // in ln L
  // One end of the set: from tb_best by factors of 2 towards `limit` until the profile falls
  // below the level (then 5 bisections in ln tb), or `limit` itself when it never does.
  const auto set_end = [&](double limit) {
    const bool down = limit < tb_best;
    double in = tb_best;
    for (int i = 0; i < 64; ++i) {
      const bool last = down ? in * 0.5 <= limit : in * 2.0 >= limit;
      const double next = last ? limit : (down ? in * 0.5 : in * 2.0);
      if (l_max - profile(next) > kHalfChi2One95) {
        double outside = next;
        for (int b = 0; b < 5; ++b) {
          const double mid = std::sqrt(in * outside);
          if (l_max - profile(mid) > kHalfChi2One95) {
            outside = mid;
          } else {
            in = mid;
          }
        }
        return in;
      }
      in = next;
      if (last) {
        break;
      }
    }
    return limit;
  };
  out.tb_lo_95_s = tb_best > tb_lo * (1.0 + 1e-9) ? set_end(tb_lo) : tb_lo;
  const double l_top = profile(tb_hi);
  if (l_max - l_top <= kHalfChi2One95) {
    out.tb_hi_95_s = std::numeric_limits<double>::infinity();
  } else {
    out.tb_hi_95_s = tb_best < tb_hi * (1.0 - 1e-9) ? set_end(tb_hi) : tb_hi;
  }
  if (better.ok) {
    out.fit = better;
  }
  out.lr_walk = 2.0 * (test.h1.loglik - out.fit.loglik);
  out.lr_reverts = std::max(0.0, 2.0 * (out.fit.loglik - l_top));
  out.ok = true;
  return out;
}

}  // namespace imu::analyze

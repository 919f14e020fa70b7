// The term registry's rows and the ModelParams accessors.
#include "imu/terms.hpp"

#include <cmath>
#include <cstring>

#include "imu/model_fit.hpp"

namespace imu {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The parameters of one instance of kind k in p, in the row's order (zeros if absent).
struct Values {
  double v[kMaxTermParams] = {};
};

Values values_of(const ModelParams& p, TermKind k, std::size_t i) {
  Values out;
  double* v = out.v;
  switch (k) {
    case TermKind::kWhite:
      v[0] = p.n;
      v[1] = p.n_filter_s;
      break;
    case TermKind::kQuantization: v[0] = p.q; break;
    case TermKind::kGaussMarkov:
      if (i < p.n_gm && i < kMaxGmTerms) {
        v[0] = std::sqrt(p.gm[i].sb * p.gm[i].tb_s / 2.0);
        v[1] = p.gm[i].tb_s;
      }
      break;
    case TermKind::kRateRandomWalk: v[0] = p.k; break;
    case TermKind::kRamp: v[0] = p.r; break;
    case TermKind::kSinusoid:
      v[0] = i == 0 ? p.sin_f0_hz : p.sin2_f0_hz;
      v[1] = i == 0 ? p.sin_a : p.sin2_a;
      break;
    case TermKind::kBiasInstability:
      v[0] = p.bi;
      v[1] = p.bi_tau_lo_s;
      v[2] = p.bi_tau_hi_s;
      break;
    case TermKind::kOscillation:
      v[0] = p.osc_f0_hz;
      v[1] = p.osc_sigma;
      v[2] = p.osc_beta_per_s / kPi;
      break;
  }
  return out;
}

bool present(const ModelParams& p, TermKind k, std::size_t i) {
  const TermInfo& t = term_info(k);
  if (i >= t.max_instances) {
    return false;
  }
  const double v = values_of(p, k, i).v[t.main_param];
  return k == TermKind::kRamp ? std::fabs(v) > 0.0 : v > 0.0;
}

}  // namespace

// NOLINTBEGIN(cppcoreguidelines-avoid-c-arrays)
const TermInfo kTermTable[kTermKinds] = {
    // name, label, AVAR, parameters {key, symbol, unit}, fit basis, kind, states, instances,
    // instances in the first-order model, deterministic, main parameter, parameters,
    // wire {record, fields, byte offsets per instance, fields}, Kalibr YAML key.
    // ModelRecord v2: version, channel, n_states, flags, then float32 n 4, q 8, gm_sb[0] 12,
    // gm_tb_s[0] 16, gm_sb[1] 20, gm_tb_s[1] 24, k 28, bi 32, bi_tau_lo_s 36, bi_tau_hi_s 40,
    // n_filter_s 44, osc_sigma 48, osc_f0_hz 52, osc_beta_per_s 56, CRC 60. ModelSignalsRecord:
    // channel, flags, 2 reserved, then ramp_r 4, sin_a[0] 8, sin_a[1] 12, sin_f0_hz[0] 16,
    // sin_f0_hz[1] 20, memory_s 24, CRC 28.
    {"white", "white noise", "N^2 / tau", {{"n", "N", "u/sqrt(Hz)"}, {"tf_s", "Tf", "s"}, {}},
     kFitWhite, TermKind::kWhite, 0, 1, 1, false, 0, 2,
     {WireRecord::kModel, {"n", "n_filter_s", nullptr}, {{4, 44, 0}, {}}, 2}, "noise_density"},
    {"quantization", "quantization", "3 Q^2 / tau^2", {{"q", "Q", "u s"}, {}, {}},
     kFitQuantization, TermKind::kQuantization, 0, 1, 0, false, 0, 1,
     {WireRecord::kModel, {"q", nullptr, nullptr}, {{8, 0, 0}, {}}, 1}, nullptr},
    {"gauss_markov", "Gauss-Markov",
     "(Sb Tb^2 / tau)(1 - (Tb / 2 tau)(3 - 4 e^(-tau/Tb) + e^(-2 tau/Tb))), Sb = 2 sigma^2 / Tb",
     {{"sigma", "sigma", "u"}, {"tb_s", "Tb", "s"}, {}}, kFitGm1, TermKind::kGaussMarkov, 1,
     kMaxGmTerms, 1, false, 0, 2,
     {WireRecord::kModel, {"gm_sb", "gm_tb_s", nullptr}, {{12, 16, 0}, {20, 24, 0}}, 2}, nullptr},
    {"rate_random_walk", "rate random walk", "K^2 tau / 3", {{"k", "K", "u/sqrt(s)"}, {}, {}},
     kFitRrw, TermKind::kRateRandomWalk, 1, 1, 0, false, 0, 1,
     {WireRecord::kModel, {"k", nullptr, nullptr}, {{28, 0, 0}, {}}, 1}, "random_walk"},
    {"ramp", "ramp", "R^2 tau^2 / 2", {{"r", "R", "u/s"}, {}, {}}, kFitRamp, TermKind::kRamp, 2,
     1, 0, true, 0, 1, {WireRecord::kSignals, {"ramp_r", nullptr, nullptr}, {{4, 0, 0}, {}}, 1},
     nullptr},
    {"sinusoid", "sinusoid", "A^2 sin^4(pi f0 tau) / (pi f0 tau)^2",
     {{"freq_hz", "f0", "Hz"}, {"amplitude", "A", "u"}, {}}, 0, TermKind::kSinusoid, 2, 2, 0, true,
     1, 2, {WireRecord::kSignals, {"sin_f0_hz", "sin_a", nullptr}, {{16, 8, 0}, {20, 12, 0}}, 2},
     nullptr},
    {"bias_instability", "bias instability", "(2 ln 2 / pi) B^2 over [tau_lo, tau_hi]",
     {{"b", "B", "u"}, {"tau_lo_s", "tau_lo", "s"}, {"tau_hi_s", "tau_hi", "s"}}, kFitFlicker,
     TermKind::kBiasInstability, 1, 1, 0, false, 0, 3,
     {WireRecord::kModel, {"bi", "bi_tau_lo_s", "bi_tau_hi_s"}, {{32, 36, 40}, {}}, 3}, nullptr},
    {"oscillation", "narrowband oscillation",
     "sigma^2 Re{2 g(x) / x}, x = (beta - i 2 pi f0) tau",
     {{"freq_hz", "f0", "Hz"}, {"sigma", "sigma", "u"}, {"bandwidth_hz", "beta/pi", "Hz"}},
     kFitOscillation, TermKind::kOscillation, 2, 1, 0, false, 1, 3,
     {WireRecord::kModel, {"osc_f0_hz", "osc_sigma", "osc_beta_per_s"}, {{52, 48, 56}, {}}, 3},
     nullptr},
};
// NOLINTEND(cppcoreguidelines-avoid-c-arrays)

const TermInfo* term_by_name(const char* name) {
  for (const TermInfo& t : kTermTable) {
    if (name != nullptr && std::strcmp(t.name, name) == 0) {
      return &t;
    }
  }
  return nullptr;
}

const TermInfo* term_by_fit_bit(std::uint32_t bit) {
  if (bit == kFitGm2) {
    return &term_info(TermKind::kGaussMarkov);
  }
  for (const TermInfo& t : kTermTable) {
    if (t.fit_bit != 0 && t.fit_bit == bit) {
      return &t;
    }
  }
  return nullptr;
}

std::size_t term_instances(const ModelParams& p, TermKind k) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < term_info(k).max_instances; ++i) {
    n += present(p, k, i) ? 1U : 0U;
  }
  return n;
}

double term_param(const ModelParams& p, TermKind k, std::size_t instance, std::size_t param) {
  if (!present(p, k, instance) || param >= term_info(k).n_params) {
    return 0.0;
  }
  return values_of(p, k, instance).v[param];
}

// The same presence rule as present(), written out per kind: model_avar calls this for every
// row and instance at every tau of every fit, so it reads the fields directly.
double term_avar(const ModelParams& p, TermKind k, std::size_t i, double tau_s) {
  switch (k) {
    case TermKind::kWhite:
      return i == 0 && p.n > 0.0 ? avar_white_filtered(p.n, p.n_filter_s, tau_s) : 0.0;
    case TermKind::kQuantization: return i == 0 && p.q > 0.0 ? avar_quantization(p.q, tau_s) : 0.0;
    case TermKind::kGaussMarkov:
      return i < p.n_gm && i < kMaxGmTerms && p.gm[i].sb > 0.0 && p.gm[i].tb_s > 0.0
                 ? avar_gauss_markov(p.gm[i].sb, p.gm[i].tb_s, tau_s)
                 : 0.0;
    case TermKind::kRateRandomWalk: return i == 0 && p.k > 0.0 ? avar_rrw(p.k, tau_s) : 0.0;
    case TermKind::kRamp: return i == 0 && std::fabs(p.r) > 0.0 ? avar_ramp(p.r, tau_s) : 0.0;
    case TermKind::kSinusoid: {
      const double a = i == 0 ? p.sin_a : p.sin2_a;
      const double f0 = i == 0 ? p.sin_f0_hz : p.sin2_f0_hz;
      const double ts = i == 0 ? p.sin_ts_s : p.sin2_ts_s;
      return i < 2 && a > 0.0 && f0 > 0.0 ? avar_sinusoid_sampled(a, f0, ts, tau_s) : 0.0;
    }
    case TermKind::kBiasInstability:
      return i == 0 && p.bi > 0.0
                 ? avar_flicker_bank(p.bi, p.bi_tau_lo_s, p.bi_tau_hi_s, tau_s)
                 : 0.0;
    case TermKind::kOscillation:
      return i == 0 && p.osc_sigma > 0.0 && p.osc_beta_per_s > 0.0
                 ? avar_oscillation_sampled(p.osc_sigma, p.osc_f0_hz, p.osc_beta_per_s,
                                            p.osc_ts_s, tau_s)
                 : 0.0;
  }
  return 0.0;
}

double term_psd(const ModelParams& p, TermKind k, std::size_t i, double f_hz, double ts_s) {
  const auto gm_psd = [f_hz](double sb, double tb_s) {
    const double w = 2.0 * kPi * f_hz * tb_s;
    return 2.0 * sb * tb_s * tb_s / (1.0 + w * w);
  };
  if (!(f_hz > 0.0) || !present(p, k, i)) {
    return 0.0;
  }
  switch (k) {
    case TermKind::kWhite: {
      const double w = 2.0 * kPi * f_hz * p.n_filter_s;
      return 2.0 * p.n * p.n / (1.0 + w * w);
    }
    case TermKind::kQuantization:
      return ts_s > 0.0 && f_hz <= 0.5 / ts_s ? 8.0 * kPi * kPi * ts_s * p.q * p.q * f_hz * f_hz
                                              : 0.0;
    case TermKind::kGaussMarkov:
      return p.gm[i].tb_s > 0.0 ? gm_psd(p.gm[i].sb, p.gm[i].tb_s) : 0.0;
    case TermKind::kRateRandomWalk: return p.k * p.k / (2.0 * kPi * kPi * f_hz * f_hz);
    case TermKind::kRamp:
    case TermKind::kSinusoid: return 0.0;
    case TermKind::kBiasInstability: {
      GmParam bank[kMaxFlickerGm] = {};
      const std::size_t n = flicker_bank(p.bi, p.bi_tau_lo_s, p.bi_tau_hi_s, bank);
      double s = 0.0;
      for (std::size_t j = 0; j < n; ++j) {
        s += gm_psd(bank[j].sb, bank[j].tb_s);
      }
      return s;
    }
    case TermKind::kOscillation: {
      const double b = p.osc_beta_per_s;
      const double lo = 2.0 * kPi * (f_hz - p.osc_f0_hz);
      const double hi = 2.0 * kPi * (f_hz + p.osc_f0_hz);
      return b > 0.0 ? 2.0 * p.osc_sigma * p.osc_sigma * (b / (b * b + lo * lo) +
                                                          b / (b * b + hi * hi))
                     : 0.0;
    }
  }
  return 0.0;
}

void remove_term(ModelParams& p, TermKind k, std::size_t from) {
  switch (k) {
    case TermKind::kWhite:
      p.n = from == 0 ? 0.0 : p.n;
      p.n_filter_s = from == 0 ? 0.0 : p.n_filter_s;
      break;
    case TermKind::kQuantization: p.q = from == 0 ? 0.0 : p.q; break;
    case TermKind::kGaussMarkov:
      for (std::size_t i = from; i < kMaxGmTerms; ++i) {
        p.gm[i] = GmParam{};
      }
      p.n_gm = p.n_gm < from ? p.n_gm : from;
      break;
    case TermKind::kRateRandomWalk: p.k = from == 0 ? 0.0 : p.k; break;
    case TermKind::kRamp: p.r = from == 0 ? 0.0 : p.r; break;
    case TermKind::kSinusoid:
      if (from == 0) {
        p.sin_a = p.sin_f0_hz = p.sin_ts_s = 0.0;
      }
      p.sin2_a = p.sin2_f0_hz = p.sin2_ts_s = 0.0;
      break;
    case TermKind::kBiasInstability: p.bi = from == 0 ? 0.0 : p.bi; break;
    case TermKind::kOscillation: p.osc_sigma = from == 0 ? 0.0 : p.osc_sigma; break;
  }
}

}  // namespace imu

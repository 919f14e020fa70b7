// Text reports of error models (see model_text.hpp).
#include "imu/model_text.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <string>

namespace imu {
namespace {

// printf into a std::string (the lines here are short; 512 bytes is ample and checked).
__attribute__((format(printf, 2, 3))) void appendf(std::string& out, const char* fmt, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, fmt);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  if (n > 0) {
    out.append(buf, static_cast<std::size_t>(n) < sizeof buf ? static_cast<std::size_t>(n)
                                                             : sizeof buf - 1);
  }
}

}  // namespace

std::string format_first_order_model(const FirstOrderGm& m) {
  std::string s;
  appendf(s, "Continuous-time model is (units depend on context):\n");
  appendf(s, "    z(t) = b(t) + n(t),\n");
  appendf(s, "    db(t)/dt = -%.4e * b(t) + w(t),\n", m.mu_per_s);
  appendf(s,
          "where n(t) is white noise with PSD S_n = %.4e and w(t) is the bias process noise "
          "with PSD S_w = %.4e.\n",
          m.sn, m.sb);
  appendf(s, "The steady-state covariance of the bias process is P_b_ss_c = %.4e.\n", m.pss);
  appendf(s, "\n");
  appendf(s, "Discrete-time model is (units depend on context):\n");
  appendf(s, "    z[k] = b[k] + n[k],\n");
  appendf(s, "    b[k+1] = %.4f * b[k] + w[k],\n", m.phi);
  appendf(s,
          "where n[k] is white noise with covariance Q_n = %.4e (std %.4e) and w[k] is the bias "
          "process with covariance Q_w = %.4e (std %.4e).\n",
          m.qn, std::sqrt(m.qn), m.qw, std::sqrt(m.qw));
  appendf(s, "The steady-state covariance of the bias process is P_b_ss_d = %.4e.\n", m.pss_d);
  return s;
}

std::string format_model_params(const ModelParams& p) {
  std::string s;
  if (p.n > 0.0) {
    appendf(s, "white noise N = %.4e u/sqrt(Hz)\n", p.n);
    if (p.n_filter_s > 0.0) {
      appendf(s, "  seen through the sensor's first-order output filter, Tf = %.4e s\n",
              p.n_filter_s);
    }
  }
  if (p.q > 0.0) {
    appendf(s, "quantization Q = %.4e u s\n", p.q);
  }
  for (std::size_t i = 0; i < p.n_gm && i < kMaxGmTerms; ++i) {
    const GmParam& g = p.gm[i];
    appendf(s, "gauss-markov %zu: Sb = %.4e u^2/s, Tb = %.4e s (B = %.4e u, peak at tau = %.4e s)\n",
            i + 1, g.sb, g.tb_s, kGmPeakAdevFactor * std::sqrt(g.sb * g.tb_s),
            kGmPeakTauFactor * g.tb_s);
  }
  if (p.k > 0.0) {
    appendf(s, "rate random walk K = %.4e u/sqrt(s)\n", p.k);
  }
  if (p.r > 0.0) {
    appendf(s, "ramp R = %.4e u/s\n", p.r);
  }
  if (p.sin_a > 0.0) {
    appendf(s, "sinusoid A = %.4e u at f0 = %.4e Hz\n", p.sin_a, p.sin_f0_hz);
  }
  return s;
}

}  // namespace imu

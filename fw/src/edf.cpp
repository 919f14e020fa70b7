// Greenhall-Riley EDF and chi-square quantiles. See imu/edf.hpp for the contracts.
#include "imu/edf.hpp"

#include <cmath>
#include <limits>

namespace imu {
namespace {

constexpr double kJMax = 100.0;  // Greenhall's J_max: beyond it the asymptotic tables are used.
constexpr double kInf = std::numeric_limits<double>::infinity();

// Eqn. (7): the generalised autocovariance kernel of the power-law noise S_y ~ f^alpha.
double sw(double t, int alpha) {
  const double at = std::fabs(t);
  switch (alpha) {
    case 2: return -at;
    case 1: return at > 0.0 ? t * t * std::log(at) : 0.0;
    case 0: return at * at * at;
    case -1: return at > 0.0 ? t * t * t * t * std::log(at) : 0.0;
    case -2: return at * at * at * at * at;
    case -3: return at > 0.0 ? t * t * t * t * t * t * std::log(at) : 0.0;
    case -4: return at * at * at * at * at * at * at;
    default: return 0.0;
  }
}

// Eqn. (8): kernel after the averaging filter of factor F (F = inf: the continuous limit).
double sx(double t, double f, int alpha) {
  if (std::isinf(f)) {
    return sw(t, alpha + 2);
  }
  const double h = 1.0 / f;
  return f * f * (2.0 * sw(t, alpha) - sw(t - h, alpha) - sw(t + h, alpha));
}

// Eqn. (9): kernel after the d-th difference: sum_k (-1)^k C(2d, d+k) sx(t + k).
double sz(double t, double f, int alpha, int d) {
  // Binomial coefficients C(2d, d+k) for k = 0..d, d = 1..3.
  static constexpr double kBinom[4][4] = {
      {1.0, 0.0, 0.0, 0.0}, {2.0, 1.0, 0.0, 0.0}, {6.0, 4.0, 1.0, 0.0}, {20.0, 15.0, 6.0, 1.0}};
  double s = kBinom[d][0] * sx(t, f, alpha);
  double sign = -1.0;
  for (int k = 1; k <= d; ++k) {
    const double kd = static_cast<double>(k);
    s += sign * kBinom[d][k] * (sx(t - kd, f, alpha) + sx(t + kd, f, alpha));
    sign = -sign;
  }
  return s;
}

// Eqn. (10): the basic sum.
double basic_sum(double j_count, double m_terms, double s, double f, int alpha, int d) {
  const double z0 = sz(0.0, f, alpha, d);
  const double zj = sz(j_count / s, f, alpha, d);
  double sum = z0 * z0 + (1.0 - j_count / m_terms) * zj * zj;
  const auto jn = static_cast<int>(j_count);
  for (int j = 1; j < jn; ++j) {
    const double jd = static_cast<double>(j);
    const double z = sz(jd / s, f, alpha, d);
    sum += 2.0 * (1.0 - jd / m_terms) * z * z;
  }
  return sum;
}

struct A01 {
  double a0;
  double a1;
};

// Table 2 (unmodified variances, large r): rows alpha = 2 .. -4, columns d = 1 .. 3.
constexpr A01 kTable2[7][3] = {
    {{1.5, 0.5}, {35.0 / 18.0, 1.0}, {2.31, 1.5}},
    {{78.6, 25.2}, {790.0, 410.0}, {9950.0, 6520.0}},
    {{2.0 / 3.0, 1.0 / 6.0}, {2.0 / 3.0, 1.0 / 3.0}, {7.0 / 9.0, 0.5}},
    {{0.0, 0.0}, {0.852, 0.375}, {0.997, 0.617}},
    {{0.0, 0.0}, {1.079, 0.368}, {1.033, 0.607}},
    {{0.0, 0.0}, {0.0, 0.0}, {1.053, 0.553}},
    {{0.0, 0.0}, {0.0, 0.0}, {1.302, 0.535}},
};
// Table 1 (modified variances, large r): rows alpha = 2 .. -4, columns d = 1 .. 3.
constexpr A01 kTable1[7][3] = {
    {{2.0 / 3.0, 1.0 / 3.0}, {7.0 / 9.0, 0.5}, {22.0 / 25.0, 2.0 / 3.0}},
    {{0.840, 0.345}, {0.997, 0.616}, {1.141, 0.843}},
    {{1.079, 0.368}, {1.033, 0.607}, {1.184, 0.848}},
    {{0.0, 0.0}, {1.048, 0.534}, {1.180, 0.816}},
    {{0.0, 0.0}, {1.302, 0.535}, {1.175, 0.777}},
    {{0.0, 0.0}, {0.0, 0.0}, {1.194, 0.703}},
    {{0.0, 0.0}, {0.0, 0.0}, {1.489, 0.702}},
};
// Table 3 (alpha = 1): b0 + b1 ln m, d = 1 .. 3.
constexpr A01 kTable3[3] = {{6.0, 4.0}, {15.23, 12.0}, {47.8, 40.0}};

}  // namespace

// Acklam's rational approximation refined by one Halley step on erfc.
double normal_quantile(double p) {
  static constexpr double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02,
                                  -2.759285104469687e+02, 1.383577518672690e+02,
                                  -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02,
                                  -1.556989798598866e+02, 6.680131188771972e+01,
                                  -1.328068155288572e+01};
  static constexpr double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01,
                                  -2.400758277161838e+00, -2.549732539343734e+00,
                                  4.374664141464968e+00, 2.938163982698783e+00};
  static constexpr double e[4] = {7.784695709041462e-03, 3.224671290700398e-01,
                                  2.445134137142996e+00, 3.754408661907416e+00};
  constexpr double p_low = 0.02425;
  double x = 0.0;
  if (p < p_low) {
    const double q = std::sqrt(-2.0 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((e[0] * q + e[1]) * q + e[2]) * q + e[3]) * q + 1.0);
  } else if (p <= 1.0 - p_low) {
    const double q = p - 0.5;
    const double r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  } else {
    const double q = std::sqrt(-2.0 * std::log(1.0 - p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((e[0] * q + e[1]) * q + e[2]) * q + e[3]) * q + 1.0);
  }
  constexpr double kSqrt2Pi = 2.50662827463100050242;
  const double err = 0.5 * std::erfc(-x / 1.41421356237309504880) - p;
  const double u = err * kSqrt2Pi * std::exp(x * x / 2.0);
  return x - u / (1.0 + x * u / 2.0);
}

namespace {

double wilson_hilferty(double p, double dof) {
  const double z = normal_quantile(p);
  const double h = 2.0 / (9.0 * dof);
  const double c = 1.0 - h + z * std::sqrt(h);
  return dof * c * c * c;
}

}  // namespace

double edf_greenhall(int alpha, int d, double m, double stride_factor, double n_terms) {
  if (d < 1 || d > 3 || alpha < -4 || alpha > 2 || alpha + 2 * d <= 1 || !(m >= 1.0) ||
      !(stride_factor >= 1.0) || stride_factor > m || !(n_terms >= 1.0)) {
    return 0.0;
  }
  const double dd = static_cast<double>(d);
  const double s = stride_factor;
  const double big_m = std::floor(n_terms);
  const double j = std::fmin(big_m, (dd + 1.0) * s);
  const double r = big_m / s;
  const A01 t2 = kTable2[2 - alpha][d - 1];
  double inv_edf = 0.0;
  if (alpha <= 0) {  // case 2: unmodified variance, alpha <= 0
    if (j <= kJMax) {
      const double f = (m * (dd + 1.0) <= kJMax) ? m : kInf;
      const double z0 = sz(0.0, f, alpha, d);
      inv_edf = basic_sum(j, big_m, s, f, alpha, d) / (z0 * z0 * big_m);
    } else if (r > dd + 1.0) {
      inv_edf = (t2.a0 - t2.a1 / r) / r;
    } else {
      const double z0 = sz(0.0, kInf, alpha, d);
      inv_edf = basic_sum(kJMax, kJMax, kJMax / r, kInf, alpha, d) / (z0 * z0 * kJMax);
    }
  } else if (alpha == 1) {  // case 3: flicker PM
    const A01 t3 = kTable3[d - 1];
    const double b = t3.a0 + t3.a1 * std::log(m);
    if (j <= kJMax) {
      const double z0 = sz(0.0, m, 1, d);
      inv_edf = basic_sum(j, big_m, s, m, 1, d) / (z0 * z0 * big_m);
    } else if (r > dd + 1.0) {
      inv_edf = (t2.a0 - t2.a1 / r) / (b * b * r);
    } else {
      const double mp = kJMax / r;
      inv_edf = basic_sum(kJMax, kJMax, mp, mp, 1, d) / (b * b * kJMax);
    }
  } else {  // case 4: white PM
    if (j <= kJMax) {
      const double z0 = sz(0.0, m, 2, d);
      inv_edf = basic_sum(j, big_m, s, m, 2, d) / (z0 * z0 * big_m);
    } else {
      inv_edf = (t2.a0 - t2.a1 / r) / big_m;
    }
  }
  if (!(inv_edf > 0.0) || std::isinf(inv_edf)) {
    return 0.0;
  }
  return 1.0 / inv_edf;
}

double edf_greenhall_modified(int alpha, int d, double m, double stride_factor,
                              double n_terms) {
  if (d < 1 || d > 3 || alpha < -4 || alpha > 2 || alpha + 2 * d <= 1 || !(m >= 1.0) ||
      !(stride_factor >= 1.0) || stride_factor > m || !(n_terms >= 1.0)) {
    return 0.0;
  }
  const double dd = static_cast<double>(d);
  const double s = stride_factor;
  const double big_m = std::floor(n_terms);
  const double j = std::fmin(big_m, (dd + 1.0) * s);
  const double r = big_m / s;
  const double z0 = sz(0.0, 1.0, alpha, d);
  double inv_edf = 0.0;
  if (j <= kJMax) {  // case 1: modified variance, every alpha
    inv_edf = basic_sum(j, big_m, s, 1.0, alpha, d) / (z0 * z0 * big_m);
  } else if (r > dd + 1.0) {
    const A01 t1 = kTable1[2 - alpha][d - 1];
    inv_edf = (t1.a0 - t1.a1 / r) / r;
  } else {
    inv_edf = basic_sum(kJMax, kJMax, kJMax / r, 1.0, alpha, d) / (z0 * z0 * kJMax);
  }
  if (!(inv_edf > 0.0) || std::isinf(inv_edf)) {
    return 0.0;
  }
  return 1.0 / inv_edf;
}

double log_gamma(double a) {
  if (!(a > 0.0) || !std::isfinite(a)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  // Lanczos approximation, g = 7, 9 terms (relative error of Gamma ~1e-15 for a > 0), with the
  // reflection formula below 1/2. Not std::lgamma: newlib's writes the sign to
  // _REENT->_gamma_signgam, which on the arm-none-eabi toolchain here lies past the linked
  // impure_data: a stray 4-byte write into the image's RAM (found in the M4 node image, where it
  // hit the input frames).
  constexpr double kPi = 3.14159265358979323846;
  if (a < 0.5) {
    return std::log(kPi / std::sin(kPi * a)) - log_gamma(1.0 - a);
  }
  constexpr double kG = 7.0;
  constexpr double kC[9] = {0.99999999999980993,  676.5203681218851,     -1259.1392167224028,
                            771.32342877765313,   -176.61502916214059,   12.507343278686905,
                            -0.13857109526572012, 9.9843695780195716e-6, 1.5056327351493116e-7};
  const double x = a - 1.0;
  double sum = kC[0];
  for (int i = 1; i < 9; ++i) {
    sum += kC[i] / (x + static_cast<double>(i));
  }
  const double t = x + kG + 0.5;
  return 0.5 * std::log(2.0 * kPi) + (x + 0.5) * std::log(t) - t + std::log(sum);
}

double gamma_p(double a, double x) {
  if (!(a > 0.0) || !(x >= 0.0)) {
    return 0.0;
  }
  if (x <= 0.0) {
    return 0.0;
  }
  constexpr int kMaxIter = 2000;
  constexpr double kEps = 1e-16;
  const double log_prefactor = -x + a * std::log(x) - log_gamma(a);
  if (x < a + 1.0) {  // series
    double ap = a;
    double del = 1.0 / a;
    double sum = del;
    for (int n = 0; n < kMaxIter; ++n) {
      ap += 1.0;
      del *= x / ap;
      sum += del;
      if (std::fabs(del) < std::fabs(sum) * kEps) {
        break;
      }
    }
    return sum * std::exp(log_prefactor);
  }
  // Continued fraction for Q(a, x), modified Lentz.
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double dv = 1.0 / b;
  double h = dv;
  for (int i = 1; i <= kMaxIter; ++i) {
    const double id = static_cast<double>(i);
    const double an = -id * (id - a);
    b += 2.0;
    dv = an * dv + b;
    if (std::fabs(dv) < kTiny) {
      dv = kTiny;
    }
    c = b + an / c;
    if (std::fabs(c) < kTiny) {
      c = kTiny;
    }
    dv = 1.0 / dv;
    const double del = dv * c;
    h *= del;
    if (std::fabs(del - 1.0) < kEps) {
      break;
    }
  }
  return 1.0 - std::exp(log_prefactor) * h;
}

double chi2_quantile(double p, double dof) {
  if (!(p > 0.0) || !(p < 1.0) || !(dof > 0.0)) {
    return 0.0;
  }
  if (dof > 20000.0) {
    return wilson_hilferty(p, dof);
  }
  const double a = 0.5 * dof;
  // Bracket [lo, hi] with P(lo) < p < P(hi); Newton steps that leave it are replaced by bisection.
  double lo = 0.0;
  double hi = dof + 10.0 * std::sqrt(2.0 * dof) + 50.0;
  double x = wilson_hilferty(p, dof);
  if (!(x > lo) || !(x < hi)) {
    x = 0.5 * (lo + hi);
  }
  const double lg = log_gamma(a);
  for (int it = 0; it < 200; ++it) {
    const double f = gamma_p(a, 0.5 * x) - p;
    if (f < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    const double pdf = 0.5 * std::exp((a - 1.0) * std::log(0.5 * x) - 0.5 * x - lg);
    double next = (pdf > 0.0) ? x - f / pdf : 0.5 * (lo + hi);
    if (!(next > lo) || !(next < hi)) {
      next = 0.5 * (lo + hi);
    }
    if (std::fabs(next - x) <= 1e-14 * x) {
      return next;
    }
    x = next;
  }
  return x;
}

DevInterval deviation_interval(double dev, double edf, double confidence) {
  if (!(edf > 0.0) || !(confidence > 0.0) || !(confidence < 1.0)) {
    return DevInterval{0.0, std::numeric_limits<double>::infinity()};
  }
  const double tail = 0.5 * (1.0 - confidence);
  const double chi_hi = chi2_quantile(1.0 - tail, edf);
  const double chi_lo = chi2_quantile(tail, edf);
  return DevInterval{dev * std::sqrt(edf / chi_hi), dev * std::sqrt(edf / chi_lo)};
}

}  // namespace imu

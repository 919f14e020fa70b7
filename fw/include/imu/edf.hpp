// Equivalent degrees of freedom and chi-square confidence intervals for Allan-type variances.
//
// EDF: C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
// differences", Proc. 35th PTTI (2003), the "basic sum" algorithm (eqns. 7-10 and tables 1-3),
// implemented here from the paper's formulas for unmodified variances (filter factor F = m) and
// modified ones (F = 1).
// The estimator is described by: d (2 = Allan), m = averaging factor tau/tau0, S = stride factor
// (terms are tau/S apart: S = 1 non-overlapping, S = m fully overlapping, anything in between
// partially overlapping), n_terms = number of terms in the sum (Greenhall's M) and the power-law
// noise exponent alpha of S_y(f) ~ f^alpha (0 = white FM, the default used by the estimates).
//
// Cost: edf_greenhall is O(min(n_terms, (d+1) S, 100)) with at most a few hundred flops per term;
// chi2_quantile is O(sqrt(dof)) up to dof 20000 (bounded loop), O(1) above. Re-entrant, no heap.
#ifndef IMU_EDF_HPP
#define IMU_EDF_HPP

#include <cstdint>

namespace imu {

/// Two-sided confidence level of the "68.3 %" interval. MODELS.md (and allantools' golden files)
/// use the chi-square quantiles at 0.1585 and 0.8415, i.e. exactly 0.683, not erf(1/sqrt 2).
inline constexpr double kOneSigmaConfidence = 0.683;

/// Greenhall-Riley EDF of an unmodified d-th difference variance (d = 1, 2 or 3).
/// Preconditions: m >= 1, 1 <= stride_factor <= m, n_terms >= 1, alpha in [-4, 2] with
/// alpha + 2 d > 1. Returns 0.0 when the preconditions are not met (no estimate possible).
[[nodiscard]] double edf_greenhall(int alpha, int d, double m, double stride_factor,
                                   double n_terms);

/// Greenhall-Riley EDF of a modified d-th difference variance (filter factor F = 1: MVAR for
/// d = 2, as MDEV and TDEV use; the paper's case 1, eqns. 7-10 and table 1). Same arguments,
/// preconditions and cost as edf_greenhall (alpha in [-4, 2], alpha + 2 d > 1); n_terms is the
/// number of terms of the modified sum. Returns 0.0 when the preconditions are not met.
[[nodiscard]] double edf_greenhall_modified(int alpha, int d, double m, double stride_factor,
                                            double n_terms);

/// Quantile of the standard normal distribution (0 < p < 1): Acklam's approximation refined by
/// one Halley step (relative error ~1e-15).
[[nodiscard]] double normal_quantile(double p);

/// Quantile of the chi-square distribution with `dof` degrees of freedom (dof > 0, 0 < p < 1):
/// Newton iteration on the regularized incomplete gamma function for dof <= 20000, the
/// Wilson-Hilferty approximation above (relative error of the
/// quantile below 1e-7 there, checked by a test). Returns 0.0 for invalid arguments.
[[nodiscard]] double chi2_quantile(double p, double dof);
/// ln Gamma(a) for a > 0 (NaN otherwise): Lanczos, ~1e-15 relative in Gamma. fw's own instead
/// of std::lgamma, whose newlib version writes the sign through a pointer that lands outside
/// its struct on the M4 toolchain (edf.cpp). O(1), re-entrant.
[[nodiscard]] double log_gamma(double a);

/// Regularized lower incomplete gamma P(a, x) (a > 0, x >= 0); bounded series / continued
/// fraction (at most 2000 iterations).
[[nodiscard]] double gamma_p(double a, double x);

struct DevInterval {
  double lo;
  double hi;
};

/// Confidence interval of a deviation (ADEV) estimated with `edf` degrees of freedom:
/// [dev sqrt(edf / chi2_{1-(1-c)/2}), dev sqrt(edf / chi2_{(1-c)/2})] (NIST SP 1065 eqn. 45).
/// With edf <= 0 the interval is [0, +inf).
[[nodiscard]] DevInterval deviation_interval(double dev, double edf,
                                             double confidence = kOneSigmaConfidence);

}  // namespace imu

#endif  // IMU_EDF_HPP

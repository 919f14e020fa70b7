// Covariance check: exact prediction by augmented-state propagation, window integration and the
// robust standard deviation (see covariance_check.hpp for the derivation).
#include "imu/covariance_check.hpp"

#include <cmath>

#include "imu/linalg.hpp"

namespace imu {
namespace {

// k-th smallest of v[0..n-1] (0-based), Hoare quickselect with median-of-three pivots.
double select_kth(double* v, std::size_t n, std::size_t k) {
  std::size_t lo = 0;
  std::size_t hi = n - 1;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    // median of three into v[mid]
    if (v[mid] < v[lo]) {
      const double t = v[mid];
      v[mid] = v[lo];
      v[lo] = t;
    }
    if (v[hi] < v[lo]) {
      const double t = v[hi];
      v[hi] = v[lo];
      v[lo] = t;
    }
    if (v[hi] < v[mid]) {
      const double t = v[hi];
      v[hi] = v[mid];
      v[mid] = t;
    }
    const double pivot = v[mid];
    std::size_t i = lo;
    std::size_t j = hi;
    while (i <= j) {
      while (v[i] < pivot) {
        ++i;
      }
      while (pivot < v[j]) {
        --j;
      }
      if (i <= j) {
        const double t = v[i];
        v[i] = v[j];
        v[j] = t;
        ++i;
        if (j == 0) {
          break;
        }
        --j;
      }
    }
    if (k <= j) {
      hi = j;
    } else if (k >= i) {
      lo = i;
    } else {
      return v[k];
    }
  }
  return v[k];
}

double median_inplace(double* v, std::size_t n) {
  const double upper = select_kth(v, n, n / 2);
  if (n % 2 == 1) {
    return upper;
  }
  // Even n: the lower middle is the largest of the elements left of n/2 after selection.
  double lower = v[0];
  for (std::size_t i = 1; i < n / 2; ++i) {
    lower = v[i] > lower ? v[i] : lower;
  }
  return 0.5 * (lower + upper);
}

}  // namespace

template <std::size_t kMaxStates>
ModelStatus predict_integral_std(const DiscreteModel<kMaxStates>& model, std::size_t n_avg,
                                 std::size_t n_int, double* std_out, CovPrediction mode) {
  const std::size_t n = model.n_states;
  if (n_avg == 0 || n_int == 0 || std_out == nullptr || n > kMaxStates ||
      !(model.ts_s > 0.0) || !(model.r_white >= 0.0) || !(model.q >= 0.0)) {
    return ModelStatus::kBadParameter;
  }
  constexpr std::size_t kS = kMaxStates + 3;   // [x (n), u_prev, A, I]
  constexpr std::size_t kE = kMaxStates + 2;   // [w (n), v, u]
  const std::size_t iu = n;
  const std::size_t ia = n + 1;
  const std::size_t ii = n + 2;
  const std::size_t ns = n + 3;
  const double qts = model.q / model.ts_s;

  Mat<double, kS, kS> p{};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      p(i, j) = model.p0(i, j);
    }
  }
  p(iu, iu) = 1.0;
  Mat<double, kE, kE> qe{};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      qe(i, j) = model.qd(i, j);
    }
  }
  qe(n, n) = model.r_white;
  qe(n + 1, n + 1) = 1.0;

  // Transition for one phase; `gain` multiplies the measurement into A (averaging) or I.
  auto build = [&](bool averaging, Mat<double, kS, kS>& f, Mat<double, kS, kE>& g) {
    f = Mat<double, kS, kS>{};
    g = Mat<double, kS, kE>{};
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        f(i, j) = model.phi(i, j);
      }
      g(i, i) = 1.0;  // w
    }
    g(iu, n + 1) = 1.0;  // u_prev' = u_k
    f(ia, ia) = 1.0;
    f(ii, ii) = 1.0;
    const std::size_t row = averaging ? ia : ii;
    const double c = averaging ? 1.0 / static_cast<double>(n_avg) : model.ts_s;
    for (std::size_t j = 0; j < n; ++j) {
      f(row, j) += c * model.h(0, j);
    }
    f(row, iu) += -c * qts;
    g(row, n) += c;        // v_k
    g(row, n + 1) += c * qts;  // u_k
    if (!averaging) {
      f(ii, ia) += -model.ts_s;
    }
  };
  Mat<double, kS, kS> f{};
  Mat<double, kS, kE> g{};
  build(true, f, g);
  Mat<double, kS, kS> gqg = g * qe * g.transpose();
  for (std::size_t k = 0; k < n_avg; ++k) {
    p = f * p * f.transpose() + gqg;
  }
  if (mode == CovPrediction::kCorrelationIgnored) {
    for (std::size_t j = 0; j < ns; ++j) {
      if (j != ia) {
        p(ia, j) = 0.0;
        p(j, ia) = 0.0;
      }
    }
  }
  build(false, f, g);
  gqg = g * qe * g.transpose();
  for (std::size_t k = 0; k < n_int; ++k) {
    p = f * p * f.transpose() + gqg;
    symmetrize(p);
    std_out[k] = std::sqrt(p(ii, ii) > 0.0 ? p(ii, ii) : 0.0);
  }
  return ModelStatus::kOk;
}

void integrate_window(const double* z, std::size_t n_avg, std::size_t n_int, double ts_s,
                      double* traj_out) {
  double sum = 0.0;
  for (std::size_t k = 0; k < n_avg; ++k) {
    sum += z[k];
  }
  const double a = n_avg > 0 ? sum / static_cast<double>(n_avg) : 0.0;
  double integral = 0.0;
  for (std::size_t j = 0; j < n_int; ++j) {
    integral += ts_s * (z[n_avg + j] - a);
    traj_out[j] = integral;
  }
}

double robust_std(double* values, std::size_t n) {
  if (n == 0) {
    return 0.0;
  }
  const double med = median_inplace(values, n);
  for (std::size_t i = 0; i < n; ++i) {
    values[i] = std::fabs(values[i] - med);
  }
  return 1.4826 * median_inplace(values, n);
}

template ModelStatus predict_integral_std<1>(const DiscreteModel<1>&, std::size_t, std::size_t,
                                             double*, CovPrediction);
template ModelStatus predict_integral_std<2>(const DiscreteModel<2>&, std::size_t, std::size_t,
                                             double*, CovPrediction);
template ModelStatus predict_integral_std<4>(const DiscreteModel<4>&, std::size_t, std::size_t,
                                             double*, CovPrediction);
template ModelStatus predict_integral_std<6>(const DiscreteModel<6>&, std::size_t, std::size_t,
                                             double*, CovPrediction);
template ModelStatus predict_integral_std<8>(const DiscreteModel<8>&, std::size_t, std::size_t,
                                             double*, CovPrediction);  // a model the node runs
template ModelStatus predict_integral_std<16>(const DiscreteModel<16>&, std::size_t,
                                              std::size_t, double*, CovPrediction);

}  // namespace imu

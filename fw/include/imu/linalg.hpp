// Fixed-size dense linear algebra for the error model and the filters: no heap, sizes in the type
// (a dimension mismatch does not compile), row-major storage inside the object.
//
// Contents: Mat<T, R, C> with +, -, *, scalar *, transpose(); identity(); lu_solve() (partial
// pivoting, returns false on a singular matrix instead of a silent zero); cholesky_psd() (lower
// factor of a symmetric positive SEMI-definite matrix, zero pivots allowed, for simulation);
// expm() (scaling and squaring with the [6/6] Pade approximant, double precision, for
// discretisation only, never per sample); symmetrize().
//
// Cost: products O(R K C); lu_solve O(n^3); expm O(n^3 (6 + s)) with s = number of squarings
// (log2 of the 1-norm). All functions are re-entrant (no static state).
#ifndef IMU_LINALG_HPP
#define IMU_LINALG_HPP

#include <cmath>
#include <cstddef>
#include <limits>

namespace imu {

template <typename T, std::size_t R, std::size_t C>
struct Mat {
  static_assert(R >= 1 && C >= 1, "empty matrices are not supported");
  static constexpr std::size_t kRows = R;
  static constexpr std::size_t kCols = C;
  T a[R][C] = {};

  T& operator()(std::size_t r, std::size_t c) { return a[r][c]; }
  const T& operator()(std::size_t r, std::size_t c) const { return a[r][c]; }

  static Mat identity() {
    static_assert(R == C, "identity() needs a square matrix");
    Mat m{};
    for (std::size_t i = 0; i < R; ++i) {
      m.a[i][i] = T(1);
    }
    return m;
  }

  Mat& operator+=(const Mat& o) {
    for (std::size_t i = 0; i < R; ++i) {
      for (std::size_t j = 0; j < C; ++j) {
        a[i][j] += o.a[i][j];
      }
    }
    return *this;
  }
  Mat& operator-=(const Mat& o) {
    for (std::size_t i = 0; i < R; ++i) {
      for (std::size_t j = 0; j < C; ++j) {
        a[i][j] -= o.a[i][j];
      }
    }
    return *this;
  }
  Mat& operator*=(T s) {
    for (std::size_t i = 0; i < R; ++i) {
      for (std::size_t j = 0; j < C; ++j) {
        a[i][j] *= s;
      }
    }
    return *this;
  }

  [[nodiscard]] Mat<T, C, R> transpose() const {
    Mat<T, C, R> t{};
    for (std::size_t i = 0; i < R; ++i) {
      for (std::size_t j = 0; j < C; ++j) {
        t.a[j][i] = a[i][j];
      }
    }
    return t;
  }

  /// Maximum absolute column sum (the matrix 1-norm).
  [[nodiscard]] T norm1() const {
    T best = T(0);
    for (std::size_t j = 0; j < C; ++j) {
      T s = T(0);
      for (std::size_t i = 0; i < R; ++i) {
        s += std::fabs(a[i][j]);
      }
      best = s > best ? s : best;
    }
    return best;
  }
};

template <typename T, std::size_t R, std::size_t C>
[[nodiscard]] Mat<T, R, C> operator+(Mat<T, R, C> x, const Mat<T, R, C>& y) {
  x += y;
  return x;
}
template <typename T, std::size_t R, std::size_t C>
[[nodiscard]] Mat<T, R, C> operator-(Mat<T, R, C> x, const Mat<T, R, C>& y) {
  x -= y;
  return x;
}
template <typename T, std::size_t R, std::size_t C>
[[nodiscard]] Mat<T, R, C> operator*(Mat<T, R, C> x, T s) {
  x *= s;
  return x;
}

/// out = x y, out distinct from x and y.
template <typename T, std::size_t R, std::size_t K, std::size_t C>
void mul_into(const Mat<T, R, K>& x, const Mat<T, K, C>& y, Mat<T, R, C>& out) {
  out = Mat<T, R, C>{};
  for (std::size_t i = 0; i < R; ++i) {
    for (std::size_t k = 0; k < K; ++k) {
      const T xik = x.a[i][k];
      for (std::size_t j = 0; j < C; ++j) {
        out.a[i][j] += xik * y.a[k][j];
      }
    }
  }
}

template <typename T, std::size_t R, std::size_t K, std::size_t C>
[[nodiscard]] Mat<T, R, C> operator*(const Mat<T, R, K>& x, const Mat<T, K, C>& y) {
  Mat<T, R, C> p{};
  mul_into(x, y, p);
  return p;
}

/// (A + A^T) / 2: removes the asymmetry rounding leaves in a covariance.
template <typename T, std::size_t N>
void symmetrize(Mat<T, N, N>& m) {
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = i + 1; j < N; ++j) {
      const T s = (m.a[i][j] + m.a[j][i]) / T(2);
      m.a[i][j] = s;
      m.a[j][i] = s;
    }
  }
}

/// Solve A X = B by LU with partial pivoting, only the leading n x n block of A is used (n <= N;
/// rows/columns beyond n are ignored and X's are left zero). Returns false (X untouched) when a
/// pivot is below `tiny` times the largest |entry| of A, i.e. A is singular to working precision.
template <typename T, std::size_t N, std::size_t C>
[[nodiscard]] bool lu_solve(Mat<T, N, N> A, Mat<T, N, C> B, Mat<T, N, C>& X, std::size_t n = N) {
  if (n == 0 || n > N) {
    return false;
  }
  T scale = T(0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      scale = std::fabs(A.a[i][j]) > scale ? std::fabs(A.a[i][j]) : scale;
    }
  }
  if (!(scale > T(0))) {
    return false;
  }
  const T tiny = scale * std::numeric_limits<T>::epsilon();
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t piv = k;
    for (std::size_t i = k + 1; i < n; ++i) {
      if (std::fabs(A.a[i][k]) > std::fabs(A.a[piv][k])) {
        piv = i;
      }
    }
    if (!(std::fabs(A.a[piv][k]) > tiny)) {
      return false;
    }
    if (piv != k) {
      for (std::size_t j = 0; j < n; ++j) {
        const T t = A.a[k][j];
        A.a[k][j] = A.a[piv][j];
        A.a[piv][j] = t;
      }
      for (std::size_t j = 0; j < C; ++j) {
        const T t = B.a[k][j];
        B.a[k][j] = B.a[piv][j];
        B.a[piv][j] = t;
      }
    }
    for (std::size_t i = k + 1; i < n; ++i) {
      const T f = A.a[i][k] / A.a[k][k];
      for (std::size_t j = k; j < n; ++j) {
        A.a[i][j] -= f * A.a[k][j];
      }
      for (std::size_t j = 0; j < C; ++j) {
        B.a[i][j] -= f * B.a[k][j];
      }
    }
  }
  Mat<T, N, C> out{};
  for (std::size_t jj = 0; jj < C; ++jj) {
    for (std::size_t ii = n; ii-- > 0;) {
      T s = B.a[ii][jj];
      for (std::size_t j = ii + 1; j < n; ++j) {
        s -= A.a[ii][j] * out.a[j][jj];
      }
      out.a[ii][jj] = s / A.a[ii][ii];
    }
  }
  X = out;
  return true;
}

/// Lower-triangular L with L L^T = A for a symmetric positive semi-definite A (leading n x n
/// block). A pivot below `rel_tol` times the largest diagonal is treated as zero (its column of L
/// is zero), so singular covariances (deterministic states) are accepted. Returns false only if
/// a pivot is clearly negative (A is not PSD beyond rounding).
template <typename T, std::size_t N>
[[nodiscard]] bool cholesky_psd(const Mat<T, N, N>& A, Mat<T, N, N>& L, std::size_t n = N,
                                T rel_tol = T(1e-12)) {
  Mat<T, N, N> out{};
  T dmax = T(0);
  for (std::size_t i = 0; i < n; ++i) {
    dmax = A.a[i][i] > dmax ? A.a[i][i] : dmax;
  }
  const T tol = rel_tol * dmax;
  for (std::size_t j = 0; j < n; ++j) {
    T d = A.a[j][j];
    for (std::size_t k = 0; k < j; ++k) {
      d -= out.a[j][k] * out.a[j][k];
    }
    if (d < -tol * T(1e3)) {
      return false;
    }
    if (!(d > tol)) {
      continue;  // zero pivot: column j of L stays zero
    }
    const T ljj = std::sqrt(d);
    out.a[j][j] = ljj;
    for (std::size_t i = j + 1; i < n; ++i) {
      T s = A.a[i][j];
      for (std::size_t k = 0; k < j; ++k) {
        s -= out.a[i][k] * out.a[j][k];
      }
      out.a[i][j] = s / ljj;
    }
  }
  L = out;
  return true;
}

/// Matrix exponential of the leading n x n block (scaling and squaring, [6/6] Pade, Golub & Van
/// Loan alg. 11.3-1). The block is scaled by 2^-s so that its 1-norm is <= 0.5; the Pade error
/// bound is then 2^{3-12} * 6!^2 / (12! 13!) * 0.5^12 < 1e-18 relative. Returns false if the
/// denominator is singular (cannot happen for finite input) or the norm is not finite.
template <std::size_t N>
[[nodiscard]] bool expm(const Mat<double, N, N>& A, Mat<double, N, N>& E, std::size_t n = N) {
  Mat<double, N, N> X = A;
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = 0; j < N; ++j) {
      if (i >= n || j >= n) {
        X.a[i][j] = 0.0;
      }
    }
  }
  const double nrm = X.norm1();
  if (!std::isfinite(nrm)) {
    return false;
  }
  int s = 0;
  double scaled = nrm;
  while (scaled > 0.5 && s < 1000) {
    scaled *= 0.5;
    ++s;
  }
  X *= std::ldexp(1.0, -s);
  // In place, with one product buffer: the stack holds 5 matrices (and lu_solve's copies), not
  // one per temporary of the expressions (the arithmetic of each entry is the same).
  constexpr int kQ = 6;
  double c = 0.5;
  Mat<double, N, N> num{};
  Mat<double, N, N> den{};
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = 0; j < N; ++j) {
      const double id = i == j && i < n ? 1.0 : 0.0;
      const double t = X.a[i][j] * c;
      num.a[i][j] = id + t;
      den.a[i][j] = id - t;
    }
  }
  Mat<double, N, N> pw = X;
  Mat<double, N, N> tmp{};
  bool positive = true;
  for (int k = 2; k <= kQ; ++k) {
    c = c * static_cast<double>(kQ - k + 1) / static_cast<double>(k * (2 * kQ - k + 1));
    mul_into(pw, X, tmp);
    pw = tmp;
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t j = 0; j < N; ++j) {
        const double t = pw.a[i][j] * c;
        num.a[i][j] += t;
        den.a[i][j] = positive ? den.a[i][j] + t : den.a[i][j] - t;
      }
    }
    positive = !positive;
  }
  if (!lu_solve(den, num, E, n)) {
    return false;
  }
  for (int k = 0; k < s; ++k) {
    mul_into(E, E, tmp);
    E = tmp;
  }
  return true;
}

}  // namespace imu

#endif  // IMU_LINALG_HPP

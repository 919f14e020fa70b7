// The example's covariance check (Fig. 2), with the model's prediction computed exactly.
//
// Check: windows of n_avg + n_int samples. The bias estimate is the mean of the first n_avg
// samples, A = (1/n_avg) sum_{k<n_avg} z_k; then the error is integrated,
// I_j = Ts sum_{k=n_avg}^{n_avg+j-1} (z_k - A), j = 1..n_int (velocity error for an accelerometer).
// Over many windows the robust standard deviation of I_j (1.4826 MAD) is compared with the
// model's predicted standard deviation; the figure of merit is the ratio at the end, j = n_int.
//
// Exact prediction (derivation). The discrete model is x_{k+1} = Phi x_k + w_k (cov Qd),
// z_k = H x_k + v_k + (Q/Ts)(u_k - u_{k-1}) with v_k white (var r_white) and u_k unit white
// (quantization: white phase noise, see error_model.hpp). Augment the state with the previous
// quantization draw, the running bias estimate and the integral:
//     s_k = [x_k; u_{k-1}; A_k; I_k],   noise e_k = [w_k; v_k; u_k],  cov(e_k) = diag(Qd, r_white, 1)
// Averaging phase (k < n_avg):   x' = Phi x + w,  u' = u_k,
//                                A' = A + (H x - (Q/Ts) u_{k-1} + v_k + (Q/Ts) u_k) / n_avg,  I' = I
// Integration phase:             x' = Phi x + w,  u' = u_k,  A' = A,
//                                I' = I + Ts (H x - (Q/Ts) u_{k-1} + v_k + (Q/Ts) u_k - A)
// Both are linear, s' = F s + G e, so cov(s') = F cov(s) F^T + G cov(e) G^T exactly (no
// approximation beyond the model itself), starting from cov(s_0) = diag(P0, 1, 0, 0): x_0 from
// the model's prior (steady state for GM terms; the RRW/ramp prior cancels in z - A for the
// constant part). var(I_j) includes the error of the averaged bias estimate AND its correlation
// with the bias during integration: A and x are correlated through the shared x_k. The example's
// prediction ignores that; CovPrediction::kCorrelationIgnored reproduces the omission by zeroing
// the cross-covariance of A with every other state at the start of integration (A's own variance
// kept), to show what the omission costs.
//
// Cost: predict_integral_std O((n_avg + n_int) (n+3)^3) flops, once per model (3000 steps of a
// 4x4 for the example's model: ~0.2 ms on the host). integrate_window O(n_avg + n_int). robust_std O(n)
// expected (quickselect, in place). No heap, re-entrant.
#ifndef IMU_COVARIANCE_CHECK_HPP
#define IMU_COVARIANCE_CHECK_HPP

#include <cstddef>

#include "imu/error_model.hpp"

namespace imu {

enum class CovPrediction : unsigned char {
  kExact = 0,            ///< averaging error and its correlation with the bias included
  kCorrelationIgnored,   ///< the example's omission: A independent of the states at the switch
};

/// Predicted standard deviation of I_j for j = 1..n_int, written to std_out[0..n_int-1].
/// kBadParameter if n_avg == 0, n_int == 0, std_out is null or the model is invalid.
template <std::size_t kMaxStates>
[[nodiscard]] ModelStatus predict_integral_std(const DiscreteModel<kMaxStates>& model,
                                               std::size_t n_avg, std::size_t n_int,
                                               double* std_out,
                                               CovPrediction mode = CovPrediction::kExact);

/// One window of samples z[0 .. n_avg + n_int - 1]: traj_out[j-1] = I_j (see above).
void integrate_window(const double* z, std::size_t n_avg, std::size_t n_int, double ts_s,
                      double* traj_out);

/// 1.4826 * median(|v - median(v)|) of values[0..n-1] (the normal-consistent MAD). Reorders
/// `values` in place (no copy, no heap). Returns 0 for n == 0.
[[nodiscard]] double robust_std(double* values, std::size_t n);

}  // namespace imu

#endif  // IMU_COVARIANCE_CHECK_HPP

// Explicit instantiations: compiles the header-only filters and monitors under fw/'s rules
// (poisoned identifiers, -fno-exceptions, -fno-rtti) for the configurations the project uses.
#include "imu/averaged_kf.hpp"
#include "imu/bias_kf.hpp"
#include "imu/residual_monitor.hpp"

namespace imu {

template class ScalarBiasKf<float>;
template class ScalarBiasKf<double>;
template class KalmanFilter<float, 1>;
template class KalmanFilter<float, 2>;
template class KalmanFilter<float, 3>;
template class KalmanFilter<double, 2>;
template class KalmanFilter<double, 3>;
template KfStatus KalmanFilter<float, 2>::configure<6>(const DiscreteModel<6>&, double);
template KfStatus KalmanFilter<float, 3>::configure<6>(const DiscreteModel<6>&, double);
template KfStatus KalmanFilter<double, 3>::configure<6>(const DiscreteModel<6>&, double);
template class AveragedKf<float, 8>;
template class AveragedKf<double, 8>;
template KfStatus AveragedKf<float, 8>::configure<9>(const DiscreteModel<9>&, double);
template class WhitenessMonitor<4>;
template struct ResidualMonitors<4>;

}  // namespace imu

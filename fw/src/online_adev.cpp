// Explicit instantiations: compiles the header-only estimator under fw/'s rules (poisoned
// identifiers, -fno-exceptions, -fno-rtti) and gives the library the default configurations.
#include "imu/online_adev.hpp"

namespace imu {
template class OnlineAdev<8, 22>;
template class OnlineAdev<8, 24>;
template class MultiAdev<6, 8, 22>;
}  // namespace imu

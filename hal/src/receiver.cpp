// Explicit instantiation of the default Receiver, so the fw prelude's poison sees its body.
#include "imu/hal/receiver.hpp"

namespace imu::hal {
template class Receiver<8>;
}  // namespace imu::hal

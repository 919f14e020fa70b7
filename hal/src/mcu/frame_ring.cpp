// The MCU frame rings (imu/hal/mcu/frame_ring.hpp) compiled under the firmware rules on every
// build, host included: the ring code and the two ports' non-virtual members, instantiated at a
// typical capacity. The library's symbol check (imu_apply_fw_rules) then shows that nothing
// here needs the heap, exceptions or RTTI. The images instantiate their own capacities.
#include "imu/hal/mcu/frame_ring.hpp"

namespace imu::hal::mcu {

template class SpscRing<RxFrame, 16>;
template class SpscRing<CanFrame, 16>;
template bool IsrFrameSource<16>::push_from_isr(const CanFrame&, std::uint32_t, std::uint64_t);
template std::uint32_t IsrFrameSource<16>::overflows() const;
template bool RingFrameSink<16>::pop(CanFrame&);
template std::uint32_t RingFrameSink<16>::overflows() const;

}  // namespace imu::hal::mcu

// Bare-metal MCU backend: the Cortex-M core instructions a main loop needs (Armv7-M: M3, M4,
// M7), so that the code above the HAL names no instruction. Bare-metal builds only.
#ifndef IMU_HAL_MCU_CORTEX_M_HPP
#define IMU_HAL_MCU_CORTEX_M_HPP

namespace imu::hal::mcu {

/// Sleeps (WFI) until an interrupt, unless `work_pending()` is true. Interrupts are masked
/// (PRIMASK) around the check: an interrupt that arrives between the check and WFI still ends
/// the sleep and is taken once the mask is cleared, so no wake-up is lost. Main loop only;
/// `work_pending` runs with interrupts masked and must be short. O(1) plus the sleep.
template <class WorkPending>
inline void sleep_until_interrupt_unless(const WorkPending& work_pending) {
  asm volatile("cpsid i" ::: "memory");
  if (!work_pending()) {
    asm volatile("dsb\n\twfi" ::: "memory");
  }
  asm volatile("cpsie i" ::: "memory");
}

}  // namespace imu::hal::mcu

#endif  // IMU_HAL_MCU_CORTEX_M_HPP

// Reset and fault handlers and the vector table of the mps2-an386 board (Arm MPS2 with the AN386
// Cortex-M4F image; nothing here but the linker script's symbols ties it to the board, so it
// serves any Cortex-M4F board folder as a starting point). Contract: imu/hal/mcu/startup.hpp.
// Reset: enable the FPU, copy .data, zero .bss, paint the stack (for the high-water mark), run
// static constructors, call imu_m4_main(), then imu_m4_exit() with its return value. Faults
// call imu_m4_fault(). The image provides both: the test images exit through semihosting
// (toolchains/m4/src/semihost_exit.cpp), the production images through the board's fault hook
// (board_hooks.cpp).
// SysTick and PendSV handlers are weak (default: the fault handler), so an image may define
// them; external interrupt vectors (the board's, e.g. the CAN controller's) follow the 16 core
// vectors from input sections .isr_vector.irq (see mps2_an386.ld).
// No newlib crt0 (the image links with -nostartfiles), so nothing calls _sbrk or atexit.
#include <cstddef>
#include <cstdint>

#include "imu/hal/mcu/startup.hpp"

extern "C" {
// Linker script symbols: addresses only, never read as values.
extern std::uint32_t _sidata[];
extern std::uint32_t _sdata[];
extern std::uint32_t _edata[];
extern std::uint32_t _sbss[];
extern std::uint32_t _ebss[];
extern std::uint32_t _sstack[];
extern std::uint32_t _estack[];
// The linker's names for the constructor table (reserved identifiers, fixed by the toolchain).
extern void (*__init_array_start[])();  // NOLINT(bugprone-reserved-identifier)
extern void (*__init_array_end[])();    // NOLINT(bugprone-reserved-identifier)

[[noreturn]] void Reset_Handler();
[[noreturn]] void Fault_Handler();
void SysTick_Handler();
void PendSV_Handler();
}

namespace {

constexpr std::uint32_t kStackPaint = 0xA5A5A5A5u;
constexpr std::uintptr_t kScbCpacr = 0xE000ED88u;  // Coprocessor Access Control Register
constexpr std::uint32_t kCp10Cp11Full = 0xFu << 20;

using Vector = void (*)();

}  // namespace

// Vector table: initial stack pointer, then the handlers (Cortex-M exceptions 1..15).
// The stack pointer entry is an address, not a function: the cast is what every Cortex-M
// startup does; it is resolved by the linker.
__attribute__((section(".isr_vector"), used)) const Vector g_vector_table[16] = {
    reinterpret_cast<Vector>(_estack),  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
    Reset_Handler,  Fault_Handler,  Fault_Handler, Fault_Handler, Fault_Handler, Fault_Handler,
    nullptr,        nullptr,        nullptr,       nullptr,
    Fault_Handler,  // SVCall
    Fault_Handler,  // DebugMonitor
    nullptr,
    PendSV_Handler,
    SysTick_Handler,
};

void Reset_Handler() {
  // 1. FPU: full access to CP10/CP11 before any floating-point instruction.
  auto* cpacr = reinterpret_cast<volatile std::uint32_t*>(kScbCpacr);  // NOLINT
  *cpacr = *cpacr | kCp10Cp11Full;
  asm volatile("dsb\n\tisb" ::: "memory");
  // 2. .data from its load address in flash, .bss to zero.
  for (std::uint32_t *src = _sidata, *dst = _sdata; dst < _edata; ++src, ++dst) {
    *dst = *src;
  }
  for (std::uint32_t* dst = _sbss; dst < _ebss; ++dst) {
    *dst = 0;
  }
  // 3. Paint the stack below the current frame (64 bytes of margin for this function).
  std::uint32_t* sp = nullptr;
  asm volatile("mov %0, sp" : "=r"(sp));
  for (std::uint32_t* p = _sstack; p < sp - 16; ++p) {
    *p = kStackPaint;
  }
  // 4. Static constructors.
  for (Vector* f = __init_array_start; f < __init_array_end; ++f) {
    (*f)();
  }
  imu_m4_exit(imu_m4_main());
}

void Fault_Handler() { imu_m4_fault(); }

// Weak: an image that uses SysTick or PendSV defines its own.
__attribute__((weak)) void SysTick_Handler() { imu_m4_fault(); }
__attribute__((weak)) void PendSV_Handler() { imu_m4_fault(); }

namespace imu::hal::mcu {

std::size_t stack_high_water_bytes() {
  const std::uint32_t* p = _sstack;
  while (p < _estack && *p == kStackPaint) {
    ++p;
  }
  return static_cast<std::size_t>(_estack - p) * sizeof(std::uint32_t);
}

std::size_t stack_size_bytes() {
  return static_cast<std::size_t>(_estack - _sstack) * sizeof(std::uint32_t);
}

}  // namespace imu::hal::mcu

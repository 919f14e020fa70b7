// Bare-metal MCU backend: the contract between the production node image and the board.
//
// The image (e.g. imu_m4_node_prod.elf) holds the node's MCU main loop (fw/node/src/
// mcu_main.cpp: one imu::node::Node for six channels, an interrupt-fed receive ring and a
// telemetry ring, imu/hal/mcu/frame_ring.hpp), which hands received frames to the node, passes
// telemetry to the CAN controller and sleeps (WFI) when there is nothing to do. The board code
// implements the hooks below (hal/src/mcu/boards/<board>/board_hooks.cpp); mps2-an386's defines
// each one weak, with the default said here, so that a board shim linked beside it replaces it.
//
// Contexts: imu_node_can_rx is called from ONE interrupt (the CAN receive interrupt; or any one
// context, but only one). Every imu_board_* hook is called from the main loop, except
// imu_board_fault (from a fault handler).
//
// Interrupt vectors: the 16 Cortex-M core vectors are in the board's startup.cpp
// (hal/src/mcu/boards/mps2_an386/startup.cpp; SysTick_Handler and PendSV_Handler are weak and
// may be defined by the board). The board adds its external interrupts as an array of handlers
// in section ".isr_vector.irq", placed right after the core vectors (entry k = IRQ k), e.g.
//   extern "C" __attribute__((section(".isr_vector.irq"), used))
//   void (*const g_board_irqs[])() = { ..., can1_rx0_isr, ... };
#ifndef IMU_HAL_MCU_BOARD_HOOKS_HPP
#define IMU_HAL_MCU_BOARD_HOOKS_HPP

#include <cstdint>

#include "imu/hal/codec.hpp"

/// Provided by the node's MCU main loop (fw/node/src/mcu_main.cpp), called by the board's CAN
/// receive interrupt for every frame: nbytes is kCanMtu (16) for a classic frame or kCanFdMtu
/// (72) for an FD frame, rx_time_ns the receive time (any monotonic clock; the node uses
/// differences only). Returns false when the receive ring is full: the frame is dropped and
/// counted, and the count goes out in the node's statistics telemetry
/// (StatsRecord::kernel_drops). O(1), lock-free.
bool imu_node_can_rx(const imu::hal::CanFrame& f, std::uint32_t nbytes, std::uint64_t rx_time_ns);

/// Clocks, pins, everything but the CAN controller. Called first. Default: nothing.
void imu_board_init();

/// CAN controller: bit timing, acceptance filters (the node's identifiers: hal/README.md), the
/// receive interrupt (whose handler calls imu_node_can_rx) and the transmit-complete interrupt
/// (its handler only needs to return: the interrupt wakes the main loop, which passes the next
/// queued frame on). Called after the node is configured. Default: nothing (no frames).
void imu_board_can_init();

/// Hands one telemetry frame to the controller. True if it took the frame (a mailbox / FIFO
/// slot was free), false if it is busy: the frame stays queued and is offered again. Must not
/// block for long: the main loop calls it while the node may be waiting for room.
/// Default: false (nothing leaves; telemetry that does not fit the ring is counted as lost).
bool imu_board_can_send(const imu::hal::CanFrame& f);

/// Milliseconds since reset, wrapping at 2^32. Used for the bus-idle flush (200 ms without a
/// frame: the node sends its full telemetry set) and to bound the wait for a free mailbox. The
/// clock's tick interrupt must also wake the core from WFI, or the idle flush waits for the
/// next frame. Default: always 0 (no clock: no idle flush; full sets follow the node's
/// adev_period_samples only).
std::uint32_t imu_board_millis();

/// A processor fault, or the node refused its configuration. Must not return.
/// Default: a system reset (SCB AIRCR SYSRESETREQ).
[[noreturn]] void imu_board_fault();

#endif  // IMU_HAL_MCU_BOARD_HOOKS_HPP

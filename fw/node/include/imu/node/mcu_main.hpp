// The node's main loop on a bare-metal MCU (imu_node_mcu, src/mcu_main.cpp): one
// imu::node::Node for six channels fed by the CAN receive interrupt through a lock-free ring,
// telemetry through a second ring to the CAN controller, WFI when idle. Built only with a
// bare-metal toolchain; the board implements imu/hal/mcu/board_hooks.hpp and provides the
// startup (imu/hal/mcu/startup.hpp: the reset handler calls this loop as imu_m4_main).
// What a board shim or a debugger may read while the image runs: the node and the rings'
// counters.
#ifndef IMU_NODE_MCU_MAIN_HPP
#define IMU_NODE_MCU_MAIN_HPP

#include <cstddef>
#include <cstdint>

#include "imu/node/node.hpp"

namespace imu::node::mcu {

inline constexpr std::size_t kRxFrames = 16;   ///< receive ring (frames)
inline constexpr std::size_t kTxFrames = 16;   ///< telemetry ring (frames)
inline constexpr std::uint32_t kIdleMs = 200;  ///< bus idle: Node::on_idle()

struct LoopCounters {
  std::uint32_t rx_pending;
  std::uint32_t rx_overflows;  ///< frames dropped: receive ring full
  std::uint32_t tx_pending;
  std::uint32_t tx_overflows;  ///< telemetry frames refused: ring full after the wait
  std::uint32_t idle_flushes;  ///< Node::on_idle() calls
};

/// The image's node (read only; the main loop is its only writer).
[[nodiscard]] const Node& image_node();
/// A snapshot of the rings' counters. Any context.
[[nodiscard]] LoopCounters loop_counters();

}  // namespace imu::node::mcu

#endif  // IMU_NODE_MCU_MAIN_HPP

// The production node image (node_prod.cpp): one imu::node::Node for six channels fed by the
// CAN receive interrupt through a lock-free ring, telemetry through a second ring to the CAN
// controller, WFI when idle. The board implements imu/hal/mcu/board_hooks.hpp. What a board
// shim or a debugger may read while the image runs: the node and the rings' counters.
#ifndef IMU_M4_NODE_PROD_HPP
#define IMU_M4_NODE_PROD_HPP

#include <cstddef>
#include <cstdint>

#include "imu/node/node.hpp"

namespace imu::m4 {

inline constexpr std::size_t kProdRxFrames = 16;  ///< receive ring (frames)
inline constexpr std::size_t kProdTxFrames = 16;  ///< telemetry ring (frames)
inline constexpr std::uint32_t kProdIdleMs = 200;  ///< bus idle: Node::on_idle()

struct ProdCounters {
  std::uint32_t rx_pending;
  std::uint32_t rx_overflows;  ///< frames dropped: receive ring full
  std::uint32_t tx_pending;
  std::uint32_t tx_overflows;  ///< telemetry frames refused: ring full after the wait
  std::uint32_t idle_flushes;  ///< Node::on_idle() calls
};

/// The image's node (read only; the main loop is its only writer).
[[nodiscard]] const node::Node& prod_node();
/// A snapshot of the rings' counters. Any context.
[[nodiscard]] ProdCounters prod_counters();

}  // namespace imu::m4

#endif  // IMU_M4_NODE_PROD_HPP

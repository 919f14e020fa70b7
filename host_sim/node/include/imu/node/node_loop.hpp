// The Linux loop around the node core: read frames from a bus (CanSocket: SocketCAN or the
// loopback socket) in batches, hand them to Node, call Node::on_idle() when the bus is idle, and
// decide when the stream has ended. Shared by the imu-fw executable and imu-sim's in-process
// node. Host code (uses the OS through imu_hal_linux); never throws.
#ifndef IMU_NODE_NODE_LOOP_HPP
#define IMU_NODE_NODE_LOOP_HPP

#include <atomic>
#include <cstdint>

#include "imu/hal/linux/can_socket.hpp"
#include "imu/node/node.hpp"

namespace imu::node {

struct LoopOptions {
  int idle_ms = 200;       ///< no frame for this long: Node::on_idle() (flush + final telemetry)
  int exit_idle_ms = 0;    ///< stop after this long without frames once samples came (0: never)
  bool exit_on_link_down = true;  ///< the loopback peer closed after samples: stream ended
  /// No frame from the peer for this long, whether it is connected and silent, gone, or never
  /// came: kPeerTimeout (0: never). Counted from the start and from the last frame.
  int peer_timeout_ms = 0;
  const std::atomic<bool>* stop = nullptr;  ///< polled between batches (e.g. set by SIGINT)
};

enum class LoopEnd : std::uint8_t {
  kLinkDown,  ///< the peer closed the loopback link after sending samples
  kIdle,      ///< exit_idle_ms passed without frames after samples
  kStopped,   ///< *stop became true
  kError,     ///< a transport error other than timeout / link down; see the socket's error()
  kPeerTimeout,  ///< peer_timeout_ms passed without a frame (the peer is gone)
};

[[nodiscard]] const char* to_string(LoopEnd e);

/// Run until the stream ends. Calls node.finish() before returning (except for kError). After
/// every batch it passes the socket's kernel_drops and peer_refused to node.set_link_counters.
/// Cost: one poll + one recvmmsg per batch of up to 64 frames.
[[nodiscard]] LoopEnd run_node_loop(Node& node, hal::CanSocket& bus, const LoopOptions& opt);

}  // namespace imu::node

#endif  // IMU_NODE_NODE_LOOP_HPP

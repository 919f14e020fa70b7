// Narrow frame I/O interfaces of the Linux HAL: a frame source and a frame sink, both carrying
// CanFrame (struct canfd_frame bytes). Backends: SocketCAN and the loopback socket (CanSocket).
// No exceptions cross these interfaces: every call returns an IoStatus and counts in LinkStats.
#ifndef IMU_HAL_FRAME_IO_HPP
#define IMU_HAL_FRAME_IO_HPP

#include <cstddef>
#include <cstdint>

#include "imu/hal/codec.hpp"

namespace imu::hal {

enum class IoStatus : std::uint8_t {
  kOk,
  kTimeout,          ///< nothing received / no room to send within the timeout
  kWouldBlock,       ///< send: back-pressure (EAGAIN / ENOBUFS) outlasted the timeout
  kLinkDown,         ///< ENETDOWN, peer gone, not connected: retried on the next call
  kNoSuchInterface,  ///< open: the named CAN interface does not exist
  kNotSupported,     ///< open: the kernel has no AF_CAN; send: FD frame on a classic interface
  kBadArgument,
  kNotOpen,
  kSysError,         ///< any other errno: LinkStats::last_errno and error() say which
};

/// Short constant name of a status, e.g. "link-down".
[[nodiscard]] const char* to_string(IoStatus s);

/// One received frame: the bytes, how many the kernel delivered (CAN_MTU or CANFD_MTU when
/// well formed; anything else is passed on for Receiver to count as bad_mtu; a frame longer
/// than 72 bytes is reported as 73), and the receive time in ns since the Unix epoch
/// (kernel SO_TIMESTAMPNS when available, else read at batch time: rx_no_timestamp counts it).
struct RxFrame {
  CanFrame frame;
  std::uint32_t nbytes;
  std::uint64_t rx_time_ns;
};

/// Transport counters. Nothing is dropped without being counted here or in RxStats.
struct LinkStats {
  std::uint64_t rx_frames = 0;
  std::uint64_t rx_batches = 0;       ///< recvmmsg calls that returned frames
  std::uint64_t rx_truncated = 0;     ///< message longer than a canfd_frame (MSG_TRUNC)
  std::uint64_t rx_no_timestamp = 0;  ///< frames without a kernel timestamp
  std::uint64_t kernel_drops = 0;     ///< SO_RXQ_OVFL: frames the kernel dropped (cumulative)
  std::uint64_t link_down = 0;        ///< link lost: ENETDOWN, ENODEV, peer closed
  std::uint64_t link_up = 0;          ///< link (re)established after open or a loss
  std::uint64_t reconnect_attempts = 0;
  std::uint64_t tx_frames = 0;
  std::uint64_t tx_backpressure = 0;  ///< sends that met EAGAIN / ENOBUFS at least once
  std::uint64_t tx_would_block = 0;   ///< sends given up after the timeout (kWouldBlock)
  std::uint64_t tx_link_down = 0;     ///< sends refused because the link was down
  std::uint64_t tx_stall_disconnects = 0;  ///< loopback peers dropped: not reading (stalled)
  std::uint64_t sys_errors = 0;
  std::uint64_t peer_refused = 0;     ///< loopback peers of another user id, closed unread
  int last_errno = 0;
};

/// Something frames come from. receive() waits at most timeout_ms (0: do not wait, -1:
/// forever) with poll, then takes up to `cap` frames in one batch; n is the number taken.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  [[nodiscard]] virtual IoStatus receive(RxFrame* out, std::size_t cap, std::size_t& n,
                                         int timeout_ms) = 0;
};

/// Something frames go to. send() writes one frame (wire_size(f) bytes); on back-pressure it
/// waits for POLLOUT up to timeout_ms, then returns kWouldBlock (counted).
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  [[nodiscard]] virtual IoStatus send(const CanFrame& f, int timeout_ms) = 0;
};

}  // namespace imu::hal

#endif  // IMU_HAL_FRAME_IO_HPP

// CanSocket: the one socket-based frame source/sink of the Linux HAL, with two backends chosen
// at run time by name, sharing every line of the read and write path (poll + recvmmsg,
// SO_TIMESTAMPNS, SO_RXQ_OVFL, EAGAIN/ENOBUFS back-pressure):
//
//   "vcan0", "can0", any interface name   SocketCAN raw socket bound to that interface,
//                                         CAN_RAW_FD_FRAMES on, every error class reported
//                                         (CAN_RAW_ERR_FILTER = CAN_ERR_MASK), non-blocking.
//   "loopback" or "loopback:NAME"         AF_UNIX SOCK_SEQPACKET in the abstract namespace
//                                         "imu-can-loopback:NAME" (NAME defaults to "default"):
//                                         the first process to open it listens, the second
//                                         connects; frames keep their boundaries and the same
//                                         16/72 bytes as SocketCAN. Point to point (2 nodes).
//   open_pair(a, b)                       two sockets of an in-process socketpair (tests).
//
// Link loss (ENETDOWN/ENODEV on CAN, peer closed on loopback) is returned as kLinkDown and
// counted; the next call retries (CAN: rebinds by name if the interface was re-created;
// loopback: reconnects or accepts a new peer). Not thread-safe on one instance; one reader
// thread and one writer thread may use two instances opened on the same bus.
#ifndef IMU_HAL_CAN_SOCKET_HPP
#define IMU_HAL_CAN_SOCKET_HPP

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "imu/hal/frame_io.hpp"

namespace imu::hal {

enum class BusKind : std::uint8_t { kNone, kSocketCan, kLoopback };

struct BusOptions {
  int rcvbuf_bytes = 1 << 20;  ///< SO_RCVBUF request (the kernel may cap it at rmem_max)
  /// Loopback listener only (the node's side): a peer that has taken no frame for this long
  /// while sends wait on it (it stopped reading) is disconnected (counted in
  /// LinkStats::tx_stall_disconnects), so a stuck peer cannot hold the node. 0: never.
  int tx_stall_limit_ms = 10000;
  /// While set, a send waiting on back-pressure gives up at once (kWouldBlock): the owner's
  /// stop flag (SIGTERM), so a peer that does not read cannot delay a stop. May be null.
  const std::atomic<bool>* abort_wait = nullptr;
};

class CanSocket final : public FrameSource, public FrameSink {
 public:
  static constexpr std::size_t kMaxBatch = 64;  ///< frames per recvmmsg call

  CanSocket() = default;
  ~CanSocket() override;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;
  CanSocket(CanSocket&& other) noexcept;
  CanSocket& operator=(CanSocket&& other) noexcept;

  /// Open a bus by name (see above). Errors: kNoSuchInterface, kNotSupported (no AF_CAN),
  /// kBadArgument (empty or too long name), kSysError; error() has the text.
  [[nodiscard]] IoStatus open(const char* bus, const BusOptions& opt = BusOptions{});
  /// Two connected in-process loopback ends.
  [[nodiscard]] static IoStatus open_pair(CanSocket& a, CanSocket& b);
  void close();

  /// See FrameSource. At most kMaxBatch frames per call. kLinkDown when the link went away.
  [[nodiscard]] IoStatus receive(RxFrame* out, std::size_t cap, std::size_t& n,
                                 int timeout_ms) override;
  /// See FrameSink. kNotSupported for an FD frame on a classic-only interface.
  [[nodiscard]] IoStatus send(const CanFrame& f, int timeout_ms) override;
  /// Write arbitrary bytes as one frame (tests of malformed input; loopback only).
  [[nodiscard]] IoStatus send_raw(const void* bytes, std::size_t nbytes, int timeout_ms);

  [[nodiscard]] const LinkStats& stats() const { return stats_; }
  [[nodiscard]] BusKind kind() const { return kind_; }
  /// True when FD frames can be sent (CAN interface MTU 72, or loopback).
  [[nodiscard]] bool fd_capable() const { return fd_capable_; }
  /// True when the kernel accepted SO_TIMESTAMPNS on the data socket (rx_time_ns is the
  /// kernel's receive time); false: rx_time_ns is read by the reader at batch time.
  [[nodiscard]] bool kernel_timestamps() const { return kernel_ts_; }
  /// Human-readable text of the last failure, naming the bus ("" if none).
  [[nodiscard]] const char* error() const { return error_; }
  /// Descriptor to poll for input (the data socket, or the listening socket before a peer).
  [[nodiscard]] int poll_fd() const { return data_fd_ >= 0 ? data_fd_ : listen_fd_; }

 private:
  IoStatus open_can();
  IoStatus open_loopback();
  IoStatus ensure_link(int timeout_ms);
  IoStatus link_lost(int err);
  IoStatus fail(IoStatus s, int err, const char* what);
  IoStatus write_bytes(const void* bytes, std::size_t nbytes, int timeout_ms);
  IoStatus stalled();
  void move_from(CanSocket& other) noexcept;

  BusKind kind_ = BusKind::kNone;
  int data_fd_ = -1;    // socket carrying frames
  int listen_fd_ = -1;  // loopback listener (the side that opened first)
  bool connector_ = false;  // loopback side that connects
  bool pair_ = false;       // in-process pair: no reconnection possible
  bool fd_capable_ = false;
  bool kernel_ts_ = false;
  bool down_ = false;
  bool tx_broken_ = false;  // loopback: a send met the closed peer; receive() drains, then closes
  bool rx_eof_pending_ = false;  // loopback: a send closed the ended link; receive() reports it
  BusOptions opt_{};
  std::int64_t stall_since_ms_ = -1;  // first send given up on the current peer's stall, or -1
  bool peer_lost_ = false;  // a listener lost its peer: sends do not wait for the next one
  char name_[64] = {};
  char error_[160] = {};
  LinkStats stats_{};
};

}  // namespace imu::hal

#endif  // IMU_HAL_CAN_SOCKET_HPP

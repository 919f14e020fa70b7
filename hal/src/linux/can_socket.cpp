// CanSocket: SocketCAN and AF_UNIX SEQPACKET loopback behind one read/write path.
#include "imu/hal/linux/can_socket.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace imu::hal {

// The codec mirrors the kernel's frame and flags without including Linux headers: prove it.
static_assert(sizeof(struct canfd_frame) == sizeof(CanFrame), "frame layout");
static_assert(offsetof(struct canfd_frame, data) == offsetof(CanFrame, data), "frame layout");
static_assert(offsetof(struct canfd_frame, len) == offsetof(CanFrame, len), "frame layout");
static_assert(offsetof(struct canfd_frame, flags) == offsetof(CanFrame, flags), "frame layout");
static_assert(CAN_MTU == kCanMtu && CANFD_MTU == kCanFdMtu, "MTU");
static_assert(CAN_EFF_FLAG == kCanEffFlag && CAN_RTR_FLAG == kCanRtrFlag, "flags");
static_assert(CAN_ERR_FLAG == kCanErrFlag && CAN_ERR_MASK == kCanErrMask, "flags");
static_assert(CANFD_BRS == kCanFdBrs && CANFD_ESI == kCanFdEsi, "flags");
static_assert(CAN_ERR_TX_TIMEOUT == 0x1U && CAN_ERR_RESTARTED == 0x100U, "error classes");

namespace {

constexpr std::size_t kCtrlLen = 64;  // room for SCM_TIMESTAMPNS + SO_RXQ_OVFL

std::uint64_t now_realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ULL +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

std::int64_t now_monotonic_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1'000'000;
}

bool is_link_error(int err) {
  return err == ENETDOWN || err == ENODEV || err == ENXIO || err == EPIPE ||
         err == ECONNRESET || err == ENOTCONN;
}

bool set_int_opt(int fd, int level, int name, int value) {
  return setsockopt(fd, level, name, &value, sizeof value) == 0;
}

/// Best effort: without an option the socket still works, with fewer diagnostics (no kernel
/// timestamps: rx_no_timestamp counts; no SO_RXQ_OVFL: kernel_drops stays 0). Returns whether
/// kernel receive timestamps are on (qemu-user, for one, refuses SO_TIMESTAMPNS).
bool configure_data_fd(int fd, const BusOptions& opt) {
  const bool stamps = set_int_opt(fd, SOL_SOCKET, SO_TIMESTAMPNS, 1);
  (void)set_int_opt(fd, SOL_SOCKET, SO_RXQ_OVFL, 1);
  (void)set_int_opt(fd, SOL_SOCKET, SO_RCVBUF, opt.rcvbuf_bytes);
  return stamps;
}

/// The loopback name lives in the abstract namespace, which any process of the network
/// namespace can bind or connect to whatever its user: the credentials of the other end
/// (SO_PEERCRED: the listener's at connect, the connector's at accept) must be our own
/// effective uid, else the socket is closed unread. Returns the peer's uid in `uid`.
bool peer_is_same_user(int fd, uid_t& uid) {
  ucred cred{};
  socklen_t len = sizeof cred;
  if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) != 0 || len != sizeof cred) {
    uid = static_cast<uid_t>(-1);
    return false;
  }
  uid = cred.uid;
  return cred.uid == geteuid();
}

socklen_t loopback_address(const char* name, sockaddr_un& addr) {
  std::memset(&addr, 0, sizeof addr);
  addr.sun_family = AF_UNIX;
  // Abstract namespace: sun_path[0] = 0, no file system entry, gone when the socket closes.
  const int len = std::snprintf(addr.sun_path + 1, sizeof addr.sun_path - 1,
                                "imu-can-loopback:%s", name);
  return static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 +
                                static_cast<std::size_t>(len));
}

// A received message's control data: the kernel's receive time (false when it sent none)
// and the socket's cumulative count of frames the kernel dropped (SO_RXQ_OVFL), when present.
bool read_control(const msghdr& h, std::uint64_t& rx_time_ns, std::uint64_t& kernel_drops) {
  bool stamped = false;
  for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr;
       c = CMSG_NXTHDR(const_cast<msghdr*>(&h), c)) {
    if (c->cmsg_level != SOL_SOCKET) {
      continue;
    }
    if (c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      rx_time_ns = static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ULL +
                   static_cast<std::uint64_t>(ts.tv_nsec);
      stamped = true;
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t drops = 0;
      std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
      kernel_drops = drops;
    }
  }
  return stamped;
}

}  // namespace

const char* to_string(IoStatus s) {
  switch (s) {
    case IoStatus::kOk: return "ok";
    case IoStatus::kTimeout: return "timeout";
    case IoStatus::kWouldBlock: return "would-block";
    case IoStatus::kLinkDown: return "link-down";
    case IoStatus::kNoSuchInterface: return "no-such-interface";
    case IoStatus::kNotSupported: return "not-supported";
    case IoStatus::kBadArgument: return "bad-argument";
    case IoStatus::kNotOpen: return "not-open";
    case IoStatus::kSysError: return "system-error";
  }
  return "?";
}

CanSocket::~CanSocket() { close(); }

CanSocket::CanSocket(CanSocket&& other) noexcept { move_from(other); }

CanSocket& CanSocket::operator=(CanSocket&& other) noexcept {
  if (this != &other) {
    close();
    move_from(other);
  }
  return *this;
}

void CanSocket::move_from(CanSocket& other) noexcept {
  kind_ = other.kind_;
  data_fd_ = other.data_fd_;
  listen_fd_ = other.listen_fd_;
  connector_ = other.connector_;
  pair_ = other.pair_;
  fd_capable_ = other.fd_capable_;
  kernel_ts_ = other.kernel_ts_;
  down_ = other.down_;
  tx_broken_ = other.tx_broken_;
  rx_eof_pending_ = other.rx_eof_pending_;
  opt_ = other.opt_;
  stall_since_ms_ = other.stall_since_ms_;
  peer_lost_ = other.peer_lost_;
  std::memcpy(name_, other.name_, sizeof name_);
  std::memcpy(error_, other.error_, sizeof error_);
  stats_ = other.stats_;
  other.data_fd_ = -1;
  other.listen_fd_ = -1;
  other.kind_ = BusKind::kNone;
}

void CanSocket::close() {
  if (data_fd_ >= 0) {
    ::close(data_fd_);
    data_fd_ = -1;
  }
  if (listen_fd_ >= 0) {
    ::close(listen_fd_);
    listen_fd_ = -1;
  }
  kind_ = BusKind::kNone;
  tx_broken_ = false;
  rx_eof_pending_ = false;
}

IoStatus CanSocket::fail(IoStatus s, int err, const char* what) {
  stats_.last_errno = err;
  if (s == IoStatus::kSysError) {
    ++stats_.sys_errors;
  }
  if (err != 0) {
    std::snprintf(error_, sizeof error_, "bus '%s': %s: %s", name_, what, std::strerror(err));
  } else {
    std::snprintf(error_, sizeof error_, "bus '%s': %s", name_, what);
  }
  return s;
}

IoStatus CanSocket::open(const char* bus, const BusOptions& opt) {
  close();
  stats_ = LinkStats{};
  error_[0] = '\0';
  pair_ = false;
  connector_ = false;
  down_ = false;
  opt_ = opt;
  if (bus == nullptr || bus[0] == '\0' || std::strlen(bus) >= sizeof name_) {
    std::snprintf(name_, sizeof name_, "%s", "");
    return fail(IoStatus::kBadArgument, 0, "empty or too long bus name");
  }
  if (std::strncmp(bus, "loopback", 8) == 0 && (bus[8] == '\0' || bus[8] == ':')) {
    std::snprintf(name_, sizeof name_, "%s", bus[8] == ':' && bus[9] != '\0' ? bus + 9 : "default");
    kind_ = BusKind::kLoopback;
    fd_capable_ = true;
    const IoStatus s = open_loopback();
    if (s != IoStatus::kOk) {
      close();
    }
    return s;
  }
  std::snprintf(name_, sizeof name_, "%s", bus);
  kind_ = BusKind::kSocketCan;
  const IoStatus s = open_can();
  if (s != IoStatus::kOk) {
    close();
  }
  return s;
}

IoStatus CanSocket::open_can() {
  if (std::strlen(name_) >= IFNAMSIZ) {
    return fail(IoStatus::kBadArgument, 0, "interface name longer than IFNAMSIZ-1");
  }
  const unsigned ifindex = if_nametoindex(name_);
  if (ifindex == 0) {
    return fail(IoStatus::kNoSuchInterface, errno, "no such network interface");
  }
  const int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
      return fail(IoStatus::kNotSupported, err, "this kernel has no SocketCAN (socket(AF_CAN))");
    }
    return fail(IoStatus::kSysError, err, "socket(AF_CAN)");
  }
  // Configure and bind a local descriptor; it becomes data_fd_ only once it is usable, so a
  // failed re-bind after ENODEV never leaves a half-open socket behind.
  const int on = 1;
  const bool fd_frames = setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) == 0;
  const can_err_mask_t err_mask = CAN_ERR_MASK;
  if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0) {
    const int err = errno;
    ::close(fd);
    return fail(IoStatus::kSysError, err, "setsockopt(CAN_RAW_ERR_FILTER)");
  }
  const bool stamps = configure_data_fd(fd, opt_);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(ifindex);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int err = errno;
    ::close(fd);
    return fail(err == ENODEV ? IoStatus::kNoSuchInterface : IoStatus::kSysError, err, "bind");
  }
  ifreq ifr{};
  std::snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", name_);
  fd_capable_ = fd_frames && ioctl(fd, SIOCGIFMTU, &ifr) == 0 && ifr.ifr_mtu == CANFD_MTU;
  kernel_ts_ = stamps;
  data_fd_ = fd;
  ++stats_.link_up;
  return IoStatus::kOk;
}

IoStatus CanSocket::open_loopback() {
  sockaddr_un addr{};
  const socklen_t len = loopback_address(name_, addr);
  for (int attempt = 0; attempt < 3; ++attempt) {
    int fd = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
      return fail(IoStatus::kSysError, errno, "socket(AF_UNIX)");
    }
    if (connect(fd, reinterpret_cast<const sockaddr*>(&addr), len) == 0) {
      uid_t uid = 0;
      if (!peer_is_same_user(fd, uid)) {
        ::close(fd);
        ++stats_.peer_refused;
        char what[64];
        std::snprintf(what, sizeof what, "name held by uid %lu, we are %lu: refused",
                      static_cast<unsigned long>(uid), static_cast<unsigned long>(geteuid()));
        return fail(IoStatus::kSysError, 0, what);
      }
      peer_lost_ = false;
  kernel_ts_ = configure_data_fd(fd, opt_);
      data_fd_ = fd;
      connector_ = true;
      ++stats_.link_up;
      return IoStatus::kOk;
    }
    int err = errno;
    ::close(fd);
    if (err != ECONNREFUSED && err != ENOENT) {
      return fail(IoStatus::kSysError, err, "connect");
    }
    fd = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
      return fail(IoStatus::kSysError, errno, "socket(AF_UNIX)");
    }
    if (bind(fd, reinterpret_cast<const sockaddr*>(&addr), len) == 0 && listen(fd, 4) == 0) {
      listen_fd_ = fd;
      connector_ = false;
      return IoStatus::kOk;  // link comes up when the peer connects
    }
    err = errno;
    ::close(fd);
    if (err != EADDRINUSE) {
      return fail(IoStatus::kSysError, err, "bind/listen");
    }
    // Another process became the listener between our connect and bind: connect again.
  }
  return fail(IoStatus::kSysError, EADDRINUSE, "loopback name contended");
}

IoStatus CanSocket::open_pair(CanSocket& a, CanSocket& b) {
  a.close();
  b.close();
  int sv[2] = {-1, -1};
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, sv) != 0) {
    std::snprintf(a.name_, sizeof a.name_, "%s", "pair");
    return a.fail(IoStatus::kSysError, errno, "socketpair");
  }
  CanSocket* ends[2] = {&a, &b};
  for (int i = 0; i < 2; ++i) {
    CanSocket& s = *ends[i];
    s.stats_ = LinkStats{};
    s.error_[0] = '\0';
    std::snprintf(s.name_, sizeof s.name_, "pair.%d", i);
    s.kind_ = BusKind::kLoopback;
    s.pair_ = true;
    s.connector_ = false;
    s.fd_capable_ = true;
    s.down_ = false;
    s.data_fd_ = sv[i];
    s.kernel_ts_ = configure_data_fd(sv[i], s.opt_);
    ++s.stats_.link_up;
  }
  return IoStatus::kOk;
}

IoStatus CanSocket::link_lost(int err) {
  if (!tx_broken_) {
    ++stats_.link_down;  // else a send that met the closed peer has counted this loss
  }
  fail(IoStatus::kLinkDown, err, "link down");
  if (kind_ == BusKind::kSocketCan) {
    if (err == ENODEV || err == ENXIO) {
      ::close(data_fd_);  // interface removed: rebind by name on the next call
      data_fd_ = -1;
    }
    down_ = true;
  } else if (!pair_) {
    ::close(data_fd_);  // peer gone: reconnect or accept a new peer on the next call
    data_fd_ = -1;
    tx_broken_ = false;
    peer_lost_ = listen_fd_ >= 0;
  } else {
    down_ = true;  // in-process pair: the other end is closed for good
  }
  return IoStatus::kLinkDown;
}

IoStatus CanSocket::ensure_link(int timeout_ms) {
  if (kind_ == BusKind::kNone) {
    return IoStatus::kNotOpen;
  }
  if (data_fd_ >= 0) {
    return pair_ && down_ ? IoStatus::kLinkDown : IoStatus::kOk;
  }
  if (pair_) {
    return IoStatus::kLinkDown;
  }
  if (kind_ == BusKind::kSocketCan) {
    ++stats_.reconnect_attempts;
    return open_can() == IoStatus::kOk ? IoStatus::kOk : IoStatus::kLinkDown;
  }
  if (listen_fd_ < 0) {  // loopback connector whose peer went away: connect or listen again
    ++stats_.reconnect_attempts;
    if (open_loopback() != IoStatus::kOk) {
      return IoStatus::kLinkDown;
    }
    if (data_fd_ >= 0) {
      return IoStatus::kOk;
    }
  }
  // Listening side without a peer: accept one, waiting at most timeout_ms.
  int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && timeout_ms != 0) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) > 0) {
      fd = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    }
  }
  if (fd < 0) {
    return IoStatus::kTimeout;
  }
  uid_t uid = 0;
  if (!peer_is_same_user(fd, uid)) {
    ::close(fd);  // another user's process connected to our name: never read from or write to it
    ++stats_.peer_refused;
    return IoStatus::kTimeout;
  }
  peer_lost_ = false;
  kernel_ts_ = configure_data_fd(fd, opt_);
  data_fd_ = fd;
  ++stats_.link_up;
  return IoStatus::kOk;
}

IoStatus CanSocket::receive(RxFrame* out, std::size_t cap, std::size_t& n, int timeout_ms) {
  n = 0;
  if (out == nullptr || cap == 0) {
    return IoStatus::kBadArgument;
  }
  if (rx_eof_pending_) {  // the loopback peer's end was met (and counted) by a send
    rx_eof_pending_ = false;
    return IoStatus::kLinkDown;
  }
  const IoStatus link = ensure_link(timeout_ms);
  if (link != IoStatus::kOk) {
    return link;
  }
  if (cap > kMaxBatch) {
    cap = kMaxBatch;
  }
  pollfd p{data_fd_, POLLIN, 0};
  const int pr = poll(&p, 1, timeout_ms);
  if (pr < 0) {
    return errno == EINTR ? IoStatus::kTimeout : fail(IoStatus::kSysError, errno, "poll");
  }
  if (pr == 0) {
    return IoStatus::kTimeout;
  }
  mmsghdr msgs[kMaxBatch];
  iovec iov[kMaxBatch];
  alignas(cmsghdr) unsigned char ctrl[kMaxBatch][kCtrlLen];
  std::memset(msgs, 0, sizeof(mmsghdr) * cap);
  for (std::size_t i = 0; i < cap; ++i) {
    iov[i].iov_base = &out[i].frame;
    iov[i].iov_len = sizeof(CanFrame);
    msgs[i].msg_hdr.msg_iov = &iov[i];
    msgs[i].msg_hdr.msg_iovlen = 1;
    msgs[i].msg_hdr.msg_control = ctrl[i];
    msgs[i].msg_hdr.msg_controllen = kCtrlLen;
  }
  int m = recvmmsg(data_fd_, msgs, static_cast<unsigned>(cap), MSG_DONTWAIT, nullptr);
  if (m < 0 && errno == ECONNRESET && kind_ == BusKind::kLoopback) {
    // A loopback peer that closed with our frames unread (e.g. killed) leaves ECONNRESET,
    // which recvmmsg reports before the frames it sent earlier and which are still queued.
    // The call consumed the error: read again, so those frames are not lost; the end of
    // stream (an empty message) follows them.
    m = recvmmsg(data_fd_, msgs, static_cast<unsigned>(cap), MSG_DONTWAIT, nullptr);
  }
  if (m < 0) {
    const int err = errno;
    if (err == EAGAIN || err == EWOULDBLOCK || err == EINTR) {
      return IoStatus::kTimeout;
    }
    if (is_link_error(err)) {
      return link_lost(err);
    }
    return fail(IoStatus::kSysError, err, "recvmmsg");
  }
  std::uint64_t batch_time_ns = 0;
  for (std::size_t i = 0; i < static_cast<std::size_t>(m); ++i) {
    const msghdr& h = msgs[i].msg_hdr;
    if (msgs[i].msg_len == 0 && kind_ == BusKind::kLoopback) {
      break;  // end of stream: the peer closed (the protocol never sends empty messages)
    }
    RxFrame& f = out[n];
    f.nbytes = msgs[i].msg_len;
    if ((h.msg_flags & MSG_TRUNC) != 0) {
      ++stats_.rx_truncated;
      f.nbytes = static_cast<std::uint32_t>(kCanFdMtu + 1);
    }
    if (!read_control(h, f.rx_time_ns, stats_.kernel_drops)) {
      if (batch_time_ns == 0) {
        batch_time_ns = now_realtime_ns();
      }
      f.rx_time_ns = batch_time_ns;
      ++stats_.rx_no_timestamp;
    }
    ++n;
  }
  if (n == 0) {
    return link_lost(EPIPE);
  }
  if (down_) {
    down_ = false;
    ++stats_.link_up;
  }
  stats_.rx_frames += n;
  ++stats_.rx_batches;
  return IoStatus::kOk;
}

IoStatus CanSocket::send(const CanFrame& f, int timeout_ms) {
  const std::size_t nbytes = wire_size(f);
  if (nbytes == kCanFdMtu && kind_ == BusKind::kSocketCan && !fd_capable_) {
    return fail(IoStatus::kNotSupported, 0, "CAN FD frame on an interface without FD (mtu 16)");
  }
  return write_bytes(&f, nbytes, timeout_ms);
}

IoStatus CanSocket::send_raw(const void* bytes, std::size_t nbytes, int timeout_ms) {
  if (kind_ != BusKind::kLoopback) {
    return IoStatus::kBadArgument;
  }
  return write_bytes(bytes, nbytes, timeout_ms);
}

// A send given up on back-pressure: kWouldBlock, or, when a loopback peer has taken nothing for
// opt_.tx_stall_limit_ms, the peer dropped (kLinkDown; a new peer may connect).
IoStatus CanSocket::stalled() {
  const std::int64_t now = now_monotonic_ms();
  if (stall_since_ms_ < 0) {
    stall_since_ms_ = now;
  }
  if (kind_ == BusKind::kLoopback && !pair_ && listen_fd_ >= 0 && opt_.tx_stall_limit_ms > 0 &&
      now - stall_since_ms_ >= opt_.tx_stall_limit_ms) {
    stall_since_ms_ = -1;
    ++stats_.tx_stall_disconnects;
    ++stats_.tx_link_down;
    return link_lost(ETIMEDOUT);
  }
  return IoStatus::kWouldBlock;
}

IoStatus CanSocket::write_bytes(const void* bytes, std::size_t nbytes, int timeout_ms) {
  if (tx_broken_) {  // loopback: an earlier send met the closed peer
    int queued = 0;
    if (ioctl(data_fd_, FIONREAD, &queued) == 0 && queued > 0) {
      ++stats_.tx_link_down;  // its last frames are still to be read: receive() first
      return fail(IoStatus::kLinkDown, EPIPE, "send: peer closed");
    }
    (void)link_lost(EPIPE);  // nothing left to read: drop it and reconnect / accept below
    rx_eof_pending_ = true;  // the reader has not seen the end of that stream: tell it once
  }
  // A loopback listener waits for its first peer, but not for the next one after losing a peer
  // (it closed, or was dropped for not reading): what answers the frames of the lost peer goes
  // nowhere at once (a receive waits for the next peer).
  const IoStatus link = ensure_link(peer_lost_ && data_fd_ < 0 ? 0 : timeout_ms);
  if (link != IoStatus::kOk) {
    if (link == IoStatus::kNotOpen) {
      return link;
    }
    ++stats_.tx_link_down;
    return fail(IoStatus::kLinkDown, ENOTCONN, "send: link down or no peer");
  }
  const std::int64_t deadline = timeout_ms > 0 ? now_monotonic_ms() + timeout_ms : 0;
  bool pressured = false;
  for (;;) {
    const ssize_t w = ::send(data_fd_, bytes, nbytes, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (w >= 0 && static_cast<std::size_t>(w) == nbytes) {
      ++stats_.tx_frames;
      stall_since_ms_ = -1;
      if (down_ && !pair_) {
        down_ = false;
        ++stats_.link_up;
      }
      return IoStatus::kOk;
    }
    const int err = w >= 0 ? EIO : errno;
    if (err == EINTR) {
      continue;
    }
    if (err == EAGAIN || err == EWOULDBLOCK || err == ENOBUFS) {
      if (!pressured) {
        pressured = true;
        ++stats_.tx_backpressure;
        if (stall_since_ms_ < 0) {
          stall_since_ms_ = now_monotonic_ms();  // the peer has taken nothing since
        }
      }
      int wait_ms = -1;
      if (timeout_ms == 0) {
        wait_ms = 0;
      } else if (timeout_ms > 0) {
        const std::int64_t left = deadline - now_monotonic_ms();
        wait_ms = left > 0 ? static_cast<int>(left) : 0;
      }
      const bool abort = opt_.abort_wait != nullptr && opt_.abort_wait->load();
      if (wait_ms == 0 || abort) {
        ++stats_.tx_would_block;
        return stalled();
      }
      if (err == ENOBUFS) {
        // A full CAN device queue does not always raise POLLOUT when it drains: nap 1 ms.
        poll(nullptr, 0, 1);
      } else {
        // At most 100 ms per wait, so that the abort flag is seen soon (a signal may also cut
        // the wait short: EINTR).
        pollfd p{data_fd_, POLLOUT, 0};
        poll(&p, 1, wait_ms < 0 || wait_ms > 100 ? 100 : wait_ms);
      }
      continue;
    }
    if (is_link_error(err)) {
      ++stats_.tx_link_down;
      if (kind_ == BusKind::kLoopback && !pair_) {
        // The peer closed, but frames it sent before may still be queued for us: keep the
        // socket for receive() to drain them and see the end of stream (closing it here lost
        // them, and the end of stream with them). See the top of write_bytes for the next send.
        tx_broken_ = true;
        ++stats_.link_down;
        return fail(IoStatus::kLinkDown, err, "send: peer closed");
      }
      return link_lost(err);
    }
    if (err == EINVAL && nbytes == kCanFdMtu && kind_ == BusKind::kSocketCan) {
      return fail(IoStatus::kNotSupported, err, "send of a CAN FD frame");
    }
    return fail(IoStatus::kSysError, err, "send");
  }
}

}  // namespace imu::hal

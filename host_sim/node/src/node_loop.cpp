// Linux loop around the node core (see node_loop.hpp).
#include "imu/node/node_loop.hpp"

#include <time.h>

namespace imu::node {
namespace {

std::int64_t now_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1'000'000;
}

}  // namespace

const char* to_string(LoopEnd e) {
  switch (e) {
    case LoopEnd::kLinkDown: return "link-down";
    case LoopEnd::kIdle: return "idle";
    case LoopEnd::kStopped: return "stopped";
    case LoopEnd::kError: return "error";
    case LoopEnd::kPeerTimeout: return "peer-timeout";
  }
  return "?";
}

LoopEnd run_node_loop(Node& node, hal::CanSocket& bus, const LoopOptions& opt) {
  hal::RxFrame local[hal::CanSocket::kMaxBatch];  // 5.6 kB of stack
  std::int64_t last_frame_ms = now_ms();
  std::int64_t last_peer_ms = last_frame_ms;  // last frame from the peer (for peer_timeout_ms)
  const auto peer_gone = [&]() {
    return opt.peer_timeout_ms > 0 && now_ms() - last_peer_ms >= opt.peer_timeout_ms;
  };
  const int wait_ms = opt.idle_ms > 0 ? opt.idle_ms : 200;
  for (;;) {
    if (opt.stop != nullptr && opt.stop->load(std::memory_order_relaxed)) {
      node.finish();
      return LoopEnd::kStopped;
    }
    std::size_t n = 0;
    const hal::IoStatus st = bus.receive(local, hal::CanSocket::kMaxBatch, n, wait_ms);
    const bool seen = node.stats().samples > 0 || node.stats().missing > 0;
    node.set_link_counters(bus.stats().kernel_drops, bus.stats().peer_refused);
    switch (st) {
      case hal::IoStatus::kOk:
        for (std::size_t i = 0; i < n; ++i) {
          if (opt.stop != nullptr && opt.stop->load(std::memory_order_relaxed)) {
            break;  // a stop is honoured within one frame (the loop's top finishes the node)
          }
          node.on_frame(local[i].frame, local[i].nbytes, local[i].rx_time_ns);
        }
        last_frame_ms = now_ms();
        last_peer_ms = last_frame_ms;
        break;
      case hal::IoStatus::kTimeout:
        node.on_idle();
        if (opt.exit_idle_ms > 0 && seen && now_ms() - last_frame_ms >= opt.exit_idle_ms) {
          return LoopEnd::kIdle;  // on_idle() above sent the final telemetry
        }
        if (peer_gone()) {
          return LoopEnd::kPeerTimeout;  // on_idle() above was the final flush
        }
        break;
      case hal::IoStatus::kLinkDown:
        if (opt.exit_on_link_down && seen) {
          node.finish();
          return LoopEnd::kLinkDown;
        }
        if (peer_gone()) {
          node.finish();
          return LoopEnd::kPeerTimeout;
        }
        // No samples yet (e.g. a previous client left): wait for the next peer.
        last_frame_ms = now_ms();
        {
          timespec nap{0, 20'000'000};
          nanosleep(&nap, nullptr);
        }
        break;
      default:
        return LoopEnd::kError;
    }
  }
}

}  // namespace imu::node

// RxPump: the reader loop body shared by every backend. One call = one poll + one recvmmsg
// batch from a FrameSource, every frame pushed through a Receiver, every resulting event handed
// to on_event(const RxEvent&) in order. On an idle timeout the receiver is flushed, so samples
// held for a late predecessor are not held forever when the sender pauses.
//
// Cost per call: one poll and one recvmmsg system call, O(frames * (72 + W)). No heap.
#ifndef IMU_HAL_RX_PUMP_HPP
#define IMU_HAL_RX_PUMP_HPP

#include <cstddef>

#include "imu/hal/frame_io.hpp"
#include "imu/hal/receiver.hpp"

namespace imu::hal {

template <std::size_t W = 8, std::size_t B = 64>
class RxPump {
 public:
  /// Returns the transport status (kOk when frames were taken). kTimeout flushes `rx`.
  template <class OnEvent>
  [[nodiscard]] IoStatus run_once(FrameSource& src, Receiver<W>& rx, int timeout_ms,
                                  OnEvent&& on_event) {
    std::size_t n = 0;
    const IoStatus s = src.receive(batch_, B, n, timeout_ms);
    if (s == IoStatus::kTimeout) {
      (void)rx.flush_drain(on_event);
      return s;
    }
    for (std::size_t i = 0; i < n; ++i) {
      (void)rx.push_drain(batch_[i].frame, batch_[i].nbytes, batch_[i].rx_time_ns, on_event);
    }
    return s;
  }

 private:
  RxFrame batch_[B];
};

}  // namespace imu::hal

#endif  // IMU_HAL_RX_PUMP_HPP

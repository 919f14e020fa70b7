// Simulation backend of the frame-source port (imu/hal/frame_io.hpp): frames from an array in
// memory, handed out in order in batches of up to `cap`, each with wire_size() bytes and a
// receive time of index x period_ns. For targets and tests without a bus (the M4 image feeds
// the node from one). Header-only, no OS, no heap; the array must outlive the source.
// receive() is O(batch) and never waits: kTimeout once the array is exhausted.
#ifndef IMU_HAL_SIM_MEMORY_FRAME_SOURCE_HPP
#define IMU_HAL_SIM_MEMORY_FRAME_SOURCE_HPP

#include <cstddef>
#include <cstdint>

#include "imu/hal/frame_io.hpp"

namespace imu::hal {

class MemoryFrameSource final : public FrameSource {
 public:
  MemoryFrameSource(const CanFrame* frames, std::size_t count, std::uint64_t period_ns = 0)
      : frames_(frames), count_(count), period_ns_(period_ns) {}
  [[nodiscard]] IoStatus receive(RxFrame* out, std::size_t cap, std::size_t& n,
                                 int /*timeout_ms*/) override {
    n = 0;
    if (out == nullptr || cap == 0) {
      return IoStatus::kBadArgument;
    }
    while (n < cap && next_ < count_) {
      out[n].frame = frames_[next_];
      out[n].nbytes = static_cast<std::uint32_t>(wire_size(frames_[next_]));
      out[n].rx_time_ns = next_ * period_ns_;
      ++n;
      ++next_;
    }
    return n > 0 ? IoStatus::kOk : IoStatus::kTimeout;
  }
  [[nodiscard]] std::size_t remaining() const { return count_ - next_; }

 private:
  const CanFrame* frames_;
  std::size_t count_;
  std::uint64_t period_ns_;
  std::size_t next_ = 0;
};

}  // namespace imu::hal

#endif  // IMU_HAL_SIM_MEMORY_FRAME_SOURCE_HPP

// The same firmware Node on the Cortex-M4 and on the host. One source, built
// for both: a small synthetic record (samples.hpp's deterministic generator, 6 channels) is
// encoded with the hal codec into an in-memory frame array (a ConfigRecord, one ModelRecord per
// channel with the largest model the node runs, kNodeSamples SampleRecords), fed through
// hal::MemoryFrameSource into imu::node::Node::on_frame, then Node::finish(). Every telemetry
// frame the node sends goes through a capturing FrameSink and is written as one line:
//   IMU-NODE BEGIN samples=<N> frames_in=<F> sizeof_node=<bytes> states=<kNodeStates>
//                  per_channel=<bytes> kf8=<sizeof KalmanFilter<float, 8>>  (not compared:
//                  sizes differ between targets)
//   T <index> id=<can id hex> len=<bytes> <payload bytes, hex>   (after the run: captured in RAM)
//   IMU-NODE END tx=<telemetry frames> crc=<crc32c of all telemetry bytes> model_states=<n>
//   rejected=<model_rejected> samples=<node samples>
// The target adds cost lines (not on the host): "IMU-NODE COST ..." (see main_node_m4.cpp).
// Host and target must print identical T and END lines: byte-for-byte equal telemetry.
// Cost: the node's per-frame cost plus O(1) per telemetry frame for the line. Static state.
#ifndef IMU_M4_NODE_WORKLOAD_HPP
#define IMU_M4_NODE_WORKLOAD_HPP

#include <cstddef>
#include <cstdint>

namespace imu::m4 {

inline constexpr std::uint32_t kNodeSamples = 1500;  ///< 15 s at 100 Hz, 6 channels

/// Receives one NUL-terminated line (ending in '\n').
using NodeWriteFn = void (*)(const char* line, void* ctx);
/// Called just before the first and just after the last input frame is handed to the node
/// (phase 0 / 1): the target reads its cycle counter there. May be null.
using NodeMarkFn = void (*)(int phase, void* ctx);  // phase 2: after every batch

enum class NodeRunStatus : std::uint8_t {
  kOk = 0,
  kLineTruncated,
  kConfigRejected,  ///< Node::configure refused the NodeConfig
  kFrameOverflow,   ///< the input frame array is too small (a bug in the sizes)
};

[[nodiscard]] NodeRunStatus run_node_workload(NodeWriteFn write, NodeMarkFn mark, void* ctx);

/// Steady-state run: a second Node, the same config and models, samples generated on the fly
/// (no input array): kSteadyWarmSamples to let the pushed filters' gains freeze, then
/// kSteadySamples between the marks (encoded before the first mark, into a static array). Prints one line (compared host vs target byte for byte):
///   IMU-NODE STEADY warm=<W> samples=<S> steady_channels=<channels with a frozen gain>
///     tx=<telemetry frames> bias=<six biases, IEEE hex>
inline constexpr std::uint32_t kSteadyWarmSamples = 12000;
inline constexpr std::uint32_t kSteadySamples = 2000;
[[nodiscard]] NodeRunStatus run_node_steady(NodeWriteFn write, NodeMarkFn mark, void* ctx);

}  // namespace imu::m4

#endif  // IMU_M4_NODE_WORKLOAD_HPP

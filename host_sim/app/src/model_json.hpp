// Reader of the model that `imu-sim analyze --json` writes, for `imu-sim run --model A.json`.
#ifndef IMU_SIM_MODEL_JSON_HPP
#define IMU_SIM_MODEL_JSON_HPP

#include <string>

#include "imu/hal/codec.hpp"

namespace imu::sim {

/// What the node is sent for one channel: its stochastic model and, when model_after has a ramp
/// or sinusoids, their ModelSignalsRecord (pushed before the ModelRecord).
struct NodeModel {
  hal::ModelRecord rec{};
  hal::ModelSignalsRecord signals{};
  bool has_signals = false;
};

/// Read `model_after` of the analysis JSON text into a version 2 ModelRecord for channel_index:
/// N, Q, up to two GMs, K, the bias instability, the white noise's output filter (`n_filter_s`;
/// absent: none) and the narrowband oscillation (`oscillation.{sigma, f0_hz, beta_per_s}`); and
/// its deterministic terms (ramp `r`, sinusoids `sin_a`/`sin_f0_hz`, `sin2_a`/`sin2_f0_hz`) into
/// a ModelSignalsRecord whose memory is the analysed record's length (`n_samples` / `fs_hz`:
/// the terms are established over it). The file's top-level "channel" must equal channel_name.
/// The deterministic terms' states are reserved first; a model the node would then refuse only
/// for its output filter or oscillation (more states than kNodeProcessStates, a term out of its
/// ranges) is sent without the filter, then with the oscillation's variance in the white noise;
/// where even the rest does not fit, the second sinusoid, the ramp, then the first sinusoid are
/// left out (each noted in `dropped`). A third GM or more would not fit the record: an error.
/// Returns false with a one-line err (missing key, malformed number, wrong channel).
/// O(text length).
[[nodiscard]] bool model_from_analysis_json(const std::string& json, const std::string& channel_name,
                                            std::size_t channel_index, NodeModel& out,
                                            std::string& dropped, std::string& err);
/// The same, the stochastic record alone: deterministic terms are noted in `dropped` as not
/// included.
[[nodiscard]] bool model_from_analysis_json(const std::string& json, const std::string& channel_name,
                                            std::size_t channel_index, hal::ModelRecord& out,
                                            std::string& dropped, std::string& err);

/// True if the analysis JSON text holds a model of channel_name: a key of its "channels" (a
/// whole-IMU analysis) or its top-level "channel". O(text length).
[[nodiscard]] bool analysis_holds_channel(const std::string& json, const std::string& channel_name);

}  // namespace imu::sim

#endif  // IMU_SIM_MODEL_JSON_HPP

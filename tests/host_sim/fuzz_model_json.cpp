// libFuzzer target for the model reader of `imu-sim run --model` (an analysis JSON, one or all
// channels): the input is the file's text. Built only with IMU_FUZZ=ON and clang (preset
// "fuzz"). Any crash or sanitizer report is a failure; a refusal with a message is the expected
// outcome for most inputs, and an accepted model must hold finite numbers.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "model_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string json(reinterpret_cast<const char*>(data), size);
  for (const char* channel : {"acc_z", "gyro_x"}) {
    (void)imu::sim::analysis_holds_channel(json, channel);  // run's slot lookup: must not crash
    imu::hal::ModelRecord rec{};
    std::string dropped;
    std::string err;
    if (imu::sim::model_from_analysis_json(json, channel, 2, rec, dropped, err)) {
      if (!std::isfinite(rec.n) || !std::isfinite(rec.q) || !std::isfinite(rec.k)) {
        std::abort();  // accepted a model with a non-finite parameter
      }
    } else if (err.empty()) {
      std::abort();  // refused without a reason
    }
  }
  return 0;
}

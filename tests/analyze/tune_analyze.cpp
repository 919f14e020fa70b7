// Threshold tuning and exploration (not a test): runs the synthetic cases on seeds given on the
// command line (tuning seeds are >= 1000, the tests use 1..5) and prints the effects found.
// usage: tune_analyze CASE SEED_FIRST SEED_COUNT [SAMPLES]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "imu/analyze/analyze.hpp"
#include "imu/analyze/synth.hpp"
#include "synth_cases.hpp"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: tune_analyze CASE SEED_FIRST SEED_COUNT [SAMPLES]\n");
    return 2;
  }
  const std::string name = argv[1];
  const auto first = std::strtoull(argv[2], nullptr, 10);
  const auto count = std::strtoull(argv[3], nullptr, 10);
  for (unsigned long long s = first; s < first + count; ++s) {
    imu::analyze::SynthSpec spec = imu::analyze::test::make_case(name, s);
    if (argc > 4) {
      spec.samples = std::strtoull(argv[4], nullptr, 10);
    }
    const std::vector<double> y = imu::analyze::synthesize(spec);
    imu::analyze::Report r;
    std::string err;
    if (!imu::analyze::analyze(y, name, imu::analyze::Options{}, r, err)) {
      std::fprintf(stderr, "%s\n", err.c_str());
      return 1;
    }
    std::printf("== %s seed %llu ==\n%s", name.c_str(), s, imu::analyze::to_text(r).c_str());
    if (std::getenv("TUNE_DUMP") != nullptr) {  // per-tau data and model ADEVs
      for (std::size_t i = 0; i < r.adev.size(); ++i) {
        const double t = r.adev[i].tau_s;
        std::printf("  tau %9.3f data %.4e clean %.4e before %+.3f after %+.3f edf %.1f\n", t,
                    std::sqrt(r.adev[i].avar), std::sqrt(r.adev_clean[i].avar),
                    std::sqrt(imu::model_avar(r.model_before, t) / r.adev[i].avar) - 1.0,
                    std::sqrt(imu::model_avar(r.model_after, t) / r.adev_clean[i].avar) - 1.0,
                    r.adev[i].edf);
      }
    }
  }
  return 0;
}

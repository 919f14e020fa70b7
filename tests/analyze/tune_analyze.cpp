// Threshold tuning and exploration (not a test): runs the synthetic cases on seeds given on the
// command line (tuning seeds are >= 1000, the tests use 1..5) and prints the effects found.
// usage: tune_analyze CASE SEED_FIRST SEED_COUNT [SAMPLES]
//        tune_analyze FILE.mat CHANNEL LSB_NAME   (a recorded channel at 100 Hz)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "imu/analyze/analyze.hpp"
#include "imu/analyze/synth.hpp"
#include "imu/mat/mat_reader.hpp"
#include "synth_cases.hpp"

namespace {

void dump(const imu::analyze::Report& r) {
  if (std::getenv("TUNE_DUMP") == nullptr) {  // per-tau data and model ADEVs
    return;
  }
  for (std::size_t i = 0; i < r.adev.size(); ++i) {
    const double t = r.adev[i].tau_s;
    std::printf("  tau %9.3f data %.4e clean %.4e before %+.3f after %+.3f edf %.1f\n", t,
                std::sqrt(r.adev[i].avar), std::sqrt(r.adev_clean[i].avar),
                std::sqrt(imu::model_avar(r.model_before, t) / r.adev[i].avar) - 1.0,
                std::sqrt(imu::model_avar(r.model_after, t) / r.adev_clean[i].avar) - 1.0,
                r.adev[i].edf);
  }
}

int run_file(const char* path, const char* channel, const char* lsb_name) {
  auto mf = imu::mat::MatFile::open(path);
  if (!mf.ok()) {
    std::fprintf(stderr, "%s\n", mf.error().message.c_str());
    return 1;
  }
  auto col = mf.value().read_column(channel);
  auto lsb = mf.value().read_scalar(lsb_name);
  if (!col.ok() || !lsb.ok()) {
    std::fprintf(stderr, "cannot read %s / %s\n", channel, lsb_name);
    return 1;
  }
  imu::analyze::Options o;
  o.fs_hz = 100.0;
  o.lsb = lsb.value();
  imu::analyze::Report r;
  std::string err;
  if (!imu::analyze::analyze(col.value(), channel, o, r, err)) {
    std::fprintf(stderr, "%s\n", err.c_str());
    return 1;
  }
  std::printf("== %s %s ==\n%s", path, channel, imu::analyze::to_text(r).c_str());
  dump(r);
  return 0;
}

}  // namespace

int run(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]).size() > 4 &&
      std::string(argv[1]).substr(std::string(argv[1]).size() - 4) == ".mat") {
    return run_file(argv[1], argv[2], argv[3]);
  }
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
    dump(r);
  }
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tune_analyze: %s\n", e.what());
    return 1;
  }
}

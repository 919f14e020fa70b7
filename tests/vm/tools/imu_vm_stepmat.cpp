// imu-vm-stepmat: MAT-files for the VM test.
//  * Synthetic: an acc_z recording from the first-order model (no rate random walk, so
//    it matches imu-fw's default model exactly) with an optional step added to every sample
//    from --step-at-s on. Streamed to imu-fw: without a step the residual monitors stay quiet,
//    with one the alarm GPIO line must go high.
//      imu-vm-stepmat --out FILE [--duration 30] [--step 0.1] [--step-at-s 20] [--seed 7]
//    Model: N = 3.3e-3, B = 9e-4, Tp = 300 s, fs = 100 Hz (imu-fw's defaults), LSB 1e-6 m/s^2.
//  * Excerpt: the first N samples of every channel of a recording (acc_x..gyro_z, fs, acc_lsb,
//    gyro_lsb copied unchanged), so that the emulated machine streams real data in seconds.
//      imu-vm-stepmat --excerpt IN --samples N --out FILE
// Exit 0 ok, 1 read/write error, 2 usage. Host/guest tool only (uses the heap freely).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "imu/error_model.hpp"
#include "imu/mat/mat_reader.hpp"
#include "imu/mat/mat_writer.hpp"
#include "imu/noise_sim.hpp"
#include "imu/online_adev.hpp"

namespace {

int excerpt(const std::string& in, std::size_t samples, const std::string& out) {
  static const char* const kColumns[] = {"acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"};
  static const char* const kScalars[] = {"fs", "acc_lsb", "gyro_lsb"};
  imu::mat::MatWriter w;
  for (const char* name : kColumns) {
    auto col = imu::mat::read_column(in, name);
    if (!col.ok()) {
      std::fprintf(stderr, "imu-vm-stepmat: %s\n", col.error().message.c_str());
      return 1;
    }
    std::vector<double> v = col.value();
    if (v.size() < samples) {
      std::fprintf(stderr, "imu-vm-stepmat: %s has %zu samples, fewer than %zu\n", name, v.size(),
                   samples);
      return 1;
    }
    v.resize(samples);
    if (!w.add_column(name, v).ok()) {
      std::fprintf(stderr, "imu-vm-stepmat: cannot add %s\n", name);
      return 1;
    }
  }
  for (const char* name : kScalars) {
    auto v = imu::mat::read_scalar(in, name);
    if (!v.ok() || !w.add_scalar(name, v.value()).ok()) {
      std::fprintf(stderr, "imu-vm-stepmat: cannot copy %s\n", name);
      return 1;
    }
  }
  auto st = w.add_string("source", "first " + std::to_string(samples) + " samples of " + in);
  if (st.ok()) {
    st = w.save(out);
  }
  if (!st.ok()) {
    std::fprintf(stderr, "imu-vm-stepmat: %s\n", st.error().message.c_str());
    return 1;
  }
  std::printf("wrote %s: first %zu samples of %s\n", out.c_str(), samples, in.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out;
  std::string excerpt_in;
  unsigned long excerpt_samples = 0;
  double duration_s = 30.0;
  double step = 0.0;
  double step_at_s = 20.0;
  unsigned long seed = 7;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--out") == 0 && has_value) {
      out = argv[++i];
    } else if (std::strcmp(argv[i], "--duration") == 0 && has_value) {
      duration_s = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--step") == 0 && has_value) {
      step = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--step-at-s") == 0 && has_value) {
      step_at_s = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--seed") == 0 && has_value) {
      seed = std::strtoul(argv[++i], nullptr, 10);
    } else if (std::strcmp(argv[i], "--excerpt") == 0 && has_value) {
      excerpt_in = argv[++i];
    } else if (std::strcmp(argv[i], "--samples") == 0 && has_value) {
      excerpt_samples = std::strtoul(argv[++i], nullptr, 10);
    } else {
      std::fprintf(stderr, "usage: imu-vm-stepmat --out FILE [--duration S] [--step X] "
                           "[--step-at-s S] [--seed N]\n"
                           "       imu-vm-stepmat --excerpt IN --samples N --out FILE\n");
      return 2;
    }
  }
  if (!excerpt_in.empty()) {
    if (out.empty() || excerpt_samples == 0) {
      std::fprintf(stderr, "imu-vm-stepmat: --excerpt needs --samples N > 0 and --out\n");
      return 2;
    }
    return excerpt(excerpt_in, excerpt_samples, out);
  }
  constexpr double kFsHz = 100.0;
  constexpr double kLsb = 1e-6;
  if (out.empty() || !(duration_s > 0.0) || duration_s * kFsHz > 1e8) {
    std::fprintf(stderr, "imu-vm-stepmat: --out is required, 0 < --duration <= 1e6 s\n");
    return 2;
  }
  imu::FirstOrderGm gm{};
  imu::ModelParams mp{};
  imu::ContinuousModel<4> cm;
  imu::DiscreteModel<4> dm;
  imu::ModelSimulator<4> sim;
  if (imu::first_order_gm_from_asd(3.3e-3, 9e-4, 300.0, kFsHz, gm) != imu::ModelStatus::kOk) {
    std::fprintf(stderr, "imu-vm-stepmat: model rejected\n");
    return 1;
  }
  mp.n = 3.3e-3;
  mp.n_gm = 1;
  mp.gm[0] = imu::GmParam{gm.sb, gm.tb_s};
  if (imu::build_model(mp, cm) != imu::ModelStatus::kOk ||
      imu::discretize(cm, 1.0 / kFsHz, dm) != imu::ModelStatus::kOk ||
      sim.configure(dm, seed) != imu::ModelStatus::kOk) {
    std::fprintf(stderr, "imu-vm-stepmat: model could not be built\n");
    return 1;
  }
  const auto n = static_cast<std::size_t>(std::llround(duration_s * kFsHz));
  const auto step_index = static_cast<std::size_t>(std::llround(step_at_s * kFsHz));
  std::vector<double> z(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double v = sim.next() + (k >= step_index ? step : 0.0);
    z[k] = static_cast<double>(imu::quantize(v, kLsb).counts) * kLsb;  // exact LSB multiples
  }
  imu::mat::MatWriter w;
  auto st = w.add_column("acc_z", z);
  if (st.ok()) {
    st = w.add_scalar("fs", kFsHz);
  }
  if (st.ok()) {
    st = w.add_scalar("acc_lsb", kLsb);
  }
  if (st.ok()) {
    st = w.add_string("source",
                      "SYNTHETIC imu-vm-stepmat: the example's first-order model, step " +
                          std::to_string(step) + " m/s^2 at " + std::to_string(step_at_s) + " s");
  }
  if (st.ok()) {
    st = w.save(out);
  }
  if (!st.ok()) {
    std::fprintf(stderr, "imu-vm-stepmat: %s\n", st.error().message.c_str());
    return 1;
  }
  std::printf("wrote %s: %zu samples, step %g m/s^2 from sample %zu\n", out.c_str(), n, step,
              step_index);
  return 0;
}

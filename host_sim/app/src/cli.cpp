// imu-sim: subcommand dispatch, synth, model and adev (run is in run.cpp).
#include "imu/sim/cli.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common.hpp"
#include "data.hpp"
#include "imu/error_model.hpp"
#include "imu/mat/mat_writer.hpp"
#include "imu/model_text.hpp"
#include "imu/noise_sim.hpp"
#include "imu/online_adev.hpp"
#include "report.hpp"
#include "run.hpp"

#ifdef IMU_HAVE_ANALYZE
#include "imu/analyze/analyze.hpp"  // imu::analyze::cli_main (host_sim/analyze, issue 6)
#endif

namespace imu::sim {
namespace {

constexpr const char* kUsage =
    "usage: imu-sim <command> [options]\n"
    "  synth [--out FILE] [--N 3.3e-3] [--B 9e-4] [--Tp 300] [--K 1.4e-4] [--fs 100]\n"
    "        [--duration 10000] [--seed 1] [--lsb 1e-6] [--channel acc_z]\n"
    "        synthetic recording (MAT-file: channel, fs, acc_lsb/gyro_lsb, source) from the\n"
    "        seed's error model plus rate random walk\n"
    "  model [--N 3.3e-3] [--B 9e-4] [--Tp 300] [--fs 100]\n"
    "        the continuous and discrete first-order model in the seed's layout\n"
    "  adev FILE [--channel acc_z] [--json OUT] [--lsb X] [--fs X]\n"
    "        online ADEV of one channel (fw OnlineAdev<8,22>), with the time it took\n"
    "  run --mat FILE [--channel acc_z] [--bus loopback|vcan0|can0] [--rate max|realtime]\n"
    "      [--node inproc|spawn|external] [--out DIR] [--json FILE] [--N --B --Tp [--K]]\n"
    "      [--no-plots] [--quiet] [--T-avg 10] [--T-int 20] [--sim-windows 1000] [--seed 2]\n"
    "      [--timeout 30] [--window 4096|256] [--layout auto|fd|classic] [--only-channel] [--fw PATH]\n"
    "        sensor emulator -> bus -> firmware node -> telemetry -> report (text, JSON,\n"
    "        CSV, SVG/PNG plots in DIR, default out/run)\n"
    "  analyze ...   (host_sim/analyze)\n";

int cmd_synth(int argc, char** argv) {
  const char* cmd = "imu-sim synth";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {{"--out", true},  {"--N", true},        {"--B", true},
                                      {"--Tp", true},   {"--K", true},        {"--fs", true},
                                      {"--duration", true}, {"--seed", true}, {"--lsb", true},
                                      {"--channel", true}};
  if (!a.parse(argc, argv, 2, specs, 0, err)) {
    return fail(cmd, err, 2);
  }
  double n = 0, b = 0, tp = 0, k = 0, fs = 0, dur = 0, seed = 0, lsb = 0;
  if (!a.number("--N", 3.3e-3, n, err) || !a.number("--B", 9e-4, b, err) ||
      !a.number("--Tp", 300.0, tp, err) || !a.number("--K", 1.4e-4, k, err) ||
      !a.number("--fs", 100.0, fs, err) || !a.number("--duration", 10000.0, dur, err) ||
      !a.number("--seed", 1.0, seed, err) || !a.number("--lsb", 1e-6, lsb, err)) {
    return fail(cmd, err, 2);
  }
  std::size_t chan = 0;
  const std::string chan_name = a.get("--channel", "acc_z");
  if (!channel_index(chan_name, chan)) {
    return fail(cmd, "unknown channel '" + chan_name + "'", 2);
  }
  if (!(dur > 0.0) || !(lsb > 0.0) || k < 0.0 || seed < 0.0 || dur * fs > 1e9) {
    return fail(cmd, "--duration, --lsb must be > 0, --K >= 0, at most 1e9 samples", 2);
  }
  FirstOrderGm gm{};
  if (first_order_gm_from_asd(n, b, tp, fs, gm) != ModelStatus::kOk) {
    return fail(cmd, "--N, --B, --Tp, --fs must be finite and > 0", 2);
  }
  ModelParams mp{};
  mp.n = n;
  mp.n_gm = 1;
  mp.gm[0] = GmParam{gm.sb, gm.tb_s};
  mp.k = k;
  ContinuousModel<4> cm;
  DiscreteModel<4> dm;
  ModelSimulator<4> sim;
  if (build_model(mp, cm) != ModelStatus::kOk || discretize(cm, 1.0 / fs, dm) != ModelStatus::kOk ||
      sim.configure(dm, static_cast<std::uint64_t>(seed)) != ModelStatus::kOk) {
    return fail(cmd, "the model could not be built or simulated");
  }
  const double t0 = now_s();
  const auto count = static_cast<std::size_t>(std::llround(dur * fs));
  std::vector<double> z(count);
  for (double& v : z) {
    v = static_cast<double>(quantize(sim.next(), lsb).counts) * lsb;  // exact LSB multiples
  }
  const std::string out = a.get("--out", "synth.mat");
  std::string source;
  appendf(source,
          "SYNTHETIC data from imu-sim synth (not a recording: the seed's marble-slab data is not "
          "public): white N=%.6g, first-order GM B=%.6g Tp=%.6g s, rate random walk K=%.6g, "
          "fs=%.6g Hz, %zu samples, seed %.0f, quantized to LSB %.6g",
          n, b, tp, k, fs, count, seed, lsb);
  mat::MatWriter w;
  auto st = w.add_column(chan_name, z);
  if (st.ok()) {
    st = w.add_scalar("fs", fs);
  }
  if (st.ok()) {
    st = w.add_scalar(chan < 3 ? "acc_lsb" : "gyro_lsb", lsb);
  }
  if (st.ok()) {
    st = w.add_string("source", source);
  }
  if (st.ok()) {
    const std::size_t slash = out.rfind('/');
    if (slash != std::string::npos && !make_dirs(out.substr(0, slash), err)) {
      return fail(cmd, err);
    }
    st = w.save(out);
  }
  if (!st.ok()) {
    return fail(cmd, st.error().message);
  }
  std::printf("wrote %s: %s (%zu samples at %g Hz, %g s), fs, %s\n%s\ntook %.2f s\n", out.c_str(),
              chan_name.c_str(), count, fs, dur, chan < 3 ? "acc_lsb" : "gyro_lsb",
              source.c_str(), now_s() - t0);
  return 0;
}

int cmd_model(int argc, char** argv) {
  const char* cmd = "imu-sim model";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {{"--N", true}, {"--B", true}, {"--Tp", true}, {"--fs", true}};
  if (!a.parse(argc, argv, 2, specs, 0, err)) {
    return fail(cmd, err, 2);
  }
  double n = 0, b = 0, tp = 0, fs = 0;
  if (!a.number("--N", 3.3e-3, n, err) || !a.number("--B", 9e-4, b, err) ||
      !a.number("--Tp", 300.0, tp, err) || !a.number("--fs", 100.0, fs, err)) {
    return fail(cmd, err, 2);
  }
  FirstOrderGm gm{};
  if (first_order_gm_from_asd(n, b, tp, fs, gm) != ModelStatus::kOk) {
    return fail(cmd, "--N, --B, --Tp, --fs must be finite and > 0", 2);
  }
  std::fputs(format_seed_model(gm).c_str(), stdout);
  return 0;
}

int cmd_adev(int argc, char** argv) {
  const char* cmd = "imu-sim adev";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {
      {"--channel", true}, {"--json", true}, {"--lsb", true}, {"--fs", true}};
  if (!a.parse(argc, argv, 2, specs, 1, err)) {
    return fail(cmd, err, 2);
  }
  if (a.positional().empty()) {
    return fail(cmd, "a MAT-file is required: imu-sim adev FILE --channel C", 2);
  }
  std::size_t chan = 0;
  const std::string chan_name = a.get("--channel", "acc_z");
  if (!channel_index(chan_name, chan)) {
    return fail(cmd, "unknown channel '" + chan_name + "'", 2);
  }
  double lsb = 0, fs = 0;
  if (!a.number("--lsb", 0.0, lsb, err) || !a.number("--fs", 0.0, fs, err)) {
    return fail(cmd, err, 2);
  }
  if (lsb < 0.0 || fs < 0.0) {
    return fail(cmd, "--lsb and --fs must be > 0", 2);
  }
  const std::string path = a.positional()[0];
  const double t0 = now_s();
  bool want[kNumChannels] = {};
  double lsb_over[kNumChannels] = {};
  want[chan] = true;
  lsb_over[chan] = lsb;
  SensorData sd;
  if (!load_sensor(path, want, want, lsb_over, fs, sd, err)) {
    return fail(cmd, err);
  }
  const double t1 = now_s();
  std::vector<std::int32_t> counts;
  ChannelData& ch = sd.ch[chan];
  to_counts(ch, counts);
  const double t2 = now_s();
  OnlineAdev<8, 22> adev(1.0 / sd.fs_hz, ch.lsb);
  adev.push_block(counts.data(), counts.size());
  AdevPoint pts[OnlineAdev<8, 22>::kMaxPoints];
  const std::size_t np = adev.snapshot(pts, OnlineAdev<8, 22>::kMaxPoints);
  const double t3 = now_s();
  const std::vector<AdevRow> rows = rows_from_points(pts, np);
  std::printf("%s %s: %zu samples at %g Hz, LSB %g %s%s\n", path.c_str(), chan_name.c_str(),
              counts.size(), sd.fs_hz, ch.lsb, channel_unit(chan),
              ch.lsb_from_file ? " (from the file)" : "");
  std::fputs(format_adev_table(rows).c_str(), stdout);
  std::printf("time: read %.3f s, quantize %.3f s, online ADEV %.3f s, total %.3f s\n", t1 - t0,
              t2 - t1, t3 - t2, t3 - t0);
  if (ch.off_grid > 0 || ch.saturated > 0) {
    std::printf("note: %llu samples off the LSB grid, %llu saturated\n",
                static_cast<unsigned long long>(ch.off_grid),
                static_cast<unsigned long long>(ch.saturated));
  }
  if (a.has("--json")) {
    std::string j = "{\n";
    j += "  \"source\": " + json_str(path) + ",\n";
    j += "  \"channel\": " + json_str(chan_name) + ",\n";
    j += "  \"unit\": " + json_str(channel_unit(chan)) + ",\n";
    j += "  \"fs_hz\": " + json_num(sd.fs_hz) + ",\n";
    j += "  \"lsb\": " + json_num(ch.lsb) + ",\n";
    j += "  \"n_samples\": " + std::to_string(counts.size()) + ",\n";
    j += "  \"adev\": " + adev_json_list(rows) + ",\n";
    j += "  \"timing_s\": {\"read\": " + json_num(t1 - t0) + ", \"quantize\": " +
         json_num(t2 - t1) + ", \"adev\": " + json_num(t3 - t2) + ", \"total\": " +
         json_num(t3 - t0) + "}\n}\n";
    if (!write_file(a.get("--json"), j, err)) {
      return fail(cmd, err);
    }
  }
  return 0;
}

}  // namespace

int cli_main(int argc, char** argv) {
  if (argc < 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string sub = argv[1];
  if (sub == "-h" || sub == "--help" || sub == "help") {
    std::fputs(kUsage, stdout);
    return 0;
  }
  if (sub == "synth") {
    return cmd_synth(argc, argv);
  }
  if (sub == "model") {
    return cmd_model(argc, argv);
  }
  if (sub == "adev") {
    return cmd_adev(argc, argv);
  }
  if (sub == "run") {
    return cmd_run(argc, argv);
  }
  if (sub == "analyze") {
#ifdef IMU_HAVE_ANALYZE
    return imu::analyze::cli_main(argc - 1, argv + 1);
#else
    return fail("imu-sim", "analyze: not built");
#endif
  }
  std::fprintf(stderr, "imu-sim: unknown command '%s'\n%s", sub.c_str(), kUsage);
  return 2;
}

}  // namespace imu::sim

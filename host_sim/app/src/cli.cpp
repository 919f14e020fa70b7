// imu-sim: subcommand dispatch, synth, model and adev (run is in run.cpp).
#include "imu/sim/cli.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "common.hpp"
#include "data.hpp"
#include "full_adev.hpp"
#include "model_json.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/cli/rosbag.hpp"
#include "imu/cli/text_input.hpp"
#include "imu/error_model.hpp"
#include "imu/mat/mat_reader.hpp"
#include "imu/mat/mat_writer.hpp"
#include "imu/model_text.hpp"
#include "imu/noise_sim.hpp"
#include "imu/online_adev.hpp"
#include "report.hpp"
#include "run.hpp"

#ifdef IMU_HAVE_ANALYZE
#include "imu/analyze/analyze.hpp"  // imu::analyze::cli_main (host_sim/analyze)
#endif

namespace imu::sim {
namespace {

using imu::cli::AtomicFileWriter;

constexpr const char* kUsageSynth =
    "usage: imu-sim synth [--out FILE] [--N 3.3e-3] [--B 9e-4] [--Tp 300] [--K 1.4e-4]\n"
    "                     [--fs 100] [--duration 10000] [--seed 1] [--lsb 1e-6] [--channel acc_z]\n"
    "       imu-sim synth --model A.json [--out FILE] [--duration 3600] [--fs HZ] [--seed 1]\n"
    "                     [--lsb X]\n"
    "  --model: every channel acc_x..gyro_z of an analyze JSON (--channel all) simulated from\n"
    "  its model_after (white, quantization, GM terms, rate random walk, bias instability,\n"
    "  narrowband oscillation; at most 8 states, as the node runs it: ramp, sinusoids and the\n"
    "  output filter left out, said) at the analysis's rate, one MAT-file.\n"
    "  synthetic recording (MAT-file: channel, fs, acc_lsb/gyro_lsb, source) from the example's\n"
    "  error model plus rate random walk. Ranges: --N --B in [1e-12, 1e3], --K in [0, 1e3],\n"
    "  --Tp in [1e-6, 1e9] s, --fs in [1e-3, 1e6] Hz, --duration x --fs in [16, 2^25] samples,\n"
    "  --seed an integer in [0, 2^53], --lsb in [1e-12, 1e6]; the model's values must fit int32\n"
    "  counts of --lsb.\n";
constexpr const char* kUsageModel =
    "usage: imu-sim model [--N 3.3e-3] [--B 9e-4] [--Tp 300] [--fs 100]\n"
    "  the continuous and discrete first-order model in the example's layout\n";
constexpr const char* kUsageAdev =
    "usage: imu-sim adev FILE [--channel acc_z|all|A,B] [--json OUT] [--csv OUT] [--lsb X]\n"
    "                         [--fs X] [--time-unit s|ms|us|ns] [--estimator online|full]\n"
    "                         [--plots DIR] [--topic NAME]\n"
    "                         [--taus octave|decade|quarter|all]\n"
    "                         [--deviation adev|mdev|hdev|tdev|A,B]\n"
    "  ADEV of a channel, with the time it took. --channel: a variable (NAME, NAME:K column K\n"
    "  of a matrix, imu.acc_z a struct field), a comma list, or all (the channels acc_x..gyro_z\n"
    "  the file holds; a text file without them: every column but the time): the channels in\n"
    "  parallel on the machine's cores, one table each, one JSON ({\"schema_version\", \"command\",\n  \"source\", \"estimator\",\n"
    "  \"channels\": {NAME: ...}}), one CSV with a channel column, --plots DIR: a plot per\n"
    "  channel (DIR/adev_NAME.svg/.png, its .csv and a .gp that runs from any directory; DIR\n"
    "  is created). --estimator full\n"
    "  (default): the fully overlapping estimator on the whole record (allantools oadev,\n"
    "  Stable32; 12 bytes per sample of memory); online: the firmware's fixed-memory estimator\n"
    "  (fw OnlineAdev<8,22>, partially overlapping, constant memory; the node's figures).\n"
    "  --taus as allantools' keywords (default: full, octave; online, its own grid): octave 1, 2, 4, ..; decade 1, 2, 4, 10, 20, 40, ..; quarter\n"
    "  quarter octaves; all every m (full only; refused when it would sum more than 2e9\n"
    "  terms). The table, JSON and CSV carry the averaging factor af = tau / Ts. NaN/Inf samples\n"
    "  are gaps (counted: \"gaps\" in the JSON). The LSB (--lsb, else the file's acc_lsb/gyro_lsb;\n"
    "  without either, full takes float values as they are, \"lsb\": null, and online\n"
    "  quantises to 1e-6 / 1e-7) must fit the data in int32 counts and must not collapse it\n"
    "  (refused: more than 99 % of the samples in one count while the quantised std is under\n"
    "  half the data's). --fs (else the file's fs or Fs, else a text file's time column) in [1e-3, 1e6]\n"
    "  Hz. A text file's time column (t, time, timestamp, %time, timestamp_ns ..) is in the\n"
    "  unit its name or header states ([ns]), else --time-unit's, else the one its steps show\n"
    "  (integer times: the first of s, ms, us, ns giving 1 Hz or more; said in a note).\n"
    "  --deviation (full only; default adev; a comma list for several): adev the overlapping\n"
    "  Allan deviation (allantools oadev); mdev the modified Allan deviation (allantools mdev,\n"
    "  NIST SP 1065 eqn. 14); hdev the overlapping Hadamard deviation (allantools ohdev, eqn.\n"
    "  20); tdev the time deviation tau mdev / sqrt(3) (allantools tdev, eqn. 15), in the\n"
    "  channel's unit times s. Each on the --taus grid up to its own last tau (mdev, tdev:\n"
    "  3 tau <= T; hdev: 3 tau < T), gaps left out as for adev, a 68.3 % interval from the\n"
    "  Greenhall-Riley EDF for white FM (mdev, tdev: of the modified variance). Output: a\n"
    "  table per deviation, the JSON key and the CSV column named by it (several: a CSV\n"
    "  column deviation, the values in column dev); --plots DIR/KIND_NAME.svg.\n"
    "  A ROS bag (format 2.0; chunks uncompressed or LZ4, BZ2 refused) is read as the columns\n"
    "  t_ns (header stamps), acc_x..acc_z (m/s^2), gyro_x..gyro_z (rad/s) of its\n"
    "  sensor_msgs/Imu topic: --topic NAME, needed when it holds several.\n";
constexpr const char* kUsageRun =
    "usage: imu-sim run FILE [--channel acc_z] [--bus loopback|vcan0|can0] [--rate max|realtime]\n"
    "      [--node inproc|spawn|external] [--out DIR] [--json FILE] [--N --B --Tp [--K]]\n"
    "      [--no-plots] [--quiet] [--T-avg 10] [--T-int 20] [--sim-windows 1000] [--seed 2]\n"
    "      [--timeout 30] [--window 4096|256] [--layout auto|fd|classic] [--only-channel]\n"
    "      [--fw PATH] [--lsb X] [--fs X] [--model A.json [--model-as-is]]\n"
    "      (--mat FILE: alias of FILE)\n"
    "  sensor emulator -> bus -> firmware node -> telemetry -> report (text, JSON, CSV, SVG/PNG\n"
    "  plots in DIR, default out/run). --channel: acc_x..gyro_z, or any variable as for adev\n"
    "  (NAME, NAME:K, imu.acc_z), which takes the acc_z slot (gyro*: gyro_z) of the six sent.\n"
    "  FILE: a MAT-file, or text or a ROS bag (its only sensor_msgs/Imu topic) as adev reads\n"
    "  it (the columns on their time grid, written to DIR/input.mat, which the run streams;\n"
    "  said in a note).\n"
    "  --model: the node runs each channel's model_after of an analyze JSON (--channel all: all\n"
    "  six), first tuned to its filter on FILE: the fast terms (N, output filter, GMs whose\n"
    "  corner 1/(2 pi Tb) lies above rate / 1024, the narrowband oscillation, one added where\n"
    "  the spectrum requires it) by the record's Whittle likelihood in the node's discrete\n"
    "  model, said in a note; --model-as-is pushes model_after unchanged.\n"
    "  A sample with NaN/Inf in a channel sent is not sent (the\n"
    "  node counts it missing). LSB and rate rules as for adev. Ranges: --T-avg + --T-int at\n"
    "  most the recording, --sim-windows in [1, 1e5] (x window samples <= 2e8), --seed in\n"
    "  [0, 2^53], --timeout in (0, 86400] s, --window in [0, 1e6].\n";
constexpr const char* kUsageAnalyze =
    "usage: imu-sim analyze FILE --channel NAME [--fs HZ] [--lsb UNITS] [--json OUT] [--plots DIR]\n"
    "  residual of the first-order model against the measured ADEV, effects found, augmented\n"
    "  model (host_sim/analyze)\n";
constexpr const char* kExitCodes =
    "exit status: 0 success, 1 run-time error (bad or unreadable file, data that cannot be\n"
    "processed, bus error, failed write, out of memory), 2 command-line error (unknown option,\n"
    "bad or out-of-range value, an option that does not fit the data); `imu-sim CMD --help`\n";

// The options of synth, range-checked (every number before it becomes a size).
struct SynthOptions {
  double n = 0, b = 0, tp = 0, k = 0, fs = 0, dur = 0, lsb = 0;
  std::uint64_t seed = 0;
  std::size_t count = 0;
  std::size_t chan = 0;
  std::string chan_name;
  std::string out;
};

bool parse_synth(const Args& a, SynthOptions& o, std::string& err) {
  if (!a.number("--N", 3.3e-3, 1e-12, 1e3, o.n, err) ||
      !a.number("--B", 9e-4, 1e-12, 1e3, o.b, err) ||
      !a.number("--Tp", 300.0, 1e-6, 1e9, o.tp, err) ||
      !a.number("--K", 1.4e-4, 0.0, 1e3, o.k, err) ||
      !a.number("--fs", 100.0, kMinFsHz, kMaxFsHz, o.fs, err) ||
      !a.number("--duration", 10000.0, 0.0, 1e12, o.dur, err) ||
      !a.integer("--seed", 1, 0, std::uint64_t{1} << 53U, o.seed, err) ||
      !a.number("--lsb", 1e-6, 1e-12, 1e6, o.lsb, err)) {
    return false;
  }
  o.chan_name = a.get("--channel", "acc_z");
  if (!channel_index(o.chan_name, o.chan)) {
    err = "unknown channel '" + o.chan_name + "' (acc_x acc_y acc_z gyro_x gyro_y gyro_z)";
    return false;
  }
  const double samples = std::round(o.dur * o.fs);
  if (!(samples >= 16.0 && samples <= static_cast<double>(kMaxStreamSamples))) {
    err = "--duration x --fs = " + std::to_string(samples) + " samples, outside [16, " +
          std::to_string(kMaxStreamSamples) + "]";
    return false;
  }
  o.count = static_cast<std::size_t>(samples);
  o.out = a.get("--out", "synth.mat");
  return true;
}

// Draw the samples (exact LSB multiples). kExitUsage if the model's values do not fit int32
// counts of the LSB (a saturated sample would be a wrong number in the file).
// Draw, quantise and write the channel's o.count samples in chunks of 8192 (memory
// independent of the length): `w` holds the header and the small variables, which follow the
// column. Exit status; err set.
int synth_write(const SynthOptions& o, ModelSimulator<4>& sim, mat::MatWriter& w,
                std::string& err) {
  auto start = w.column_start(o.chan_name, o.count);
  if (!start.ok()) {
    err = start.error().message;
    return kExitRuntime;
  }
  const std::vector<std::uint8_t>& small = w.bytes();
  constexpr std::size_t kHeader = 128;
  const std::size_t slash = o.out.rfind('/');
  AtomicFileWriter out;
  if ((slash != std::string::npos && !make_dirs(o.out.substr(0, slash), err)) ||
      !out.open(o.out, err) || !out.write(small.data(), kHeader, err) ||
      !out.write(start.value().data(), start.value().size(), err)) {
    return kExitRuntime;
  }
  constexpr std::size_t kChunk = 8192;
  std::vector<double> z(kChunk);
  std::vector<std::uint8_t> bytes(8U * kChunk);
  for (std::size_t done = 0; done < o.count;) {
    const std::size_t n = std::min(kChunk, o.count - done);
    for (std::size_t i = 0; i < n; ++i) {
      const double x = sim.next();
      const QuantizeResult q = quantize(x, o.lsb);
      if (q.saturated || !std::isfinite(x)) {
        err = "the model's values reach " + imu::cli::num_text(x) +
              ", beyond int32 counts of --lsb " + imu::cli::num_text(o.lsb) +
              " (lower --N/--B/--K or raise --lsb)";
        return kExitUsage;  // `out` removes its temporary file
      }
      z[i] = static_cast<double>(q.counts) * o.lsb;
    }
    mat::MatWriter::encode_doubles(z.data(), n, bytes.data());
    if (!out.write(bytes.data(), 8U * n, err)) {
      return kExitRuntime;
    }
    done += n;
  }
  if (!out.write(small.data() + kHeader, small.size() - kHeader, err) || !out.commit(err)) {
    return kExitRuntime;
  }
  return kExitOk;
}

// The rate analyze gave a channel: "fs_hz" of its object in `json` (0 if absent).
double analysis_fs(const std::string& json, const std::string& name) {
  const std::size_t at = json.find(imu::cli::json_str(name) + ": {");
  const std::size_t fs = at == std::string::npos ? at : json.find("\"fs_hz\": ", at);
  return fs == std::string::npos ? 0.0 : std::strtod(json.c_str() + fs + 9, nullptr);
}

// The analysis JSON of `synth --model` (at most 64 MiB); false with the reason.
bool read_model_json(const std::string& path, std::string& json, std::string& err) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  std::ifstream in(path, std::ios::binary);
  if (ec || !in || size > (std::uintmax_t{64} << 20U)) {
    err = "--model " + path + ": cannot read" +
          (ec || !in ? std::string() : " (larger than 64 MiB)");
    return false;
  }
  std::stringstream buf;
  buf << in.rdbuf();
  json = buf.str();
  return true;
}

// A model record's terms as the node runs them (what `run --model` pushes). The output filter
// is not simulated, said in `dropped`: the node sees the white noise through its averaging
// sampler, where the filter changes a sample's variance by about 1.5 n_filter_s / Ts, but this
// simulator takes point samples, whose variance through the filter is N^2 / (2 tf).
ModelParams params_as_node_runs(const hal::ModelRecord& rec, std::string& dropped) {
  const auto d = [](float v) { return static_cast<double>(v); };
  ModelParams mp{};
  mp.n = d(rec.n);
  mp.q = d(rec.q);
  for (std::size_t g = 0; g < 2; ++g) {
    if (rec.gm_sb[g] > 0.0F && rec.gm_tb_s[g] > 0.0F) {
      mp.gm[mp.n_gm++] = GmParam{d(rec.gm_sb[g]), d(rec.gm_tb_s[g])};
    }
  }
  mp.k = d(rec.k);
  mp.bi = d(rec.bi);
  mp.bi_tau_lo_s = d(rec.bi_tau_lo_s);
  mp.bi_tau_hi_s = d(rec.bi_tau_hi_s);
  mp.osc_sigma = d(rec.osc_sigma);
  mp.osc_f0_hz = d(rec.osc_f0_hz);
  mp.osc_beta_per_s = d(rec.osc_beta_per_s);
  if (rec.n_filter_s > 0.0F) {
    dropped += std::string(dropped.empty() ? "" : "; ") + "output filter (" +
               imu::cli::num_text(d(rec.n_filter_s)) + " s) not simulated: white N";
  }
  return mp;
}

// z.size() samples of the model at fs, quantised to lsb. 0, or the exit status with err.
int simulate_channel(const ModelParams& mp, double fs, std::uint64_t seed, double lsb,
                     const std::string& name, std::vector<double>& z, std::string& err) {
  ContinuousModel<8> cm;
  DiscreteModel<8> dm;
  ModelSimulator<8> sim;
  if (build_model(mp, cm) != ModelStatus::kOk ||
      discretize(cm, 1.0 / fs, dm) != ModelStatus::kOk ||
      sim.configure(dm, seed) != ModelStatus::kOk) {
    err = name + "'s model could not be built or simulated (at most 8 states, the node's "
          "largest filter)";
    return kExitRuntime;
  }
  for (double& v : z) {
    const double x = sim.next();
    const QuantizeResult q = quantize(x, lsb);
    if (q.saturated || !std::isfinite(x)) {
      err = name + ": the model's values reach " + imu::cli::num_text(x) +
            ", beyond int32 counts of the LSB " + imu::cli::num_text(lsb) + " (raise --lsb)";
      return kExitUsage;
    }
    v = static_cast<double>(q.counts) * lsb;
  }
  return 0;
}

// The channel's model in the MAT-file's `source` string.
void append_model_text(std::string& source, const std::string& name, const ModelParams& mp,
                       double lsb) {
  appendf(source, " %s N=%.4g Q=%.4g", name.c_str(), mp.n, mp.q);
  for (std::size_t g = 0; g < mp.n_gm; ++g) {
    appendf(source, " GM(Sb=%.4g,Tb=%.4g s)", mp.gm[g].sb, mp.gm[g].tb_s);
  }
  appendf(source, " K=%.4g B=%.4g", mp.k, mp.bi);
  if (mp.osc_sigma > 0.0) {
    appendf(source, " OSC(sigma=%.4g,f0=%.4g Hz,beta=%.4g/s)", mp.osc_sigma, mp.osc_f0_hz,
            mp.osc_beta_per_s);
  }
  appendf(source, " LSB=%.4g;", lsb);
}

// `synth --model A.json`: every channel acc_x..gyro_z an analysis JSON holds, simulated from
// its model_after (white, quantization, GM terms, rate random walk, bias instability: the
// model the node runs, read by the reader of run --model; ramp and sinusoids are deterministic
// and left out, said) at the analysis's rate (or --fs), quantised to --lsb (else the usual
// default per sensor), into one MAT-file. Memory: the channels are held (8 bytes per sample
// each). Exit status.
int synth_from_model(const Args& a, const char* cmd) {
  std::string err;
  for (const char* opt : {"--N", "--B", "--Tp", "--K", "--channel"}) {
    if (a.has(opt)) {
      return fail(cmd, std::string(opt) + " and --model both give the model: use one",
                  kExitUsage);
    }
  }
  double dur = 0.0;
  double fs_opt = 0.0;
  double lsb_opt = 0.0;
  std::uint64_t seed = 0;
  if (!a.number("--duration", 3600.0, 0.0, 1e12, dur, err) ||
      (a.has("--fs") && !a.number("--fs", 0.0, kMinFsHz, kMaxFsHz, fs_opt, err)) ||
      (a.has("--lsb") && !a.number("--lsb", 0.0, 1e-12, 1e6, lsb_opt, err)) ||
      !a.integer("--seed", 1, 0, std::uint64_t{1} << 53U, seed, err)) {
    return fail(cmd, err, kExitUsage);
  }
  const std::string path = a.get("--model");
  const std::string out = a.get("--out", "synth.mat");
  std::string json;
  if (!read_model_json(path, json, err)) {
    return fail(cmd, err);
  }
  mat::MatWriter w;
  std::string source = "SYNTHETIC data from imu-sim synth --model " + path + ":";
  std::size_t written = 0;
  double fs_all = 0.0;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    const std::string name = kChannelNames[c];
    if (!analysis_holds_channel(json, name)) {
      continue;
    }
    hal::ModelRecord rec{};
    std::string dropped;
    if (!model_from_analysis_json(json, name, c, rec, dropped, err)) {
      return fail(cmd, path + ": " + err);  // NOLINT(performance-inefficient-string-concatenation)
    }
    const double fs = fs_opt > 0.0 ? fs_opt : analysis_fs(json, name);
    if (!(fs >= kMinFsHz && fs <= kMaxFsHz) || (fs_all > 0.0 && std::fabs(fs - fs_all) > 0.0)) {
      std::string msg = path;
      msg += ": " + name + ": no rate, or not the other channels' (give --fs)";
      return fail(cmd, msg, kExitUsage);
    }
    fs_all = fs;
    const double samples = std::round(dur * fs);
    if (!(samples >= 16.0 && samples <= static_cast<double>(std::size_t{1} << 26U))) {
      return fail(cmd, "--duration x rate = " + std::to_string(samples) +
                           " samples, outside [16, 2^26] per channel", kExitUsage);
    }
    const ModelParams mp = params_as_node_runs(rec, dropped);
    const double lsb = lsb_opt > 0.0 ? lsb_opt : default_lsb(c);
    std::vector<double> z(static_cast<std::size_t>(samples));
    if (const int status = simulate_channel(mp, fs, seed + c, lsb, name, z, err); status != 0) {
      std::string msg = path;
      msg += ": " + err;
      return fail(cmd, msg, status);
    }
    if (auto st = w.add_column(name, z); !st.ok()) {
      return fail(cmd, st.error().message);
    }
    append_model_text(source, name, mp, lsb);
    if (!dropped.empty()) {
      std::printf("note: %s: simulated as the node runs it: %s\n", name.c_str(),
                  imu::cli::term_safe(dropped).c_str());
    }
    ++written;
  }
  if (written == 0) {
    return fail(cmd, path + ": no channel acc_x..gyro_z in it (imu-sim analyze FILE --channel "
                     "all --json A.json writes one)");
  }
  appendf(source, " %g Hz, seed %llu", fs_all, static_cast<unsigned long long>(seed));
  auto st = w.add_scalar("fs", fs_all);
  if (st.ok()) {
    st = w.add_string("source", source);
  }
  if (!st.ok()) {
    return fail(cmd, st.error().message);
  }
  const std::size_t slash = out.rfind('/');
  if ((slash != std::string::npos && !make_dirs(out.substr(0, slash), err)) ||
      !imu::cli::write_file_atomic(out, std::string(w.bytes().begin(), w.bytes().end()), err)) {
    return fail(cmd, err);
  }
  std::printf("wrote %s: %zu channels at %g Hz, %g s\n%s\n", imu::cli::term_safe(out).c_str(),
              written, fs_all, dur, imu::cli::term_safe(source).c_str());
  return kExitOk;
}

int cmd_synth(int argc, char** argv) {
  const char* cmd = "imu-sim synth";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {{"--out", true},  {"--N", true},        {"--B", true},
                                      {"--Tp", true},   {"--K", true},        {"--fs", true},
                                      {"--duration", true}, {"--seed", true}, {"--lsb", true},
                                      {"--channel", true},  {"--model", true}};
  if (!a.parse(argc, argv, 2, specs, 0, err)) {
    return fail(cmd, err, kExitUsage);
  }
  if (a.help()) {
    return print_help("synth");
  }
  if (a.has("--model")) {
    return synth_from_model(a, cmd);
  }
  SynthOptions o;
  if (!parse_synth(a, o, err)) {
    return fail(cmd, err, kExitUsage);
  }
  FirstOrderGm gm{};
  if (first_order_gm_from_asd(o.n, o.b, o.tp, o.fs, gm) != ModelStatus::kOk) {
    return fail(cmd, "--N, --B, --Tp, --fs do not make a first-order model", kExitUsage);
  }
  ModelParams mp{};
  mp.n = o.n;
  mp.n_gm = 1;
  mp.gm[0] = GmParam{gm.sb, gm.tb_s};
  mp.k = o.k;
  ContinuousModel<4> cm;
  DiscreteModel<4> dm;
  ModelSimulator<4> sim;
  if (build_model(mp, cm) != ModelStatus::kOk || discretize(cm, 1.0 / o.fs, dm) != ModelStatus::kOk ||
      sim.configure(dm, o.seed) != ModelStatus::kOk) {
    return fail(cmd, "the model could not be built or simulated");
  }
  const double t0 = now_s();
  std::string source;
  appendf(source,
          "SYNTHETIC data from imu-sim synth (not a recording: the marble-slab recording of the example is not "
          "public): white N=%.6g, first-order GM B=%.6g Tp=%.6g s, rate random walk K=%.6g, "
          "fs=%.6g Hz, %zu samples, seed %llu, quantized to LSB %.6g",
          o.n, o.b, o.tp, o.k, o.fs, o.count, static_cast<unsigned long long>(o.seed), o.lsb);
  const char* lsb_name = o.chan < 3 ? "acc_lsb" : "gyro_lsb";
  mat::MatWriter w;
  auto st = w.add_scalar("fs", o.fs);
  if (st.ok()) {
    st = w.add_scalar(lsb_name, o.lsb);
  }
  if (st.ok()) {
    st = w.add_string("source", source);
  }
  if (!st.ok()) {
    return fail(cmd, st.error().message);
  }
  const int st_w = synth_write(o, sim, w, err);
  if (st_w != kExitOk) {
    return fail(cmd, err, st_w);
  }
  std::printf("wrote %s: %s (%zu samples at %g Hz, %g s), fs, %s\n%s\ntook %.2f s\n",
              o.out.c_str(), o.chan_name.c_str(), o.count, o.fs, o.dur, lsb_name, source.c_str(),
              now_s() - t0);
  return kExitOk;
}

int cmd_model(int argc, char** argv) {
  const char* cmd = "imu-sim model";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {{"--N", true}, {"--B", true}, {"--Tp", true}, {"--fs", true}};
  if (!a.parse(argc, argv, 2, specs, 0, err)) {
    return fail(cmd, err, kExitUsage);
  }
  if (a.help()) {
    return print_help("model");
  }
  double n = 0, b = 0, tp = 0, fs = 0;
  if (!a.number("--N", 3.3e-3, n, err) || !a.number("--B", 9e-4, b, err) ||
      !a.number("--Tp", 300.0, tp, err) || !a.number("--fs", 100.0, fs, err)) {
    return fail(cmd, err, kExitUsage);
  }
  FirstOrderGm gm{};
  if (first_order_gm_from_asd(n, b, tp, fs, gm) != ModelStatus::kOk) {
    return fail(cmd, "--N, --B, --Tp, --fs must be finite and > 0", kExitUsage);
  }
  std::fputs(format_first_order_model(gm).c_str(), stdout);
  return kExitOk;
}

// The ADEV of one channel with its non-finite samples as gaps (stream_counts() splits the
// record: samples before the first and after the last finite one are not part of the series,
// as for the node, whose receiver starts at the first sample it gets; each run of non-finite
// samples inside is one mark_missing()).
class AdevSink final : public CountSink {
 public:
  explicit AdevSink(OnlineAdev<8, 22>& adev) : adev_(adev) {}
  void push(const std::int32_t* counts, std::size_t n) override { adev_.push_block(counts, n); }
  void gap(std::size_t n) override { adev_.mark_missing(n); }

 private:
  OnlineAdev<8, 22>& adev_;
};

struct AdevTiming {
  double read, quantize, adev, total;
};

// The unit of a channel: its slot's for acc*/gyro* names (the last field of a struct's), else
// the file's own (unknown here).
std::string adev_unit(const std::string& chan_name, std::size_t chan) {
  const std::string field = chan_name.substr(chan_name.rfind('.') + 1);  // imu.acc_z: acc_z
  const bool known = field.rfind("acc", 0) == 0 || field.rfind("gyro", 0) == 0;
  return known ? channel_unit(chan) : "(the file's unit)";
}

// The options of adev, checked (usage errors) before any file is opened.
struct AdevOptions {
  std::string path;
  std::string spec;  // --channel: NAME, NAME:K, a comma list or `all`
  std::string estimator;
  std::string taus;  // "" : the online estimator's own grid
  std::vector<Deviation> devs;  // --deviation, in the order given
  bool full = false;
  double lsb = 0.0;  // 0: the file's or the default
  double fs = 0.0;   // 0: the file's
  double time_unit_s = 0.0;  // --time-unit; 0: the time column's own
  std::string topic;  // --topic: a ROS bag's sensor_msgs/Imu topic ("": its only one)
};

bool parse_adev(const Args& a, AdevOptions& o, std::string& err) {
  o.estimator = a.get("--estimator", "full");
  o.full = o.estimator == "full";
  if (!o.full && o.estimator != "online") {
    err = "--estimator " + o.estimator + ": online or full";
    return false;
  }
  o.taus = a.get("--taus", o.full ? "octave" : "");
  std::vector<std::uint64_t> probe;
  if (!o.taus.empty() && !tau_grid(o.taus, 1000, probe)) {
    err = "--taus " + o.taus + ": octave, decade, quarter or all";
    return false;
  }
  if (o.taus == "all" && !o.full) {
    err = "--taus all needs --estimator full (the online estimator has its own grid)";
    return false;
  }
  if (!parse_deviations(a.get("--deviation", "adev"), o.devs, err)) {
    err = "--deviation " + err;
    return false;
  }
  if (!o.full && (o.devs.size() > 1 || o.devs[0] != Deviation::kAdev)) {
    err = "--deviation " + a.get("--deviation") +
          " needs --estimator full (the online estimator computes adev only)";
    return false;
  }
  if (a.positional().empty()) {
    err = "a MAT-file or text file is required: imu-sim adev FILE --channel C";
    return false;
  }
  o.path = a.positional()[0];
  o.spec = a.get("--channel", "acc_z");
  o.topic = a.get("--topic");
  return (!a.has("--lsb") || a.number("--lsb", 0.0, 1e-12, 1e6, o.lsb, err)) &&
         (!a.has("--fs") || a.number("--fs", 0.0, kMinFsHz, kMaxFsHz, o.fs, err)) &&
         imu::cli::time_unit_option(a, o.time_unit_s, err);
}

// One deviation's rows.
struct DevRows {
  Deviation kind = Deviation::kAdev;
  std::vector<AdevRow> rows;
};

// One channel's ADEV: what it was read as, its rows, the time each step took, or its error.
struct AdevResult {
  std::string name;  // as named on the command line
  std::size_t chan = 0;  // its slot: acc_x..gyro_z, else acc_z (gyro* names: gyro_z) for the
                         // default LSB and the unit
  SensorData sd;
  std::vector<DevRows> devs;  // one per --deviation, in its order
  AdevTiming t{};
  std::string err;
  int status = kExitOk;
  // Text input with several channels: the column read in the run's one pass, and its rate
  // (nullptr: the channel streams the file on its own).
  const std::vector<double>* read_samples = nullptr;
  double read_fs_hz = 0.0;
  std::string time_note;  // how a text time column's unit was found, if from its steps
};

// Several text columns read in one pass over the file (imu::cli::TextColumnStream), each on
// the grid, when they fit kOnePassSamples values; else none (each channel then streams the
// file: at most kMaxStreamedColumns of them). Exit status; err set.
constexpr std::size_t kOnePassSamples = std::size_t{1} << 26U;  // 512 MiB of doubles
constexpr std::size_t kMaxStreamedColumns = 16;
int read_text_columns(const AdevOptions& o, const std::vector<std::string>& names,
                      std::vector<std::vector<double>>& cols, double& fs_hz, std::string& note,
                      std::string& err) {
  cols.assign(names.size(), {});
  imu::cli::TextColumnStream st;
  if (!st.open(o.path, names, o.fs, err, o.time_unit_s, o.topic)) {
    const bool usage = err.rfind("no column", 0) == 0;
    err = err.rfind(o.path, 0) == 0 ? err : o.path + ": " + err;
    return usage ? kExitUsage : kExitRuntime;
  }
  fs_hz = st.fs_hz();
  note = st.time_note();
  const std::size_t k = names.size();
  constexpr std::size_t kChunk = 4096;
  std::vector<double> buf(kChunk * k);
  std::size_t held = 0;
  for (;;) {
    std::size_t got = 0;
    if (!st.read(buf.data(), kChunk, got, err)) {
      if (err.rfind(o.path, 0) != 0) {
        err.insert(0, o.path + ": ");
      }
      return kExitRuntime;
    }
    if (got == 0) {
      return kExitOk;
    }
    held += got * k;
    if (held > kOnePassSamples) {
      cols.clear();
      if (k > kMaxStreamedColumns) {
        err = o.path + ": " + std::to_string(k) + " channels of over " +
              std::to_string(held / k) + " samples are more than one pass holds (" +
              std::to_string(kOnePassSamples) + " values); name at most " +
              std::to_string(kMaxStreamedColumns) + " with --channel";
        return kExitUsage;
      }
      return kExitOk;
    }
    for (std::size_t i = 0; i < got; ++i) {
      for (std::size_t c = 0; c < k; ++c) {
        cols[c].push_back(buf[i * k + c]);
      }
    }
  }
}

// Rate, LSB and length of the channel: a text column's rate from its first rows (the samples
// are streamed later, their number known at the end), or a MAT variable's header. Exit status;
// r.err set.
int adev_load(const AdevOptions& o, bool text, AdevResult& r) {
  ChannelVars vars;
  bool renamed = false;
  if (!channel_slot(r.name, r.chan, vars, renamed, r.err)) {
    return kExitUsage;
  }
  if (text) {
    if (r.read_samples != nullptr) {
      r.sd.fs_hz = r.read_fs_hz;
    } else {
      imu::cli::TextColumnStream probe;
      if (!probe.open(o.path, r.name, o.fs, r.err, o.time_unit_s, o.topic)) {
        const bool usage = r.err.rfind("no column", 0) == 0;  // like a MAT variable not found
        r.err = r.err.rfind(o.path, 0) == 0 ? r.err : o.path + ": " + r.err;
        return usage ? kExitUsage : kExitRuntime;
      }
      r.sd.fs_hz = probe.fs_hz();
      r.time_note = probe.time_note();
    }
    r.sd.path = o.path;
    ChannelData& ch = r.sd.ch[r.chan];
    ch.present = true;
    ch.lsb = o.lsb > 0.0 ? o.lsb : default_lsb(r.chan);
    ch.lsb_from_option = o.lsb > 0.0;
    if (!(r.sd.fs_hz >= kMinFsHz && r.sd.fs_hz <= kMaxFsHz)) {
      r.err = o.path + ": the time column gives " + imu::cli::num_text(r.sd.fs_hz) +
              " Hz, outside [1e-3, 1e6] Hz (give --fs)";
      return kExitRuntime;
    }
    return kExitOk;
  }
  bool want[kNumChannels] = {};
  double lsb_over[kNumChannels] = {};
  want[r.chan] = true;
  lsb_over[r.chan] = o.lsb;
  if (!load_sensor_meta(o.path, want, want, lsb_over, o.fs, r.sd, r.err,
                        renamed ? &vars : nullptr)) {
    return renamed && r.err.find("not found") != std::string::npos ? kExitUsage : kExitRuntime;
  }
  return kExitOk;
}

// The ADEV of a loaded channel: the counts streamed (MAT) or fed (text) into the estimator.
// Exit status; r.devs and r.t set, or r.err.
int adev_compute(const AdevOptions& o, bool text, double t0, AdevResult& r) {
  ChannelData& ch = r.sd.ch[r.chan];
  std::vector<std::uint64_t> grid;
  // The tau grid and the full estimator's cost: before reading a MAT variable (its length is in
  // its header), after streaming a text column (its length is known at its end).
  const auto plan = [&]() {
    grid.clear();
    if (!o.taus.empty()) {
      (void)tau_grid(o.taus, r.sd.n_samples, grid);  // the keyword was checked by parse_adev
    }
    const double cost =
        o.full ? full_adev_cost(r.sd.n_samples, grid) * static_cast<double>(o.devs.size()) : 0.0;
    if (cost > 2e9) {
      r.err = "--taus " + o.taus + " on " + std::to_string(r.sd.n_samples) +
              " samples would sum " + imu::cli::num_text(cost) +
              (o.devs.size() == 1 && o.devs[0] == Deviation::kAdev ? " second differences"
                                                                    : " differences") +
              " (limit 2e9): use --taus quarter or octave";
      return false;
    }
    return true;
  };
  if (!text && !plan()) {
    return kExitUsage;
  }
  StreamTiming tm;
  TextChannelSource text_src(o.path, r.name, o.fs, o.time_unit_s, o.topic, r.read_samples);
  const auto feed = [&](CountSink& sink) {
    int st = text ? stream_counts(text_src, o.path + ": column '" + r.name + "': ", ch, sink, tm,
                                  r.err)
                  : stream_counts(o.path, r.chan, ch, sink, tm, r.err);
    if (st == kExitOk && text) {
      r.sd.n_samples = static_cast<std::size_t>(text_src.samples());
      st = plan() ? kExitOk : kExitUsage;
    }
    return st;
  };
  if (o.full) {
    // Float data without an LSB (none given, none in the file) needs no grid: its values are
    // kept as they are, as allantools takes them.
    ch.no_grid = !ch.lsb_from_option && !ch.lsb_from_file && !ch.integer_counts;
    FullAdevSink sink(ch.no_grid);
    const int st = feed(sink);
    if (st != kExitOk) {
      return st;
    }
    for (const Deviation d : o.devs) {
      r.devs.push_back(DevRows{d, full_deviation(sink, d, grid, 1.0 / r.sd.fs_hz, ch.lsb)});
    }
  } else {
    OnlineAdev<8, 22> adev(1.0 / r.sd.fs_hz, ch.lsb);
    AdevSink sink(adev);
    const int st = feed(sink);
    if (st != kExitOk) {
      return st;
    }
    AdevPoint pts[OnlineAdev<8, 22>::kMaxPoints];
    const std::size_t np = adev.snapshot(pts, OnlineAdev<8, 22>::kMaxPoints);
    std::vector<AdevRow> rows = rows_from_points(pts, np);
    if (!grid.empty()) {
      rows = rows_on_grid(rows, grid);
    }
    r.devs.push_back(DevRows{Deviation::kAdev, rows});
  }
  // The times of the interleaved steps are summed: read = metadata + read + inflate.
  const double total = now_s() - t0;
  r.t = AdevTiming{total - tm.quantize_s - tm.sink_s, tm.quantize_s, tm.sink_s, total};
  return kExitOk;
}

// One channel, start to end (the unit of adev's parallel work). Never throws.
void adev_channel(const AdevOptions& o, bool text, AdevResult& r) {
  try {
    const double t0 = now_s();
    r.status = adev_load(o, text, r);
    if (r.status == kExitOk) {
      r.status = adev_compute(o, text, t0, r);
    }
  } catch (const std::bad_alloc&) {
    r.status = kExitRuntime;
    r.err = "out of memory";
  }
}

// The heading and axis name of a deviation, and whether a result is the plain ADEV (its
// output as it was before --deviation).
const char* deviation_title(Deviation d) {
  switch (d) {
    case Deviation::kAdev: return "Allan deviation";
    case Deviation::kMdev: return "modified Allan deviation";
    case Deviation::kHdev: return "overlapping Hadamard deviation";
    case Deviation::kTdev: return "time deviation";
  }
  return "";
}

bool adev_only(const AdevResult& r) {
  return r.devs.size() == 1 && r.devs[0].kind == Deviation::kAdev;
}

void print_adev(FILE* out, const std::string& path, const AdevResult& r) {
  const ChannelData& ch = r.sd.ch[r.chan];
  std::fprintf(out, "%s %s: %zu samples at %g Hz, ", imu::cli::term_safe(path).c_str(),
               imu::cli::term_safe(r.name).c_str(), r.sd.n_samples, r.sd.fs_hz);
  if (ch.no_grid) {
    std::fprintf(out, "values as read (no LSB) %s\n", adev_unit(r.name, r.chan).c_str());
  } else {
    std::fprintf(out, "LSB %g %s%s\n", ch.lsb, adev_unit(r.name, r.chan).c_str(),
                 ch.lsb_from_file ? " (from the file)" : "");
  }
  const bool plain = adev_only(r);
  for (const DevRows& d : r.devs) {
    if (!plain) {
      std::fprintf(out, "%s: %s%s\n", deviation_name(d.kind), deviation_title(d.kind),
                   d.kind == Deviation::kTdev ? " (unit x s)" : "");
    }
    std::fputs(format_adev_table(d.rows, deviation_name(d.kind)).c_str(), out);
  }
  std::fprintf(out, "time: read %.3f s, quantize %.3f s, %s %.3f s, total %.3f s\n", r.t.read,
               r.t.quantize, plain ? "online ADEV" : "deviations", r.t.adev, r.t.total);
  if (ch.non_finite > 0) {
    std::fprintf(out, "note: %llu non-finite samples (NaN/Inf) treated as gaps\n",
                static_cast<unsigned long long>(ch.non_finite));
  }
  if (ch.off_grid > 0) {
    std::fprintf(out, "note: %llu samples off the LSB grid (quantised to it)\n",
                static_cast<unsigned long long>(ch.off_grid));
  }
  if (!r.time_note.empty()) {
    std::fprintf(out, "note: %s\n", imu::cli::term_safe(r.time_note).c_str());
  }
}

// One channel's JSON members (without braces), each line indented by `in`.
std::string adev_members(const AdevResult& r, const std::string& in) {
  const ChannelData& ch = r.sd.ch[r.chan];
  std::string j;
  j += in + "\"channel\": " + json_str(r.name) + ",\n";
  j += in + "\"unit\": " + json_str(adev_unit(r.name, r.chan)) + ",\n";
  j += in + "\"fs_hz\": " + json_num(r.sd.fs_hz) + ",\n";
  j += in + "\"lsb\": " + (ch.no_grid ? std::string("null") : json_num(ch.lsb)) + ",\n";
  j += in + "\"n_samples\": " + std::to_string(r.sd.n_samples) + ",\n";
  j += in + "\"gaps\": {\"samples\": " + std::to_string(ch.non_finite) + "},\n";
  j += in + "\"units\": " + imu::cli::json_units(adev_unit(r.name, r.chan)) + ",\n";
  for (const DevRows& d : r.devs) {
    j += in + json_str(deviation_name(d.kind)) + ": " +
         adev_json_list(d.rows, deviation_name(d.kind)) + ",\n";
  }
  j += in + "\"timing_s\": {\"read\": " + json_num(r.t.read) + ", \"quantize\": " +
       json_num(r.t.quantize) + ", \"adev\": " + json_num(r.t.adev) + ", \"total\": " +
       json_num(r.t.total) + "}\n";
  return j;
}

// {"schema_version", "command", "source", "estimator", "channels": {NAME: {...}}}: one shape
// for one channel or many (host_sim/cli/imu-sim.schema.json).
std::string adev_json(const AdevOptions& o, const std::vector<AdevResult>& rs) {
  std::string j = "{\n" + imu::cli::json_head("adev", o.path, "  ");
  j += "  \"estimator\": " + json_str(o.estimator) + ",\n";
  j += "  \"channels\": {\n";
  for (std::size_t i = 0; i < rs.size(); ++i) {
    j += "    " + json_str(rs[i].name) + ": {\n" + adev_members(rs[i], "      ") + "    }";
    j += i + 1 < rs.size() ? ",\n" : "\n";
  }
  return j + "  }\n}\n";
}

// One channel and one deviation: adev_csv's table named by it; several channels: a first column
// `channel`; several deviations: then a column `deviation`, the values in column `dev`.
std::string adev_csv_all(const std::vector<AdevResult>& rs) {
  const bool chans = rs.size() > 1;
  const bool kinds = rs[0].devs.size() > 1;
  if (!chans && !kinds) {
    return adev_csv(rs[0].devs[0].rows, deviation_name(rs[0].devs[0].kind));
  }
  const std::string head = std::string(chans ? "channel," : "") + (kinds ? "deviation," : "");
  std::string out;
  for (const AdevResult& r : rs) {
    for (const DevRows& d : r.devs) {
      const std::string t = adev_csv(d.rows, kinds ? "dev" : deviation_name(d.kind));
      const std::string prefix = (chans ? r.name + "," : std::string()) +
                                 (kinds ? std::string(deviation_name(d.kind)) + "," : "");
      std::size_t pos = 0;
      for (bool header = true; pos < t.size(); header = false) {
        const std::size_t eol = t.find('\n', pos);
        const std::string line = t.substr(pos, eol - pos);
        if (!header || out.empty()) {
          out += (header ? head : prefix) + line + "\n";
        }
        pos = eol == std::string::npos ? t.size() : eol + 1;
      }
    }
  }
  return out;
}

// One channel's plot in `abs` (an absolute folder): adev_NAME.csv, .gp (runs from any
// directory), and with gnuplot (`have`) .svg and .png: the ADEV with its 68.3 % intervals, the
// unit on the axis, the name as given (noenhanced). False with err.
bool adev_plot(const std::string& abs, bool have, const AdevResult& r, const DevRows& d,
               const std::string& stem, std::string& err) {
  const std::string kind = deviation_name(d.kind);
  std::string upper = kind;
  for (char& c : upper) {
    c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  const std::string unit =
      adev_unit(r.name, r.chan) + (d.kind == Deviation::kTdev ? " x s" : "");
  const std::string base = kind + "_" + stem;
  std::string gp = "cd " + imu::cli::gnuplot_str(abs) + "\n";
  gp += "set datafile separator ','\nset logscale xy\nset format x '10^{%L}'\n";
  gp += "set format y '10^{%L}'\nset grid xtics ytics mxtics mytics lc rgb '#dddddd'\n";
  gp += "set key bottom left box opaque noenhanced\nset xlabel 'tau [s]'\n";
  gp += "set ylabel " +
        imu::cli::gnuplot_str(std::string(deviation_title(d.kind)) + " [" + unit + "]") +
        " noenhanced\n";
  gp += "set title " + imu::cli::gnuplot_str(upper + " of " + r.name + " (" + r.sd.path + ")") +
        " noenhanced\n";
  gp += "plot '" + base + ".csv' skip 1 using 1:3:4:5 with yerrorbars pt 7 ps 0.6 lc rgb ";
  gp += "'#1f77b4' title '" + upper + ", 68.3 % interval'\n";
  const std::string path = abs + "/" + base;
  if (!write_file(path + ".csv", adev_csv(d.rows, kind.c_str()), err) ||
      !write_file(path + ".gp", gp, err)) {
    return false;
  }
  if (!have) {
    std::printf("plots: gnuplot NOT FOUND: %s.{csv,gp} written, no SVG/PNG\n",
                imu::cli::term_safe(path).c_str());
  } else if (!imu::cli::gnuplot_render(abs, base, 700)) {
    err = "gnuplot failed on " + path + ".gp (see " + base + ".gnuplot.log)";
    return false;
  } else {
    std::printf("plots: %s.{svg,png}\n", imu::cli::term_safe(path).c_str());
  }
  return true;
}

// --plots DIR (created): a plot per channel and deviation (adev_plot). False with err.
bool adev_plots(const std::string& dir, const std::vector<AdevResult>& rs, std::string& err) {
  if (!imu::cli::make_dirs(dir, err)) {
    return false;
  }
  std::error_code ec;
  const std::string abs = std::filesystem::absolute(dir, ec).lexically_normal().string();
  const bool have = imu::cli::gnuplot_available();
  // File names from channel names (user data): one safe component each, distinct.
  std::vector<std::string> names;
  names.reserve(rs.size());
  for (const AdevResult& r : rs) {
    names.push_back(r.name);
  }
  const std::vector<std::string> stems = imu::cli::safe_components(names);
  for (std::size_t i = 0; i < rs.size(); ++i) {
    for (const DevRows& d : rs[i].devs) {
      if (!adev_plot(abs, have, rs[i], d, stems[i], err)) {
        return false;
      }
    }
  }
  return true;
}

// The channels --channel names: from the text file's header (a ROS bag's columns) or the
// MAT-file's variables.
bool adev_channels(const AdevOptions& o, bool text, std::vector<std::string>& names,
                   std::string& err) {
  if (text) {
    const auto rows = imu::cli::open_rows(o.path, o.topic, err);
    return rows != nullptr && imu::cli::text_channels(rows->names(), o.spec, names, err);
  }
  std::vector<std::string> held;
  if (o.spec == "all") {
    auto vars = mat::scan_variables(o.path);
    if (!vars.ok()) {
      err = vars.error().message;
      return false;
    }
    for (const auto& v : vars.value()) {
      held.push_back(v.name);
    }
  }
  if (!imu::cli::expand_channels(o.spec, held, names, err)) {
    err = o.path + ": " + err;
    return false;
  }
  return true;
}

int cmd_adev(int argc, char** argv) {
  const char* cmd = "imu-sim adev";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {{"--channel", true},   {"--json", true}, {"--lsb", true},
                                      {"--fs", true},        {"--csv", true},  {"--taus", true},
                                      {"--estimator", true}, {"--plots", true},
                                      {"--time-unit", true}, {"--deviation", true},
                                      {"--topic", true}};
  if (!a.parse(argc, argv, 2, specs, 1, err)) {
    return fail(cmd, err, kExitUsage);
  }
  if (a.help()) {
    return print_help("adev");
  }
  AdevOptions o;
  if (!parse_adev(a, o, err)) {
    return fail(cmd, err, kExitUsage);
  }
  // Text input (CSV/TSV/blank-separated with a header; imu/cli/text_input.hpp) and ROS bags
  // (imu/cli/rosbag.hpp), both read as rows (imu/cli/row_source.hpp): streamed, as a MAT-file is.
  const bool bag = imu::cli::looks_like_bag(o.path);
  const bool text = bag || imu::cli::looks_like_text(o.path);
  if (!bag && !o.topic.empty()) {
    return fail(cmd, "--topic " + o.topic + ": " + o.path + " is not a ROS bag (--topic reads one)",
                kExitUsage);
  }
  if (bag && o.time_unit_s > 0.0) {
    return fail(cmd, "--time-unit: " + o.path + " is a ROS bag, whose header stamps are in ns",
                kExitUsage);
  }
  std::vector<std::string> names;
  if (!adev_channels(o, text, names, err)) {
    return fail(cmd, err,
                err.find("empty name") != std::string::npos || imu::cli::names_missing_channel(err)
                    ? kExitUsage
                    : kExitRuntime);
  }
  if (o.lsb > 0.0 && names.size() > 1) {
    return fail(cmd, "--lsb applies to one channel; with several, each takes its LSB from the file",
                kExitUsage);
  }
  // Output paths are checked before the work.
  for (const char* opt : {"--json", "--csv"}) {
    if (a.has(opt) && !imu::cli::check_output_path(a.get(opt), err)) {
      return fail(cmd, std::string(opt) + ": " + err, kExitUsage);
    }
  }
  if (a.get("--json") == "-" && a.get("--csv") == "-") {
    return fail(cmd, "--json - and --csv - cannot both be standard output", kExitUsage);
  }
  if (a.has("--plots") && !imu::cli::check_output_dir(a.get("--plots"), err)) {
    return fail(cmd, "--plots: " + err, kExitUsage);
  }
  // The channels in parallel, reported in the order named. Several text columns are read in
  // one pass; a MAT variable (or one text column) is streamed from the file on its own: memory
  // per channel is constant.
  std::vector<AdevResult> rs(names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    rs[i].name = names[i];
  }
  std::vector<std::vector<double>> text_cols;
  if (text && names.size() > 1) {
    double fs_hz = 0.0;
    std::string note;
    const int st = read_text_columns(o, names, text_cols, fs_hz, note, err);
    if (st != kExitOk) {
      return fail(cmd, err, st);
    }
    for (std::size_t i = 0; i < text_cols.size(); ++i) {
      rs[i].read_samples = &text_cols[i];
      rs[i].read_fs_hz = fs_hz;
      rs[i].time_note = note;
    }
  }
  imu::cli::parallel_for(rs.size(), [&](std::size_t i) {
    adev_channel(o, text, rs[i]);
  });
  for (const AdevResult& r : rs) {
    if (r.status != kExitOk) {
      return fail(cmd, (rs.size() > 1 ? r.name + ": " : std::string()) + r.err, r.status);
    }
  }
  // With --json - or --csv -, standard output carries that document alone: the tables go to
  // standard error.
  FILE* info = a.get("--json") == "-" || a.get("--csv") == "-" ? stderr : stdout;
  for (const AdevResult& r : rs) {
    print_adev(info, o.path, r);
  }
  if ((a.has("--json") && !write_file(a.get("--json"), adev_json(o, rs), err)) ||
      (a.has("--csv") && !write_file(a.get("--csv"), adev_csv_all(rs), err)) ||
      (a.has("--plots") && !adev_plots(a.get("--plots"), rs, err))) {
    return fail(cmd, err);
  }
  return kExitOk;
}

int dispatch(const std::string& sub, int argc, char** argv) {
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
#ifdef IMU_HAVE_ANALYZE
  return imu::analyze::cli_main(argc - 1, argv + 1);
#else
  return fail("imu-sim", "analyze: not built");
#endif
}

}  // namespace

const char* command_usage(const std::string& cmd) {
  if (cmd == "synth") {
    return kUsageSynth;
  }
  if (cmd == "model") {
    return kUsageModel;
  }
  if (cmd == "adev") {
    return kUsageAdev;
  }
  if (cmd == "run") {
    return kUsageRun;
  }
  if (cmd == "analyze") {
    return kUsageAnalyze;
  }
  return "";
}

int print_help(const std::string& cmd) {
  std::fputs(command_usage(cmd), stdout);
  std::fputs(kExitCodes, stdout);
  return kExitOk;
}

int cli_main(int argc, char** argv) {
  const auto usage = [](std::FILE* to) {
    std::fputs("usage: imu-sim <command> [options]   (imu-sim <command> --help; imu-sim --version)\n",
               to);
    for (const char* c : {"synth", "model", "adev", "run", "analyze"}) {
      std::fputs(command_usage(c), to);
    }
    std::fputs(kExitCodes, to);
  };
  if (argc < 2) {
    usage(stderr);
    return kExitUsage;
  }
  const std::string sub = argv[1];
  if (sub == "-h" || sub == "--help" || sub == "help") {
    usage(stdout);
    return kExitOk;
  }
  if (sub == "--version" || sub == "version") {
    std::printf("imu-sim %s\n", IMU_VERSION);
    return kExitOk;
  }
  if (command_usage(sub)[0] == '\0') {
    const std::string near =
        imu::cli::closest(sub, {"synth", "model", "adev", "run", "analyze"});
    std::fprintf(stderr, "imu-sim: unknown command '%s'%s (synth, model, adev, run, analyze; "
                 "imu-sim --help)\n", imu::cli::term_safe(sub).c_str(),
                 near.empty() ? "" : ("; did you mean " + near + "?").c_str());
    return kExitUsage;
  }
  // Sizes are checked before they are allocated; this is the last line of defence (a machine
  // short of memory): one line, exit 1, and no exception escapes.
  try {
    return dispatch(sub, argc, argv);
  } catch (const std::bad_alloc&) {
    return fail(("imu-sim " + sub).c_str(), "out of memory");
  } catch (const std::length_error&) {
    return fail(("imu-sim " + sub).c_str(), "out of memory (a size beyond the address space)");
  }
}

}  // namespace imu::sim

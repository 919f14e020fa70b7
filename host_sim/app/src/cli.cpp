// imu-sim: subcommand dispatch, synth, model and adev (run is in run.cpp).
#include "imu/sim/cli.hpp"

#include <cmath>
#include <cstdio>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "common.hpp"
#include "data.hpp"
#include "full_adev.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/cli/text_input.hpp"
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

using imu::cli::AtomicFileWriter;

constexpr const char* kUsageSynth =
    "usage: imu-sim synth [--out FILE] [--N 3.3e-3] [--B 9e-4] [--Tp 300] [--K 1.4e-4]\n"
    "                     [--fs 100] [--duration 10000] [--seed 1] [--lsb 1e-6] [--channel acc_z]\n"
    "  synthetic recording (MAT-file: channel, fs, acc_lsb/gyro_lsb, source) from the seed's\n"
    "  error model plus rate random walk. Ranges: --N --B in [1e-12, 1e3], --K in [0, 1e3],\n"
    "  --Tp in [1e-6, 1e9] s, --fs in [1e-3, 1e6] Hz, --duration x --fs in [16, 2^25] samples,\n"
    "  --seed an integer in [0, 2^53], --lsb in [1e-12, 1e6]; the model's values must fit int32\n"
    "  counts of --lsb.\n";
constexpr const char* kUsageModel =
    "usage: imu-sim model [--N 3.3e-3] [--B 9e-4] [--Tp 300] [--fs 100]\n"
    "  the continuous and discrete first-order model in the seed's layout\n";
constexpr const char* kUsageAdev =
    "usage: imu-sim adev FILE [--channel acc_z] [--json OUT] [--csv OUT] [--lsb X] [--fs X]\n"
    "                         [--estimator online|full] [--taus octave|decade|quarter|all]\n"
    "  ADEV of one channel, with the time it took. --estimator online (default): the firmware's\n"
    "  fixed-memory estimator (fw OnlineAdev<8,22>, partially overlapping, constant memory);\n"
    "  full: the fully overlapping estimator on the whole record (allantools oadev, Stable32;\n"
    "  12 bytes per sample of memory). --taus as allantools' keywords (default: online, its own\n"
    "  grid; full, octave): octave 1, 2, 4, ..; decade 1, 2, 4, 10, 20, 40, ..; quarter\n"
    "  quarter octaves; all every m (full only; refused when it would sum more than 2e9\n"
    "  terms). The table, JSON and CSV carry the averaging factor af = tau / Ts. NaN/Inf samples\n"
    "  are gaps (counted: \"gaps\" in the JSON). The LSB (--lsb, else the file's acc_lsb/gyro_lsb,\n"
    "  else 1e-6 / 1e-7) must fit the data in int32 counts and must not collapse it (refused:\n"
    "  more than 99 % of the samples in one count while the quantised std is under half the\n"
    "  data's). --fs (else the file's fs or Fs) in [1e-3, 1e6] Hz.\n";
constexpr const char* kUsageRun =
    "usage: imu-sim run FILE [--channel acc_z] [--bus loopback|vcan0|can0] [--rate max|realtime]\n"
    "      [--node inproc|spawn|external] [--out DIR] [--json FILE] [--N --B --Tp [--K]]\n"
    "      [--no-plots] [--quiet] [--T-avg 10] [--T-int 20] [--sim-windows 1000] [--seed 2]\n"
    "      [--timeout 30] [--window 4096|256] [--layout auto|fd|classic] [--only-channel]\n"
    "      [--fw PATH] [--lsb X] [--fs X] [--model A.json]  (--mat FILE: alias of FILE)\n"
    "  sensor emulator -> bus -> firmware node -> telemetry -> report (text, JSON, CSV, SVG/PNG\n"
    "  plots in DIR, default out/run). A sample with NaN/Inf in a channel sent is not sent (the\n"
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

// The options of synth, range-checked (issue 13: every number before it becomes a size).
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
// Draw, quantise and write the channel's o.count samples in chunks of 8192 (issue 14: memory
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
        err = "the model's values reach " + std::to_string(x) +
              ", beyond int32 counts of --lsb " + std::to_string(o.lsb) +
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

int cmd_synth(int argc, char** argv) {
  const char* cmd = "imu-sim synth";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {{"--out", true},  {"--N", true},        {"--B", true},
                                      {"--Tp", true},   {"--K", true},        {"--fs", true},
                                      {"--duration", true}, {"--seed", true}, {"--lsb", true},
                                      {"--channel", true}};
  if (!a.parse(argc, argv, 2, specs, 0, err)) {
    return fail(cmd, err, kExitUsage);
  }
  if (a.help()) {
    return print_help("synth");
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
          "SYNTHETIC data from imu-sim synth (not a recording: the seed's marble-slab data is not "
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
  std::fputs(format_seed_model(gm).c_str(), stdout);
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

// The unit of a channel: its slot's for acc*/gyro* names, else the file's own (unknown here).
std::string adev_unit(const std::string& chan_name, std::size_t chan) {
  const std::string field = chan_name.substr(chan_name.rfind('.') + 1);  // imu.acc_z: acc_z
  const bool known = field.rfind("acc", 0) == 0 || field.rfind("gyro", 0) == 0;
  return known ? channel_unit(chan) : "(the file's unit)";
}

std::string adev_json(const std::string& path, const std::string& chan_name, std::size_t chan,
                      const SensorData& sd, std::size_t n, const std::vector<AdevRow>& rows,
                      const AdevTiming& t, const std::string& estimator) {
  const ChannelData& ch = sd.ch[chan];
  std::string j = "{\n";
  j += "  \"source\": " + json_str(path) + ",\n";
  j += "  \"estimator\": " + json_str(estimator) + ",\n";
  j += "  \"channel\": " + json_str(chan_name) + ",\n";
  j += "  \"unit\": " + json_str(adev_unit(chan_name, chan)) + ",\n";
  j += "  \"fs_hz\": " + json_num(sd.fs_hz) + ",\n";
  j += "  \"lsb\": " + json_num(ch.lsb) + ",\n";
  j += "  \"n_samples\": " + std::to_string(n) + ",\n";
  j += "  \"gaps\": " + std::to_string(ch.non_finite) + ",\n";
  j += "  \"adev\": " + adev_json_list(rows) + ",\n";
  j += "  \"timing_s\": {\"read\": " + json_num(t.read) + ", \"quantize\": " +
       json_num(t.quantize) + ", \"adev\": " + json_num(t.adev) + ", \"total\": " +
       json_num(t.total) + "}\n}\n";
  return j;
}

int cmd_adev(int argc, char** argv) {
  const char* cmd = "imu-sim adev";
  Args a;
  std::string err;
  const std::vector<OptSpec> specs = {{"--channel", true},   {"--json", true}, {"--lsb", true},
                                      {"--fs", true},        {"--csv", true},  {"--taus", true},
                                      {"--estimator", true}};
  if (!a.parse(argc, argv, 2, specs, 1, err)) {
    return fail(cmd, err, kExitUsage);
  }
  if (a.help()) {
    return print_help("adev");
  }
  const std::string estimator = a.get("--estimator", "online");
  const bool full = estimator == "full";
  if (!full && estimator != "online") {
    return fail(cmd, "--estimator " + estimator + ": online or full", kExitUsage);
  }
  const std::string taus = a.get("--taus", full ? "octave" : "");
  std::vector<std::uint64_t> probe;
  if (!taus.empty() && !tau_grid(taus, 1000, probe)) {
    return fail(cmd, "--taus " + taus + ": octave, decade, quarter or all", kExitUsage);
  }
  if (taus == "all" && !full) {
    return fail(cmd, "--taus all needs --estimator full (the online estimator has its own grid)",
                kExitUsage);
  }
  if (a.positional().empty()) {
    return fail(cmd, "a MAT-file is required: imu-sim adev FILE --channel C", kExitUsage);
  }
  const std::string path = a.positional()[0];
  std::size_t chan = 0;
  const std::string chan_name = a.get("--channel", "acc_z");
  ChannelVars vars;
  bool renamed = false;
  if (!channel_index(chan_name, chan)) {
    // Any variable of the file, or NAME:K for column K (1-based) of a matrix: it takes the
    // acc_z slot (gyro* names the gyro_z slot, for the default LSB and the unit).
    imu::cli::ChannelSpec cs;
    if (!imu::cli::parse_channel_spec(chan_name, cs, err)) {
      return fail(cmd, err, kExitUsage);
    }
    chan = chan_name.substr(chan_name.rfind('.') + 1).rfind("gyro", 0) == 0 ? 5 : 2;
    vars.names[chan] = cs.name;
    vars.columns[chan] = cs.column;
    vars.column_given[chan] = cs.has_column;
    renamed = true;
  }
  double lsb = 0, fs = 0;
  if ((a.has("--lsb") && !a.number("--lsb", 0.0, 1e-12, 1e6, lsb, err)) ||
      (a.has("--fs") && !a.number("--fs", 0.0, kMinFsHz, kMaxFsHz, fs, err))) {
    return fail(cmd, err, kExitUsage);
  }
  const double t0 = now_s();
  bool want[kNumChannels] = {};
  double lsb_over[kNumChannels] = {};
  want[chan] = true;
  lsb_over[chan] = lsb;
  SensorData sd;
  // Text input (CSV/TSV/blank-separated with a header; imu/cli/text_input.hpp): the column is
  // read whole (text files are not streamed), its rate from --fs or a time column.
  const bool text = imu::cli::looks_like_text(path);
  if (text) {
    imu::cli::TextTable table;
    imu::cli::TextChannel tc;
    if (!imu::cli::read_text_table(path, table, err) ||
        !imu::cli::text_channel(table, chan_name, fs, tc, err)) {
      const bool usage = err.rfind("no column", 0) == 0;  // like a MAT variable not found
      return fail(cmd, err.rfind(path, 0) == 0 ? err : path + ": " + err,
                  usage ? kExitUsage : kExitRuntime);
    }
    sd.path = path;
    sd.fs_hz = tc.fs_hz;
    sd.n_samples = tc.samples.size();
    ChannelData& tch = sd.ch[chan];
    tch.present = true;
    tch.values = std::move(tc.samples);
    tch.lsb = lsb > 0.0 ? lsb : default_lsb(chan);
    tch.lsb_from_option = lsb > 0.0;
    if (!(sd.fs_hz >= kMinFsHz && sd.fs_hz <= kMaxFsHz)) {
      return fail(cmd, path + ": the time column gives " + std::to_string(sd.fs_hz) +
                           " Hz, outside [1e-3, 1e6] Hz (give --fs)");
    }
  } else if (!load_sensor_meta(path, want, want, lsb_over, fs, sd, err,
                               renamed ? &vars : nullptr)) {
    return fail(cmd, err, renamed && err.find("not found") != std::string::npos ? kExitUsage
                                                                                : kExitRuntime);
  }
  // The counts into a sink: streamed from a MAT-file, or from a text column's values (finite
  // runs as counts, each run of missing samples between two finite ones as one gap, as
  // stream_counts does).
  const auto feed = [&](CountSink& sink, StreamTiming& timing) {
    ChannelData& c = sd.ch[chan];
    if (!text) {
      return stream_counts(path, chan, c, sink, timing, err);
    }
    std::vector<std::int32_t> counts;
    const int st = to_counts(path, chan, c, counts, err);
    if (st != kExitOk) {
      return st;
    }
    std::size_t i = 0;
    const std::size_t n = c.values.size();
    while (i < n && !std::isfinite(c.values[i])) {
      ++i;
    }
    std::size_t end = n;
    while (end > i && !std::isfinite(c.values[end - 1])) {
      --end;
    }
    while (i < end) {
      std::size_t j = i;
      const bool finite = std::isfinite(c.values[i]);
      while (j < end && std::isfinite(c.values[j]) == finite) {
        ++j;
      }
      if (finite) {
        sink.push(counts.data() + i, j - i);
      } else {
        sink.gap(j - i);
      }
      i = j;
    }
    return kExitOk;
  };
  // The channel in chunks (issue 14: memory independent of the record's length); the times of
  // the interleaved steps are summed.
  ChannelData& ch = sd.ch[chan];
  std::vector<std::uint64_t> grid;
  if (!taus.empty()) {
    (void)tau_grid(taus, sd.n_samples, grid);  // the keyword was checked above
  }
  if (full && full_adev_cost(sd.n_samples, grid) > 2e9) {
    return fail(cmd, "--taus " + taus + " on " + std::to_string(sd.n_samples) +
                         " samples would sum " + std::to_string(full_adev_cost(sd.n_samples, grid)) +
                         " second differences (limit 2e9): use --taus quarter or octave",
                kExitUsage);
  }
  StreamTiming tm;
  std::vector<AdevRow> rows;
  if (full) {
    FullAdevSink sink;
    const int st = feed(sink, tm);
    if (st != kExitOk) {
      return fail(cmd, err, st);
    }
    rows = full_adev(sink, grid, 1.0 / sd.fs_hz, ch.lsb);
  } else {
    OnlineAdev<8, 22> adev(1.0 / sd.fs_hz, ch.lsb);
    AdevSink sink(adev);
    const int st = feed(sink, tm);
    if (st != kExitOk) {
      return fail(cmd, err, st);
    }
    AdevPoint pts[OnlineAdev<8, 22>::kMaxPoints];
    const std::size_t np = adev.snapshot(pts, OnlineAdev<8, 22>::kMaxPoints);
    rows = rows_from_points(pts, np);
    if (!grid.empty()) {
      rows = rows_on_grid(rows, grid);
    }
  }
  const double t3 = now_s();
  const double t1 = t0 + (t3 - t0 - tm.quantize_s - tm.sink_s);  // metadata + read + inflate
  const double t2 = t1 + tm.quantize_s;
  const std::size_t n_samples = sd.n_samples;
  std::printf("%s %s: %zu samples at %g Hz, LSB %g %s%s\n", path.c_str(), chan_name.c_str(),
              n_samples, sd.fs_hz, ch.lsb, adev_unit(chan_name, chan).c_str(),
              ch.lsb_from_file ? " (from the file)" : "");
  std::fputs(format_adev_table(rows).c_str(), stdout);
  std::printf("time: read %.3f s, quantize %.3f s, online ADEV %.3f s, total %.3f s\n", t1 - t0,
              t2 - t1, t3 - t2, t3 - t0);
  if (ch.non_finite > 0) {
    std::printf("note: %llu non-finite samples (NaN/Inf) treated as gaps\n",
                static_cast<unsigned long long>(ch.non_finite));
  }
  if (ch.off_grid > 0) {
    std::printf("note: %llu samples off the LSB grid (quantised to it)\n",
                static_cast<unsigned long long>(ch.off_grid));
  }
  if (a.has("--json") &&
      !write_file(a.get("--json"),
                  adev_json(path, chan_name, chan, sd, n_samples, rows,
                            AdevTiming{t1 - t0, t2 - t1, t3 - t2, t3 - t0}, estimator),
                  err)) {
    return fail(cmd, err);
  }
  if (a.has("--csv") && !write_file(a.get("--csv"), adev_csv(rows), err)) {
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
    std::fputs("usage: imu-sim <command> [options]   (imu-sim <command> --help)\n", to);
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
  if (command_usage(sub)[0] == '\0') {
    std::fprintf(stderr, "imu-sim: unknown command '%s' (synth, model, adev, run, analyze; "
                 "imu-sim --help)\n", sub.c_str());
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

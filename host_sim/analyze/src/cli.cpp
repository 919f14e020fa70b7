// `analyze FILE.mat --channel NAME [--fs HZ] [--lsb UNITS] [--json OUT] [--plots DIR]`, on the
// command-line parser and exit codes every imu-sim subcommand shares (host_sim/cli).
#include <cmath>
#include <cstdio>
#include <new>
#include <string>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/cli/args.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/mat/mat_reader.hpp"

namespace imu::analyze {
namespace {

using imu::cli::kExitOk;
using imu::cli::kExitRuntime;
using imu::cli::kExitUsage;

constexpr const char* kUsage =
    "usage: imu-sim analyze FILE --channel NAME [--fs HZ] [--lsb UNITS] [--json OUT] [--plots DIR]\n"
    "  (also imu-analyze) residual of the first-order model against the measured ADEV and the\n"
    "  bias filter's innovations, effects found, augmented model. --fs (else the file's fs or\n"
    "  Fs) in [1e-3, 1e6] Hz; --lsb (else the file's <group>_lsb, NAME_lsb or lsb) in\n"
    "  [1e-12, 1e6]. NaN/Inf samples are gaps (counted in the report's `gaps`).\n"
    "exit status: 0 success, 1 run-time error (bad or unreadable file, data that cannot be\n"
    "processed, failed write, out of memory), 2 command-line error\n";

int fail(const std::string& msg, int status) {
  std::fprintf(stderr, "imu-sim analyze: %s\n", msg.c_str());
  return status;
}

// The rate: --fs, else the file's `fs`, else its `Fs`.
bool file_rate(const imu::mat::MatFile& m, const std::string& file, double& fs_hz,
               std::string& err) {
  for (const char* name : {"fs", "Fs"}) {
    auto f = m.read_scalar(name);
    if (f.ok()) {
      fs_hz = f.value();
      if (!(fs_hz >= 1e-3 && fs_hz <= 1e6)) {
        err = file + ": " + name + " = " + std::to_string(fs_hz) +
              " Hz is not a rate in [0.001, 1e+06] Hz (give --fs)";
        return false;
      }
      return true;
    }
  }
  err = file + ": no --fs given and no scalar 'fs' or 'Fs' in the file";
  return false;
}

// acc_x -> acc_lsb, gyro_z -> gyro_lsb; also NAME_lsb and lsb. 0 if none.
double file_lsb(const imu::mat::MatFile& m, const std::string& channel) {
  const std::size_t us = channel.find('_');
  const std::string names[3] = {
      us != std::string::npos ? channel.substr(0, us) + "_lsb" : std::string(),
      channel + "_lsb", "lsb"};
  for (const auto& n : names) {
    if (n.empty()) {
      continue;
    }
    auto v = m.read_scalar(n);
    if (v && v.value() > 0.0 && std::isfinite(v.value())) {
      return v.value();
    }
  }
  return 0.0;
}

// The run-time part: read, analyse, print, write. Exit status.
int analyze_file(const std::string& file, const std::string& channel, double fs, double lsb,
                 const std::string& json, const std::string& plots) {
  auto mf = imu::mat::MatFile::open(file);
  if (!mf) {
    return fail(mf.error().message, kExitRuntime);
  }
  const imu::mat::MatFile& m = mf.value();
  auto col = m.read_column(channel);
  if (!col) {
    return fail(col.error().message, kExitRuntime);
  }
  Options o;
  std::string err;
  if (fs > 0.0) {
    o.fs_hz = fs;
  } else if (!file_rate(m, file, o.fs_hz, err)) {
    return fail(err, kExitRuntime);
  }
  o.lsb = lsb > 0.0 ? lsb : file_lsb(m, channel);
  Report r;
  if (!analyze(col.value(), channel, o, r, err)) {
    return fail(err, kExitRuntime);
  }
  if (o.lsb > 0.0 && lsb <= 0.0) {
    r.lsb_note = "LSB from the file: " + r.lsb_note.substr(r.lsb_note.find(':') + 2);
  }
  std::fputs(to_text(r).c_str(), stdout);
  if (!json.empty()) {
    if (!imu::cli::write_file_atomic(json, to_json(r), err)) {
      return fail(err, kExitRuntime);
    }
    std::printf("wrote %s\n", json.c_str());
  }
  if (!plots.empty()) {
    std::string msg;
    if (!write_plots(r, plots, msg)) {
      return fail(msg, kExitRuntime);
    }
    std::printf("%s\n", msg.c_str());
  }
  return kExitOk;
}

}  // namespace

int cli_main(int argc, char** argv) {
  imu::cli::Args a;
  std::string err;
  const std::vector<imu::cli::OptSpec> specs = {
      {"--channel", true}, {"--json", true}, {"--plots", true}, {"--fs", true}, {"--lsb", true}};
  if (!a.parse(argc, argv, 1, specs, 1, err)) {
    return fail(err + " (imu-sim analyze --help)", kExitUsage);
  }
  if (a.help()) {
    std::fputs(kUsage, stdout);
    return kExitOk;
  }
  double fs = 0.0;
  double lsb = 0.0;
  if ((a.has("--fs") && !a.number("--fs", 0.0, 1e-3, 1e6, fs, err)) ||
      (a.has("--lsb") && !a.number("--lsb", 0.0, 1e-12, 1e6, lsb, err))) {
    return fail(err, kExitUsage);
  }
  if (a.positional().empty() || !a.has("--channel")) {
    return fail("FILE and --channel NAME are required (imu-sim analyze --help)", kExitUsage);
  }
  // Sizes are bounded by the MAT reader's budget; this is the last line of defence (a machine
  // short of memory): one line, exit 1, no exception escapes.
  try {
    return analyze_file(a.positional()[0], a.get("--channel"), fs, lsb, a.get("--json"),
                        a.get("--plots"));
  } catch (const std::bad_alloc&) {
    return fail("out of memory", kExitRuntime);
  }
}

}  // namespace imu::analyze

// `analyze FILE.mat --channel NAME|A,B|all [--fs HZ] [--lsb UNITS] [--json OUT] [--plots DIR]
// [--yaml IMU.yaml]`, on the command-line parser and exit codes every imu-sim subcommand
// shares (host_sim/cli).
#include <algorithm>
#include <iterator>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/cli/args.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/cli/json.hpp"
#include "imu/cli/sensors.hpp"
#include "imu/cli/rosbag.hpp"
#include "imu/cli/text_input.hpp"
#include "imu/mat/mat_reader.hpp"

namespace imu::analyze {
namespace {

// Records longer than this are analysed on block means: the analysis keeps several values per
// sample (up to about 50 bytes in flight while the sinusoid search holds its spectrum), so 2^20
// samples (2.9 h at 100 Hz, 17 min at 1 kHz) stay under 64 MB per channel whatever the record's
// length. The ADIS16405 records of imudata (1.008e6 samples at 100 Hz) stay at full rate.
constexpr std::uint64_t kMaxAnalysedSamples = std::uint64_t{1} << 20;

using imu::cli::kExitOk;
using imu::cli::kExitRuntime;
using imu::cli::kExitUsage;

constexpr const char* kUsage =
    "usage: imu-sim analyze FILE --channel NAME|NAME:K|A,B,..|all [--fs HZ] [--lsb UNITS]\n"
    "                         [--time-unit s|ms|us|ns] [--json OUT]\n"
    "                         [--plots DIR] [--yaml IMU.yaml] [--topic NAME]\n"
    "       imu-sim analyze FILE --acc COLS --gyro COLS [--acc-unit g|m/s^2]\n"
    "                         [--gyro-unit rad/s|deg/s|deg/h] [--acc-lsb X] [--gyro-lsb X] ..\n"
    "  NAME:K is column K (1-based) of a matrix NAME; a matrix without :K is refused.\n"
    "  (also imu-analyze) residual of the first-order model against the measured ADEV and the\n"
    "  bias filter's innovations, effects found, augmented model. --channel all: the channels\n"
    "  acc_x..gyro_z the file holds (a comma list: those), analysed in parallel on the machine's\n"
    "  cores; one report, one JSON ({\"schema_version\", \"command\", \"source\", \"channels\":\n"
    "  {NAME: ...}}, for one channel too; host_sim/cli/imu-sim.schema.json). --yaml: Kalibr's\n"
    "  imu.yaml (needs accelerometer and gyroscope channels).\n"
    "  Sensors: --acc/--gyro name each sensor's channels (any names, NAME:K columns; instead of\n"
    "  --channel), else a name tells (acc*, a_*, ax..; gyro*, w_*, gx..); --acc-unit/--gyro-unit\n"
    "  their unit, else the accelerometer's is read from its three axes' mean norm (about 1: g,\n"
    "  about 9.81: m/s^2) and the gyroscope's taken as deg/s beside an accelerometer in g, else\n"
    "  as rad/s, each said in a note; everything is analysed and reported in m/s^2 and rad/s.\n"
    "  --acc-lsb/--gyro-lsb: a sensor's LSB in its unit. --fs (else\n"
    "  the file's fs or Fs, else a text file's time column, in the unit it states or\n"
    "  --time-unit's, else the one its steps show) in [1e-3, 1e6] Hz; --lsb (else the file's <group>_lsb, NAME_lsb or\n"
    "  lsb) in [1e-12, 1e6], for a single channel only. NaN/Inf samples are gaps (counted in\n"
    "  the report's `gaps`). --plots DIR (created if missing): analyze_NAME_adev.csv and\n"
    "  analyze_NAME_{before,after}.{svg,png}, NAME made a safe file name (no ':' or '/').\n"
    "  A channel longer than 2^20 samples is analysed on block means of 2^k samples, and\n"
    "  its first 2^20 samples at full rate for what the means cannot resolve (said in the\n"
    "  report); the file (MAT or text) is\n"
    "  read in chunks, never whole. A ROS bag (format 2.0; chunks uncompressed or LZ4, BZ2\n"
    "  refused) is read as the columns t_ns (header stamps), acc_x..acc_z (m/s^2),\n"
    "  gyro_x..gyro_z (rad/s) of its sensor_msgs/Imu topic: --topic NAME, needed when it holds\n"
    "  several.\n"
    "exit status: 0 success, 1 run-time error (bad or unreadable file, data that cannot be\n"
    "processed, failed write, out of memory), 2 command-line error\n";

// The file's variables through the streaming reader: headers, scalars and the analysed columns
// are read as needed, never the file whole (a long record's file image would be the largest
// thing in memory). The variable list is scanned once.
class StreamedFile {
 public:
  explicit StreamedFile(std::string path) : path_(std::move(path)) {}
  [[nodiscard]] const std::string& display_name() const { return path_; }
  [[nodiscard]] imu::mat::Result<std::vector<imu::mat::VariableInfo>> list_variables() const {
    if (!listed_) {
      listed_ = std::make_unique<imu::mat::Result<std::vector<imu::mat::VariableInfo>>>(
          imu::mat::scan_variables(path_));
    }
    return *listed_;
  }
  [[nodiscard]] imu::mat::Result<double> read_scalar(std::string_view name) const {
    return imu::mat::stream_scalar(path_, name);
  }
  // A whole column, read in chunks from the stream (its checks and messages).
  [[nodiscard]] imu::mat::Result<std::vector<double>> read_column(std::string_view name,
                                                                  std::size_t column) const {
    auto st = imu::mat::ChannelStream::open(path_, name, column);
    if (!st) {
      return st.error();
    }
    std::vector<double> out;
    out.reserve(
        static_cast<std::size_t>(std::min<std::uint64_t>(st.value().size(), kMaxAnalysedSamples)));
    double chunk[4096];
    for (;;) {
      auto got = st.value().read(chunk, std::size(chunk));
      if (!got) {
        return got.error();
      }
      if (got.value() == 0) {
        break;
      }
      out.insert(out.end(), chunk, chunk + got.value());
    }
    return out;
  }

 private:
  std::string path_;
  mutable std::unique_ptr<imu::mat::Result<std::vector<imu::mat::VariableInfo>>> listed_;
};

int fail(const std::string& msg, int status) {
  std::fprintf(stderr, "imu-sim analyze: %s\n",
               imu::cli::term_safe(imu::cli::with_suggestion(msg)).c_str());
  return status;
}

// A channel the file does not hold is a command-line mistake (exit 2), as in adev and run.
int read_status(const std::string& err) {
  return imu::cli::names_missing_channel(err) ? kExitUsage : kExitRuntime;
}

// The rate: --fs, else the file's `fs`, else its `Fs`.
// `scope`: the struct holding the channels (`imu` of `imu.acc_z`): its fs/Fs come first.
bool file_rate(const StreamedFile& m, const std::string& file, const std::string& scope,
               double& fs_hz, std::string& err) {
  const std::string in = scope.empty() ? std::string() : scope + ".";
  std::string found;
  for (const std::string& name : {in + "fs", in + "Fs", std::string("fs"), std::string("Fs")}) {
    auto f = m.read_scalar(name);
    if (f.ok()) {
      fs_hz = f.value();
      found = name;
      break;
    }
  }
  if (!found.empty() && !(fs_hz >= 1e-3 && fs_hz <= 1e6)) {
    err = file + ": " + found + " = " + imu::cli::num_text(fs_hz) +
          " Hz is not a rate in [0.001, 1e+06] Hz (give --fs)";
    return false;
  }
  if (!found.empty()) {
    return true;
  }
  err = file + ": no --fs given and no scalar 'fs' or 'Fs' in the file";
  return false;
}

// The LSB the file gives a channel (imu::cli::file_lsb: the same rule as adev and run).
bool file_lsb(const StreamedFile& m, const std::string& channel, double& lsb,
              std::string& err) {
  auto vars = m.list_variables();
  if (!vars) {
    err = vars.error().message;
    return false;
  }
  const auto& listed = vars.value();
  return imu::cli::file_lsb(
      channel, m.display_name(),
      [&listed](const std::string& n) {
        return std::any_of(listed.begin(), listed.end(),
                           [&n](const imu::mat::VariableInfo& v) { return v.name == n; });
      },
      [&m](const std::string& n, double& v, std::string& e) {
        auto r = m.read_scalar(n);
        if (!r) {
          e = r.error().message;
          return false;
        }
        v = r.value();
        return true;
      },
      lsb, err);
}

// --channel: NAME, a comma list, or `all` (the IMU channels the file holds, in the usual order).
// Channels in one run: four 6-axis IMUs. Each is held (up to kMaxAnalysedSamples values) and
// analysed in turn, so a file of thousands of short columns would take minutes and gigabytes.
constexpr std::size_t kMaxChannels = 24;

bool within_channel_limit(const std::string& file, const std::vector<std::string>& names,
                          std::string& err) {
  if (names.size() <= kMaxChannels) {
    return true;
  }
  err = file + ": " + std::to_string(names.size()) + " channels, more than the " +
        std::to_string(kMaxChannels) + " one run analyses; name those to analyse with --channel " +
        "A,B,...";
  return false;
}

bool resolve_channels(const StreamedFile& m, const std::string& file,
                      const std::string& spec, std::vector<std::string>& out, std::string& err) {
  std::vector<std::string> held;
  if (spec == "all") {
    auto vars = m.list_variables();
    if (!vars) {
      err = vars.error().message;
      return false;
    }
    for (const auto& v : vars.value()) {
      held.push_back(v.name);
    }
  }
  if (!imu::cli::expand_channels(spec, held, out, err)) {
    err = file + ": " + err;
    return false;
  }
  return within_channel_limit(file, out, err);
}

// Samples in, means of blocks of B consecutive samples out, one rule for every input: a block
// with fewer than half of its samples finite is a gap (NaN); a last, partial block is dropped.
// B starts at `block` (a power of two) and doubles whenever the complete blocks would pass
// kMaxAnalysedSamples: a block of 2B is two aligned blocks of B, whose sums and finite counts
// are merged, so the means are those of blocks of the final B read directly, for a record of
// unknown length (a text stream). B = 1 gives the samples themselves (non-finite ones NaN).
class BlockMeans {
 public:
  explicit BlockMeans(std::uint64_t block) : block_(block) {}
  void push(double v) {
    if (std::isfinite(v)) {
      sum_ += v;
      ++finite_;
    }
    if (++in_block_ == block_) {
      sums_.push_back(sum_);
      finite_counts_.push_back(finite_);
      sum_ = 0.0;
      finite_ = 0;
      in_block_ = 0;
      if (sums_.size() > kMaxAnalysedSamples) {
        merge_pairs();
      }
    }
  }
  [[nodiscard]] std::uint64_t block() const { return block_; }
  // The means (the sums' storage), with the samples of the dropped partial block.
  std::vector<double> take(std::uint64_t& dropped) {
    for (std::size_t i = 0; i < sums_.size(); ++i) {
      sums_[i] = 2 * std::uint64_t{finite_counts_[i]} >= block_
                     ? sums_[i] / static_cast<double>(finite_counts_[i])
                     : std::numeric_limits<double>::quiet_NaN();
    }
    finite_counts_ = std::vector<std::uint32_t>{};
    dropped = in_block_;
    return std::move(sums_);
  }

 private:
  void merge_pairs() {
    const std::size_t pairs = sums_.size() / 2;
    const bool odd = sums_.size() % 2 != 0;
    const double last_sum = sums_.back();
    const std::uint32_t last_finite = finite_counts_.back();
    for (std::size_t i = 0; i < pairs; ++i) {
      sums_[i] = sums_[2 * i] + sums_[2 * i + 1];
      finite_counts_[i] = finite_counts_[2 * i] + finite_counts_[2 * i + 1];
    }
    sums_.resize(pairs);
    finite_counts_.resize(pairs);
    if (odd) {  // the last complete block is the first half of the block now being filled
      sum_ += last_sum;
      finite_ += last_finite;
      in_block_ += block_;
    }
    block_ *= 2;
  }
  std::uint64_t block_;
  std::vector<double> sums_;
  std::vector<std::uint32_t> finite_counts_;  // a block's finite samples: at most 2^31 here
  double sum_ = 0.0;
  std::uint32_t finite_ = 0;
  std::uint64_t in_block_ = 0;
};

// Block means of `block` consecutive samples of the stream, read in chunks (nothing of the
// record is held but the means; BlockMeans' rule).
bool read_block_means(imu::mat::ChannelStream& st, std::uint64_t block, std::vector<double>& out,
                      std::uint64_t& dropped, std::string& err) {
  std::vector<double> buf(std::size_t{1} << 16U);
  BlockMeans means(block);
  for (;;) {
    auto got = st.read(buf.data(), buf.size());
    if (!got) {
      err = got.error().message;
      return false;
    }
    if (got.value() == 0) {
      break;
    }
    for (std::size_t i = 0; i < got.value(); ++i) {
      means.push(buf[i]);
    }
  }
  out = means.take(dropped);
  return true;
}

// The first kMaxAnalysedSamples samples of a stream (a long record's head). read(dst, max, got,
// err) hands out at most max samples; got = 0 is the end.
template <typename Read>
bool read_head(Read&& read, std::vector<double>& out, std::string& err) {
  out.assign(static_cast<std::size_t>(kMaxAnalysedSamples), 0.0);
  std::size_t have = 0;
  std::size_t got = 0;
  while (have < out.size()) {
    if (!read(out.data() + have, out.size() - have, got, err)) {
      return false;
    }
    if (got == 0) {
      break;
    }
    have += got;
  }
  out.resize(have);
  return true;
}

// A MAT channel's head (NAME or NAME:K); integer counts times `scale` (> 0).
bool read_head_mat(const std::string& path, const std::string& spec, double scale,
                   std::vector<double>& out, std::string& err) {
  imu::cli::ChannelSpec cs;
  if (!imu::cli::parse_channel_spec(spec, cs, err)) {
    return false;
  }
  auto st = imu::mat::ChannelStream::open(path, cs.name, cs.column);
  if (!st) {
    err = st.error().message;
    return false;
  }
  const auto read = [&st](double* dst, std::size_t max, std::size_t& got, std::string& e) {
    auto r = st.value().read(dst, max);
    if (!r) {
      e = r.error().message;
      return false;
    }
    got = r.value();
    return true;
  };
  if (!read_head(read, out, err)) {
    return false;
  }
  if (scale > 0.0) {
    for (double& v : out) {
      v *= scale;
    }
  }
  return true;
}

// A text file's column's head (its rows again: the same grid and gaps as the first pass).
bool read_head_text(const std::string& file, const std::string& name, double fs,
                    double time_unit_s, const std::string& topic, std::vector<double>& out,
                    std::string& err) {
  imu::cli::TextColumnStream st;
  const auto read = [&st](double* dst, std::size_t max, std::size_t& got, std::string& e) {
    return st.read(dst, std::min<std::size_t>(4096, max), got, e);
  };
  return st.open(file, {name}, fs, err, time_unit_s, topic) && read_head(read, out, err);
}

// NAME or NAME:K (column K, 1-based as in Octave, of a matrix NAME). A matrix named without a
// column is refused (reading its first column silently was a wrong answer). A record longer
// than kMaxAnalysedSamples comes back as block means of `block` samples (a power of two, the
// smallest that brings it under the limit; 1 otherwise), with the samples a last partial block
// dropped.
bool read_channel(const StreamedFile& m, const std::string& spec, std::vector<double>& out,
                  bool& integer_class, std::uint64_t& block, std::uint64_t& dropped,
                  std::string& err) {
  integer_class = false;
  block = 1;
  dropped = 0;
  imu::cli::ChannelSpec cs;
  if (!imu::cli::parse_channel_spec(spec, cs, err)) {
    return false;
  }
  const std::string& name = cs.name;
  const std::size_t column = cs.column;
  const bool has_column = cs.has_column;
  auto vars = m.list_variables();
  if (!vars) {
    err = vars.error().message;
    return false;
  }
  std::vector<imu::mat::VariableInfo> listed = std::move(vars.value());
  if (name.find('.') != std::string::npos) {
    // A struct field: its class and size from the reader's descent (not a top-level variable).
    auto field = imu::mat::ChannelStream::open(m.display_name(), name, column);
    if (!field) {
      err = field.error().message;
      return false;
    }
    listed.push_back(field.value().info());
  }
  for (const auto& v : listed) {
    if (v.name == name) {
      integer_class = v.class_name.rfind("int", 0) == 0 || v.class_name.rfind("uint", 0) == 0;
    }
    if (v.name == name && v.rows > 1 && v.cols > 1 && !has_column) {
      err = "'" + name + "' is a " + std::to_string(v.rows) + " x " + std::to_string(v.cols);
      err += " matrix: name a column, " + name;
      err += ":1 .. " + name;
      err += ":" + std::to_string(v.cols);
      return false;
    }
  }
  std::uint64_t n = 0;
  for (const auto& v : listed) {
    if (v.name == name) {
      n = has_column ? v.rows : v.rows * v.cols;
    }
  }
  while (n / block > kMaxAnalysedSamples) {
    block *= 2;
  }
  if (block > 1) {
    auto st = imu::mat::ChannelStream::open(m.display_name(), name, column);
    if (!st) {
      err = st.error().message;
      return false;
    }
    return read_block_means(st.value(), block, out, dropped, err);
  }
  auto col = m.read_column(name, column);
  if (!col) {
    err = col.error().message;
    return false;
  }
  out = std::move(col.value());
  return true;
}

// The sensors and units the command line declares (--acc/--gyro, --acc-unit/--gyro-unit,
// --acc-lsb/--gyro-lsb). A factor or LSB of 0 is not declared.
struct Declared {
  std::vector<std::string> acc;
  std::vector<std::string> gyro;
  std::string acc_unit;
  std::string gyro_unit;
  double acc_to_si = 0.0;
  double gyro_to_si = 0.0;
  double acc_lsb = 0.0;
  double gyro_lsb = 0.0;
};

// A channel's sensor: the one --acc/--gyro declare, else the one its name suggests.
imu::cli::Sensor sensor_of(const std::string& channel, const Declared& d, bool& declared) {
  declared = true;
  if (std::find(d.acc.begin(), d.acc.end(), channel) != d.acc.end()) {
    return imu::cli::Sensor::kAcc;
  }
  if (std::find(d.gyro.begin(), d.gyro.end(), channel) != d.gyro.end()) {
    return imu::cli::Sensor::kGyro;
  }
  declared = false;
  return imu::cli::guess_sensor(channel);
}

// The LSB a sensor's declaration gives (in its declared unit), else `lsb` (--lsb).
double declared_lsb(imu::cli::Sensor s, const Declared& d, double lsb) {
  const double own = s == imu::cli::Sensor::kAcc    ? d.acc_lsb
                     : s == imu::cli::Sensor::kGyro ? d.gyro_lsb
                                                    : 0.0;
  return own > 0.0 ? own : lsb;
}

// The LSB's file name for a channel spec: the base name of NAME:K.
std::string base_name(const std::string& spec) {
  imu::cli::ChannelSpec cs;
  std::string unused;
  return imu::cli::parse_channel_spec(spec, cs, unused) ? cs.name : spec;
}

struct Job {
  std::string channel;
  imu::cli::Sensor sensor = imu::cli::Sensor::kUnknown;
  bool sensor_declared = false;  // by --acc/--gyro (else from the name)
  // A long record (block > 1, read_head set): its first kMaxAnalysedSamples samples, read again
  // at full rate (a second pass over the file's first chunks), are analysed with head_o after
  // the means.
  std::uint64_t block = 1;
  std::function<bool(std::vector<double>&, std::string&)> read_head;
  Options head_o;
  bool counts_scaled = false;    // an integer variable, multiplied by its LSB
  bool counts_unscaled = false;  // an integer variable without an LSB: counts
  std::string text_note;         // where a text file's rate and gaps came from
  std::string unit_note;         // the sensor and its unit, and how they were found
  std::string block_note;        // a long record analysed on block means
  std::vector<double> samples;
  Options o;
  Report r;
  std::string err;
  bool ok = false;
};

// The second analysis of a long record: its head at full rate, joined to the block means' report
// (merge_full_rate_head). A head that cannot be read or analysed is a note, not a failure: the
// record's own analysis stands.
void analyze_head(Job& j) {
  std::vector<double> head;
  std::string err;
  Report h;
  if (!j.read_head(head, err) || !analyze(std::move(head), j.channel, j.head_o, h, err)) {
    j.r.notes.push_back("full-rate head not analysed: " + err);
    return;
  }
  merge_full_rate_head(j.r, std::move(h), j.block, j.head_o);
}

// Each channel's analysis is independent (imu::cli::parallel_for: the machine's cores). An
// exception (out of memory) in one job is that job's error.
void run_jobs(std::vector<Job>& jobs) {
  imu::cli::parallel_for(jobs.size(), [&jobs](std::size_t i) {
    Job& j = jobs[i];
    try {
      j.ok = analyze(std::move(j.samples), j.channel, j.o, j.r, j.err);  // leaves it empty
      if (j.ok && j.read_head) {
        analyze_head(j);
      }
    } catch (const std::bad_alloc&) {
      j.ok = false;
      j.err = "out of memory";
    }
    j.samples = std::vector<double>{};
  });
}

// The mean of a record's finite samples (NaN if none).
double finite_mean(const std::vector<double>& v) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const double x : v) {
    if (std::isfinite(x)) {
      sum += x;
      ++n;
    }
  }
  return n > 0 ? sum / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

// Every job in SI units: the accelerometer's unit declared (--acc-unit), else the one a static
// triad's mean norm shows (about 1: g, about 9.81: m/s^2), else m/s^2; the gyroscope's
// declared (--gyro-unit), else deg/s beside an accelerometer in g, else rad/s. Samples and LSBs are scaled to SI (a long record's
// full-rate head too); each channel's note says its sensor, its unit and how both were found.
void apply_units(std::vector<Job>& jobs, const Declared& d) {
  using imu::cli::Sensor;
  std::vector<const Job*> acc;
  for (const Job& j : jobs) {
    if (j.sensor == Sensor::kAcc) {
      acc.push_back(&j);
    }
  }
  double norm = std::numeric_limits<double>::quiet_NaN();
  if (acc.size() == 3) {
    double sum2 = 0.0;
    for (const Job* j : acc) {
      const double m = finite_mean(j->samples);
      sum2 += m * m;
    }
    norm = std::sqrt(sum2);
  }
  const std::string gravity = imu::cli::unit_from_gravity(norm);
  const std::string norm_text = "the mean norm of its three axes is " + imu::cli::num_text(norm);
  double acc_f = 1.0;
  std::string acc_note;
  if (d.acc_to_si > 0.0) {
    acc_f = d.acc_to_si;
    acc_note = "in " + d.acc_unit + " (--acc-unit)";
    if (!gravity.empty() && (gravity == "g") != (d.acc_unit == "g")) {
      acc_note += "; but " + norm_text + ", gravity in " + gravity + ": check --acc-unit";
    }
  } else if (gravity == "g") {
    acc_f = imu::cli::kStandardGravity;
    acc_note = "in g: " + norm_text + " (a static accelerometer reads 1 g; --acc-unit m/s^2 "
               "says otherwise)";
  } else if (gravity == "m/s^2") {
    acc_note = "in m/s^2: " + norm_text + " (gravity)";
  } else if (acc.size() == 3) {
    acc_note = "taken as m/s^2 (--acc-unit g|m/s^2 declares it): " + norm_text +
               ", neither 1 g nor 9.81 m/s^2 (not static, or another unit)";
  } else {
    acc_note = "taken as m/s^2 (--acc-unit g|m/s^2 declares it; with its three axes, the mean "
               "norm checks it)";
  }
  // Undeclared, the gyroscope's unit follows the accelerometer's convention: loggers that write
  // g write deg/s (datasheet units), those that write m/s^2 write rad/s (SI, ROS REP 103).
  double gyro_f = 1.0;
  std::string gyro_note = "taken as rad/s (--gyro-unit rad/s|deg/s|deg/h declares it)";
  if (d.gyro_to_si > 0.0) {
    gyro_f = d.gyro_to_si;
    gyro_note = "in " + d.gyro_unit + " (--gyro-unit)";
  } else if (std::fabs(acc_f - imu::cli::kStandardGravity) < 1e-9) {
    std::string unit_err;
    (void)imu::cli::unit_to_si(Sensor::kGyro, "deg/s", gyro_f, unit_err);
    gyro_note = "taken as deg/s, the unit that goes with an accelerometer in g (--gyro-unit "
                "rad/s|deg/s|deg/h declares it)";
  }
  for (Job& j : jobs) {
    if (j.sensor == Sensor::kUnknown) {
      continue;
    }
    const bool is_acc = j.sensor == Sensor::kAcc;
    const double f = is_acc ? acc_f : gyro_f;
    j.unit_note = std::string(imu::cli::sensor_name(j.sensor)) +
                  (j.sensor_declared ? " (--acc/--gyro)" : " (from the channel's name; --acc/--gyro "
                                                           "declare it)") +
                  ", " + (is_acc ? acc_note : gyro_note);
    if (!(f < 1.0 || f > 1.0)) {  // SI already
      continue;
    }
    j.unit_note += "; analysed in " + std::string(imu::cli::si_unit(j.sensor)) + " (x " +
                   imu::cli::num_text(f) + ")";
    for (double& v : j.samples) {
      v *= f;
    }
    j.o.lsb *= f;
    j.head_o.lsb *= f;
    if (j.read_head) {
      j.read_head = [inner = std::move(j.read_head), f](std::vector<double>& out,
                                                        std::string& e) {
        if (!inner(out, e)) {
          return false;
        }
        for (double& v : out) {
          v *= f;
        }
        return true;
      };
    }
  }
}

// A finished job's report with its sensor, unit and the notes of how its data was read (the
// first note first).
Report job_report(Job& j, double lsb, const Declared& d) {
  if (j.o.lsb > 0.0 && declared_lsb(j.sensor, d, lsb) <= 0.0) {
    j.r.lsb_note = "LSB from the file: " + j.r.lsb_note.substr(j.r.lsb_note.find(':') + 2);
  }
  j.r.sensor = imu::cli::sensor_name(j.sensor);
  j.r.unit = imu::cli::si_unit(j.sensor);
  std::vector<std::string> first;
  if (j.counts_scaled) {
    first.push_back("the variable holds integer counts: analysed as counts x LSB (" +
                    std::to_string(j.o.lsb) + " per count)");
  } else if (j.counts_unscaled) {
    first.emplace_back("the variable holds integer counts and no LSB was found (--lsb, "
                       "NAME_lsb, <group>_lsb, lsb): analysed in counts");
  }
  for (const std::string* note : {&j.block_note, &j.text_note, &j.unit_note}) {
    if (!note->empty()) {
      first.push_back(*note);
    }
  }
  j.r.notes.insert(j.r.notes.begin(), first.begin(), first.end());
  return std::move(j.r);
}

// The per-channel figures and one per sensor with its axes and the IEEE 952 lines (the
// field's figure) in `plots`; the files written said on `info`. False with msg.
bool write_all_plots(const std::vector<Report>& reports, const std::string& plots, FILE* info,
                     std::string& msg) {
  // File names from channel names (a CSV header is user data): one safe component each,
  // distinct, inside DIR.
  std::vector<std::string> names;
  names.reserve(reports.size());
  for (const Report& r : reports) {
    names.push_back(r.channel);
  }
  const std::vector<std::string> stems = imu::cli::safe_components(names);
  for (std::size_t i = 0; i < reports.size(); ++i) {
    if (!write_plots(reports[i], plots, stems[i], msg)) {
      return false;
    }
    std::fprintf(info, "%s\n", imu::cli::term_safe(msg).c_str());
  }
  if (!write_sensor_plots(reports, plots, msg)) {
    return false;
  }
  if (!msg.empty()) {
    std::fprintf(info, "%s\n", imu::cli::term_safe(msg).c_str());
  }
  return true;
}

// Analyse the jobs (in parallel), print, write. Exit status.
int finish(const std::string& file, std::vector<Job>& jobs, double lsb, const Declared& d,
           const std::string& json, const std::string& plots, const std::string& yaml) {
  std::string err;
  const auto has = [&jobs](imu::cli::Sensor s) {
    return std::any_of(jobs.begin(), jobs.end(), [s](const Job& j) { return j.sensor == s; });
  };
  // Kalibr takes both sensors: said before the analysis, not after it.
  if (!yaml.empty() && (!has(imu::cli::Sensor::kAcc) || !has(imu::cli::Sensor::kGyro))) {
    return fail("--yaml needs at least one accelerometer and one gyroscope channel (Kalibr "
                "takes both sensors): declare them with --acc COLS --gyro COLS",
                kExitUsage);
  }
  apply_units(jobs, d);
  run_jobs(jobs);
  std::vector<Report> reports;
  for (Job& j : jobs) {
    if (!j.ok) {
      return fail((jobs.size() > 1 ? j.channel + ": " : std::string()) + j.err, kExitRuntime);
    }
    reports.push_back(job_report(j, lsb, d));
  }
  // With --json - (or --yaml -) standard output carries that document alone: the text report
  // and the "wrote" lines go to standard error.
  FILE* info = json == "-" || yaml == "-" ? stderr : stdout;
  for (const Report& r : reports) {
    if (reports.size() > 1) {
      std::fprintf(info, "==== %s ====\n", imu::cli::term_safe(r.channel).c_str());
    }
    std::fputs(imu::cli::term_safe_text(to_text(r)).c_str(), info);
  }
  if (!json.empty()) {
    // One shape for one channel or many (host_sim/cli/imu-sim.schema.json).
    std::string text = "{\n" + imu::cli::json_head("analyze", file, "") + "\"channels\": {";
    for (std::size_t i = 0; i < reports.size(); ++i) {
      text += std::string(i > 0 ? "," : "") + "\n" + imu::cli::json_str(reports[i].channel) +
              ": " + to_json(reports[i]);
    }
    text += "\n}\n}\n";
    if (!imu::cli::write_file_atomic(json, text, err)) {
      return fail(err, kExitRuntime);
    }
    if (json != "-") {
      std::fprintf(info, "wrote %s\n", imu::cli::term_safe(json).c_str());
    }
  }
  if (!yaml.empty()) {
    std::string text;
    if (!kalibr_yaml(reports, file, text, err) || !imu::cli::write_file_atomic(yaml, text, err)) {
      return fail(err, kExitRuntime);
    }
    if (yaml != "-") {
      std::fprintf(info, "wrote %s\n", imu::cli::term_safe(yaml).c_str());
    }
  }
  if (!plots.empty() && !write_all_plots(reports, plots, info, err)) {
    return fail(err, kExitRuntime);
  }
  return kExitOk;
}

// A job read as block means of B > 1 samples (a long record): means of B samples on an LSB grid
// lie on a grid B times finer, at a rate B times lower; the report's first note says so.
void on_block_means(Job& j, double fs_hz, std::uint64_t block, std::uint64_t dropped) {
  if (block <= 1) {
    return;
  }
  const std::uint64_t n = j.samples.size() * block + dropped;
  j.block = block;
  j.head_o = j.o;
  j.head_o.fs_hz = fs_hz;
  j.o.fs_hz = fs_hz / static_cast<double>(block);
  if (j.o.lsb > 0.0) {
    j.o.lsb /= static_cast<double>(block);
  }
  j.block_note = "long record: its " + std::to_string(n) + " samples analysed as " +
                 std::to_string(j.samples.size()) + " means of " + std::to_string(block) +
                 " samples (rate " + imu::cli::json_num(j.o.fs_hz) + " Hz" +
                 (dropped > 0 ? ", the last " + std::to_string(dropped) + " samples dropped" : "") +
                 ") to keep memory bounded: taus below " +
                 imu::cli::json_num(static_cast<double>(block) / fs_hz) +
                 " s, quantisation and effects faster than " +
                 imu::cli::json_num(j.o.fs_hz / 2.0) +
                 " Hz are not resolved on the means: the first " +
                 std::to_string(kMaxAnalysedSamples) + " samples are analysed at full rate for "
                 "them (full_rate_head)";
}

// A text file's channels as jobs (or a ROS bag topic's, imu/cli/row_source.hpp): NAME, a comma
// list, or all (the IMU channels it holds, else every column but the time column). The rate:
// --fs, else the time column's. One pass over the rows for every channel
// (imu::cli::TextColumnStream), each into its BlockMeans: a channel is held as its samples, or
// as block means once it passes kMaxAnalysedSamples, never the table.
bool text_jobs(const std::string& file, const std::string& spec, double fs, double time_unit_s,
               const std::string& topic, double lsb, const Declared& d, std::vector<Job>& jobs,
               std::string& err) {
  std::vector<std::string> names;
  {
    const auto header = imu::cli::open_rows(file, topic, err);
    if (header == nullptr) {
      return false;
    }
    if (!imu::cli::text_channels(header->names(), spec, names, err)) {
      err.insert(0, file + ": ");
      return false;
    }
    if (!within_channel_limit(file, names, err)) {
      return false;
    }
  }
  const auto with_file = [&file](std::string& e) {
    if (e.rfind(file, 0) != 0) {
      e.insert(0, file + ": ");
    }
  };
  imu::cli::TextColumnStream st;
  if (!st.open(file, names, fs, err, time_unit_s, topic)) {
    with_file(err);
    return false;
  }
  const std::size_t k = names.size();
  std::vector<BlockMeans> means(k, BlockMeans(1));
  constexpr std::size_t kChunk = 4096;
  std::vector<double> buf(kChunk * k);
  for (;;) {
    std::size_t got = 0;
    if (!st.read(buf.data(), kChunk, got, err)) {
      with_file(err);
      return false;
    }
    if (got == 0) {
      break;
    }
    for (std::size_t i = 0; i < got; ++i) {
      for (std::size_t c = 0; c < k; ++c) {
        means[c].push(buf[i * k + c]);
      }
    }
  }
  for (std::size_t c = 0; c < k; ++c) {
    Job j;
    j.channel = names[c];
    std::uint64_t dropped = 0;
    j.samples = means[c].take(dropped);
    j.o.fs_hz = st.fs_hz();
    j.sensor = sensor_of(j.channel, d, j.sensor_declared);
    j.o.lsb = declared_lsb(j.sensor, d, lsb);
    if (!st.time_name().empty()) {
      j.text_note = st.origin() + ": rate " + imu::cli::num_text(st.fs_hz()) + " Hz" +
                    (fs > 0.0 ? " (--fs)" : " from the time column '" + st.time_name() + "'");
      if (!st.time_note().empty()) {
        j.text_note += "; " + st.time_note();
      }
      if (st.time_gap_samples() > 0) {
        j.text_note += "; its steps left " + std::to_string(st.time_gap_samples()) +
                       " samples missing (gaps)";
      }
    }
    on_block_means(j, st.fs_hz(), means[c].block(), dropped);
    if (j.block > 1) {
      j.read_head = [file, name = names[c], fs, time_unit_s, topic](std::vector<double>& out,
                                                                   std::string& e) {
        return read_head_text(file, name, fs, time_unit_s, topic, out, e);
      };
    }
    jobs.push_back(std::move(j));
  }
  return true;
}

// The run-time part: read, analyse (in parallel), print, write. Exit status.
int analyze_file(const std::string& file, const std::string& channel_spec, double fs,
                 double time_unit_s, const std::string& topic, double lsb, const Declared& d,
                 const std::string& json, const std::string& plots, const std::string& yaml) {
  std::string err;
  // Text and ROS bags are read as rows (imu/cli/row_source.hpp).
  const bool bag = imu::cli::looks_like_bag(file);
  if (!bag && !topic.empty()) {
    return fail("--topic " + topic + ": " + file + " is not a ROS bag (--topic reads one)",
                kExitUsage);
  }
  if (bag && time_unit_s > 0.0) {
    return fail("--time-unit: " + file + " is a ROS bag, whose header stamps are in ns", kExitUsage);
  }
  if (bag || imu::cli::looks_like_text(file)) {
    std::vector<Job> jobs;
    if (!text_jobs(file, channel_spec, fs, time_unit_s, topic, lsb, d, jobs, err)) {
      return fail(err, read_status(err));
    }
    return finish(file, jobs, lsb, d, json, plots, yaml);
  }
  const StreamedFile m(file);
  if (auto listed = m.list_variables(); !listed) {
    return fail(listed.error().message, kExitRuntime);
  }
  std::vector<std::string> channels;
  if (!resolve_channels(m, file, channel_spec, channels, err)) {
    return fail(err, read_status(err));
  }
  if (lsb > 0.0 && channels.size() > 1) {
    return fail("--lsb applies to one channel; with several, each takes its LSB from the file",
                kExitUsage);
  }
  Options o;
  const std::size_t dot = base_name(channels[0]).rfind('.');
  const std::string scope = dot == std::string::npos ? std::string() : channels[0].substr(0, dot);
  if (fs > 0.0) {
    o.fs_hz = fs;
  } else if (!file_rate(m, file, scope, o.fs_hz, err)) {
    return fail(err, kExitRuntime);
  }
  std::vector<Job> jobs(channels.size());
  for (std::size_t i = 0; i < channels.size(); ++i) {
    bool integer_class = false;
    std::uint64_t block = 1;
    std::uint64_t dropped = 0;
    if (!read_channel(m, channels[i], jobs[i].samples, integer_class, block, dropped, err)) {
      return fail(err, read_status(err));
    }
    jobs[i].channel = channels[i];
    jobs[i].sensor = sensor_of(channels[i], d, jobs[i].sensor_declared);
    jobs[i].o = o;
    jobs[i].o.lsb = declared_lsb(jobs[i].sensor, d, lsb);
    if (jobs[i].o.lsb <= 0.0 && !file_lsb(m, channels[i], jobs[i].o.lsb, err)) {
      return fail(err, kExitRuntime);
    }
    // Integer counts (int16 from a logger) with a known LSB are counts x LSB in the channel's
    // unit; without one they stay counts (said in the report).
    if (integer_class && jobs[i].o.lsb > 0.0) {
      for (double& v : jobs[i].samples) {
        v *= jobs[i].o.lsb;
      }
      jobs[i].counts_scaled = true;
    } else if (integer_class) {
      jobs[i].counts_unscaled = true;
    }
    on_block_means(jobs[i], o.fs_hz, block, dropped);
    if (block > 1) {
      const double scale = jobs[i].counts_scaled ? jobs[i].head_o.lsb : 0.0;
      jobs[i].read_head = [file, spec = channels[i], scale](std::vector<double>& out,
                                                            std::string& e) {
        return read_head_mat(file, spec, scale, out, e);
      };
    }
  }
  return finish(file, jobs, lsb, d, json, plots, yaml);
}

// --acc COLS, --gyro COLS (comma lists of channel specs), --acc-unit, --gyro-unit, --acc-lsb,
// --gyro-lsb. False with err on a unit neither sensor has, an LSB out of range, a channel
// named twice.
bool declared_sensors(const imu::cli::Args& a, Declared& d, std::string& err) {
  const auto split = [](const std::string& list) {
    std::vector<std::string> out;
    std::size_t start = 0;
    while (start <= list.size()) {
      const std::size_t comma = std::min(list.find(',', start), list.size());
      if (comma > start) {
        out.push_back(list.substr(start, comma - start));
      }
      start = comma + 1;
    }
    return out;
  };
  d.acc = split(a.get("--acc"));
  d.gyro = split(a.get("--gyro"));
  for (const std::string& c : d.acc) {
    if (std::count(d.acc.begin(), d.acc.end(), c) > 1 ||
        std::find(d.gyro.begin(), d.gyro.end(), c) != d.gyro.end()) {
      err = "channel '" + c + "' is named twice in --acc/--gyro";
      return false;
    }
  }
  if (a.has("--acc-unit")) {
    d.acc_unit = a.get("--acc-unit");
    if (!imu::cli::unit_to_si(imu::cli::Sensor::kAcc, d.acc_unit, d.acc_to_si, err)) {
      err = "--acc-unit: " + err;
      return false;
    }
    d.acc_unit = d.acc_to_si > 1.0 ? "g" : "m/s^2";
  }
  if (a.has("--gyro-unit")) {
    d.gyro_unit = a.get("--gyro-unit");
    if (!imu::cli::unit_to_si(imu::cli::Sensor::kGyro, d.gyro_unit, d.gyro_to_si, err)) {
      err = "--gyro-unit: " + err;
      return false;
    }
  }
  return (!a.has("--acc-lsb") || a.number("--acc-lsb", 0.0, 1e-12, 1e6, d.acc_lsb, err)) &&
         (!a.has("--gyro-lsb") || a.number("--gyro-lsb", 0.0, 1e-12, 1e6, d.gyro_lsb, err));
}

}  // namespace

int cli_main(int argc, char** argv) {
  imu::cli::Args a;
  std::string err;
  const std::vector<imu::cli::OptSpec> specs = {
      {"--channel", true},  {"--json", true},      {"--plots", true},     {"--fs", true},
      {"--lsb", true},      {"--yaml", true},      {"--time-unit", true}, {"--acc", true},
      {"--gyro", true},     {"--acc-unit", true},  {"--gyro-unit", true}, {"--acc-lsb", true},
      {"--gyro-lsb", true}, {"--topic", true}};
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
  double time_unit_s = 0.0;
  if (!imu::cli::time_unit_option(a, time_unit_s, err)) {
    return fail(err, kExitUsage);
  }
  Declared d;
  if (!declared_sensors(a, d, err)) {
    return fail(err, kExitUsage);
  }
  const bool by_sensor = a.has("--acc") || a.has("--gyro");
  if (a.has("--channel") && by_sensor) {
    return fail("--channel and --acc/--gyro both name the channels: give one of them",
                kExitUsage);
  }
  if (a.positional().empty() || !(a.has("--channel") || by_sensor)) {
    return fail("FILE and --channel NAME (or --acc COLS --gyro COLS) are required "
                "(imu-sim analyze --help)",
                kExitUsage);
  }
  std::string channel_spec = a.get("--channel");
  if (by_sensor) {
    channel_spec.clear();
    for (const auto* list : {&d.acc, &d.gyro}) {
      for (const std::string& c : *list) {
        channel_spec += (channel_spec.empty() ? "" : ",") + c;
      }
    }
  }
  // Output paths are checked before the work (an analysis is not lost to a typo in --json).
  for (const char* opt : {"--json", "--yaml"}) {
    if (a.has(opt) && !imu::cli::check_output_path(a.get(opt), err)) {
      return fail(std::string(opt) + ": " + err, kExitUsage);
    }
  }
  if (a.has("--json") && a.has("--yaml") && a.get("--json") == "-" && a.get("--yaml") == "-") {
    return fail("--json - and --yaml - cannot both be standard output", kExitUsage);
  }
  if (a.has("--plots") && !imu::cli::check_output_dir(a.get("--plots"), err)) {
    return fail("--plots: " + err, kExitUsage);
  }
  if (a.has("--yaml")) {
    if (channel_spec != "all" && channel_spec.find(',') == std::string::npos) {
      return fail("--yaml needs several channels (at least one accelerometer and one gyroscope; "
                  "Kalibr takes both sensors): use --channel all, a list, or --acc COLS --gyro "
                  "COLS",
                  kExitUsage);
    }
  }
  // Sizes are bounded by the MAT reader's budget; this is the last line of defence (a machine
  // short of memory): one line, exit 1, no exception escapes.
  try {
    return analyze_file(a.positional()[0], channel_spec, fs, time_unit_s, a.get("--topic"), lsb,
                        d, a.get("--json"), a.get("--plots"), a.get("--yaml"));
  } catch (const std::bad_alloc&) {
    return fail("out of memory", kExitRuntime);
  }
}

}  // namespace imu::analyze

// Loading a sensor recording (see data.hpp).
#include "data.hpp"

#include "imu/cli/args.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <string_view>
#include <system_error>
#include <thread>

#include "imu/mat/mat_reader.hpp"
#include "imu/online_adev.hpp"

namespace imu::sim {
namespace {

const mat::VariableInfo* find_var(const std::vector<mat::VariableInfo>& vars, const char* name) {
  for (const auto& v : vars) {
    if (v.name == name) {
      return &v;
    }
  }
  return nullptr;
}

std::string num(double v) {
  char buf[32];
  (void)std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// The scalars of a file through a ChannelStream (the file is not read whole).
struct StreamScalars {
  const std::string& path;
  [[nodiscard]] mat::Result<double> read_scalar(std::string_view name) const {
    return mat::stream_scalar(path, name);
  }
};

// The rate: fs_override, else the file's `fs`, else its `Fs`, within [kMinFsHz, kMaxFsHz].
// `scope`: the struct that holds the channels (`imu` for `imu.acc_z`), whose `fs`/`Fs` come
// first; "" for top-level channels. Reader: mat::MatFile or StreamScalars.
template <class Reader>
bool read_rate(const Reader& mf, const std::vector<mat::VariableInfo>& vars,
               const std::string& path, double fs_override, const std::string& scope,
               double& fs_hz, std::string& err) {
  if (fs_override > 0.0) {
    fs_hz = fs_override;
    return true;
  }
  std::string name = find_var(vars, "fs") == nullptr && find_var(vars, "Fs") != nullptr ? "Fs"
                                                                                       : "fs";
  auto fs = mf.read_scalar(name);
  for (const char* in_scope : {".Fs", ".fs"}) {
    auto v = scope.empty() ? fs : mf.read_scalar(scope + in_scope);
    if (v.ok() && !scope.empty()) {
      fs = v;
      name = scope + in_scope;
    }
  }
  if (!fs.ok()) {
    err = fs.error().message + " (give --fs)";
    return false;
  }
  fs_hz = fs.value();
  if (!(fs_hz >= kMinFsHz && fs_hz <= kMaxFsHz)) {
    err = path + ": " + name + " = " + num(fs_hz) + " Hz is not a rate in [" + num(kMinFsHz) +
          ", " + num(kMaxFsHz) + "] Hz (give --fs)";
    return false;
  }
  return true;
}

// The LSB the file gives channel `name` (imu::cli::file_lsb: the rule of every command).
template <class Reader>
bool file_lsb_of(const Reader& mf, const std::vector<mat::VariableInfo>& vars,
                 const std::string& path, const std::string& name, double& lsb,
                 std::string& err) {
  return imu::cli::file_lsb(
      name, path, [&vars](const std::string& n) { return find_var(vars, n.c_str()) != nullptr; },
      [&mf](const std::string& n, double& v, std::string& e) {
        auto r = mf.read_scalar(n);
        if (!r.ok()) {
          e = r.error().message;
          return false;
        }
        v = r.value();
        return true;
      },
      lsb, err);
}

// A channel is one vector: an N x M matrix would be read as its first column without a word.
bool check_vector(const mat::VariableInfo& v, const std::string& path, std::string& err) {
  if (v.rows <= 1U || v.cols <= 1U) {
    return true;
  }
  err = path + ": variable '" + v.name + "' is a " + std::to_string(v.rows) + "x" +
        std::to_string(v.cols) + " matrix, not one channel: name a column (--channel " + v.name +
        ":3 for its third), or save each column as its own vector named acc_x .. gyro_z";
  return false;
}

// imu::quantize(x, lsb).counts for finite x, from c = x / lsb, without branches: half away from
// zero is trunc(c + copysign(0.5, c)) (equal to quantize's floor forms on each side of zero),
// clamped in double first so that the conversion is defined, saturating at the int32 ends as
// quantize does.
std::int32_t round_counts(double c) {
  const double t = std::min(std::max(c + std::copysign(0.5, c), -2147483648.0), 2147483647.0);
  return static_cast<std::int32_t>(t);
}

// Count, mean, sum of squared deviations and largest |x| of a stream given in chunks: each
// chunk's own mean and deviations (two passes in cache, no division per sample), merged by
// Chan et al.'s update (equal to Welford's recurrence up to rounding).
struct Moments {
  std::uint64_t n = 0;
  double mean = 0.0;
  double m2 = 0.0;
  double max_abs = 0.0;
  [[nodiscard]] double std_dev() const {
    return n > 1 ? std::sqrt(m2 / static_cast<double>(n - 1)) : 0.0;
  }
  void add(const double* x, std::size_t k) {
    if (k == 0U) {
      return;
    }
    double sum[4] = {0.0, 0.0, 0.0, 0.0};  // four chains: the adds do not wait on each other
    double top[4] = {0.0, 0.0, 0.0, 0.0};
    std::size_t i = 0;
    for (; i + 4U <= k; i += 4U) {
      for (std::size_t l = 0; l < 4U; ++l) {
        sum[l] += x[i + l];
        top[l] = std::max(top[l], std::fabs(x[i + l]));
      }
    }
    for (; i < k; ++i) {
      sum[0] += x[i];
      top[0] = std::max(top[0], std::fabs(x[i]));
    }
    const double kd = static_cast<double>(k);
    const double mean_k = ((sum[0] + sum[1]) + (sum[2] + sum[3])) / kd;
    double dev[4] = {0.0, 0.0, 0.0, 0.0};
    for (i = 0; i + 4U <= k; i += 4U) {
      for (std::size_t l = 0; l < 4U; ++l) {
        const double d = x[i + l] - mean_k;
        dev[l] += d * d;
      }
    }
    for (; i < k; ++i) {
      const double d = x[i] - mean_k;
      dev[0] += d * d;
    }
    const double m2_k = (dev[0] + dev[1]) + (dev[2] + dev[3]);
    const double nd = static_cast<double>(n);
    const double delta = mean_k - mean;
    const double total = nd + kd;
    mean += delta * kd / total;
    m2 += m2_k + delta * delta * nd * kd / total;
    n += k;
    max_abs = std::max({max_abs, std::max(top[0], top[1]), std::max(top[2], top[3])});
  }
};

}  // namespace


mat::Result<mat::ChannelStream> open_channel(const SensorData& sd, std::size_t c) {
  const ChannelData& ch = sd.ch[c];
  return mat::ChannelStream::open(sd.path, ch.var.empty() ? std::string(kChannelNames[c]) : ch.var,
                                  ch.column);
}

void scale_counts(const ChannelData& ch, double* v, std::size_t n) {
  if (ch.integer_counts) {
    for (std::size_t i = 0; i < n; ++i) {
      v[i] *= ch.scale;
    }
  }
}

bool MatChannelSource::open(std::string& err) {
  auto cs = open_channel(sd_, c_);
  if (!cs.ok()) {
    err = cs.error().message;
    return false;
  }
  stream_ = std::make_unique<mat::ChannelStream>(std::move(cs.value()));
  return true;
}

bool MatChannelSource::read(double* out, std::size_t n, std::size_t& got, std::string& err) {
  const auto r = stream_->read(out, n);
  if (!r.ok()) {
    err = r.error().message;
    return false;
  }
  got = r.value();
  return true;
}

bool TextChannelSource::open(std::string& err) {
  samples_ = 0;
  if (read_samples_ != nullptr) {
    return true;
  }
  stream_ = imu::cli::TextColumnStream{};
  if (!stream_.open(path_, column_, fs_hz_, err, time_unit_s_, topic_)) {
    err = err.rfind(path_, 0) == 0 ? err : path_ + ": " + err;
    return false;
  }
  return true;
}

bool TextChannelSource::read(double* out, std::size_t n, std::size_t& got, std::string& err) {
  if (read_samples_ != nullptr) {
    const std::size_t at = static_cast<std::size_t>(samples_);
    got = std::min(n, read_samples_->size() - at);
    std::copy_n(read_samples_->data() + at, got, out);
    samples_ += got;
    return true;
  }
  if (!stream_.read(out, n, got, err)) {
    err = err.rfind(path_, 0) == 0 ? err : path_ + ": " + err;
    return false;
  }
  samples_ += got;
  return true;
}

bool channel_slot(const std::string& name, std::size_t& chan, ChannelVars& vars, bool& renamed,
                  std::string& err) {
  renamed = false;
  if (channel_index(name, chan)) {
    return true;
  }
  imu::cli::ChannelSpec cs;
  if (!imu::cli::parse_channel_spec(name, cs, err)) {
    return false;
  }
  chan = name.substr(name.rfind('.') + 1).rfind("gyro", 0) == 0 ? 5 : 2;
  vars.names[chan] = cs.name;
  vars.columns[chan] = cs.column;
  vars.column_given[chan] = cs.has_column;
  renamed = true;
  return true;
}

bool load_sensor_meta(const std::string& path, const bool (&want)[kNumChannels],
                      const bool (&required)[kNumChannels],
                      const double (&lsb_override)[kNumChannels], double fs_override,
                      SensorData& out, std::string& err, const ChannelVars* cv) {
  out = SensorData{};
  out.path = path;
  auto listed = mat::scan_variables(path);
  if (!listed.ok()) {
    err = listed.error().message;
    return false;
  }
  const std::vector<mat::VariableInfo>& vars = listed.value();
  const StreamScalars mf{path};
  // Channels in a struct (`imu.acc_z`): its fs comes before the top-level one.
  std::string scope;
  for (std::size_t c = 0; cv != nullptr && c < kNumChannels && scope.empty(); ++c) {
    const std::size_t dot = want[c] ? cv->names[c].rfind('.') : std::string::npos;
    scope = dot == std::string::npos ? std::string() : cv->names[c].substr(0, dot);
  }
  if (!read_rate(mf, vars, path, fs_override, scope, out.fs_hz, err)) {
    return false;
  }
  bool any = false;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    const bool renamed = cv != nullptr && !cv->names[c].empty();
    const std::string name = renamed ? cv->names[c] : std::string(kChannelNames[c]);
    const std::size_t column = renamed ? cv->columns[c] : 0;
    const mat::VariableInfo* info = find_var(vars, name.c_str());
    mat::VariableInfo field;  // a struct field's: from its stream (not a top-level variable)
    if (info == nullptr && want[c] && name.find('.') != std::string::npos) {
      auto fcs = mat::ChannelStream::open(path, name, column);
      if (!fcs.ok()) {
        err = fcs.error().message;
        return false;
      }
      field = fcs.value().info();
      info = &field;
    }
    if (!want[c] || (info == nullptr && !required[c])) {
      continue;
    }
    if (info == nullptr) {
      // Missing and required: the reader's "not found; variables: ..." message.
      auto cs = mat::ChannelStream::open(path, name);
      if (cs.ok()) {
        err = path + ": variable '";
        err += name + "' not found";
      } else {
        err = cs.error().message;
      }
      return false;
    }
    if (!(renamed && cv->column_given[c]) && !check_vector(*info, path, err)) {
      return false;
    }
    // Class, dimensions against the data, budget: checked by opening the stream (no data read).
    auto cs = mat::ChannelStream::open(path, name, column);
    if (!cs.ok()) {
      err = cs.error().message;
      return false;
    }
    const auto n = static_cast<std::size_t>(cs.value().size());
    if (any && n != out.n_samples) {
      err = path + ": variable '";
      err += name + "' has " + std::to_string(n);
      err += " samples, others " + std::to_string(out.n_samples);
      return false;
    }
    out.n_samples = n;
    any = true;
    ChannelData& ch = out.ch[c];
    ch.present = true;
    ch.var = renamed ? name : std::string();
    ch.column = column;
    ch.integer_counts = info->class_name.rfind("int", 0) == 0 ||
                        info->class_name.rfind("uint", 0) == 0;
    double fl = 0.0;
    if (!file_lsb_of(mf, vars, path, name, fl, err)) {
      return false;
    }
    ch.lsb_from_option = lsb_override[c] > 0.0;
    ch.lsb_from_file = !ch.lsb_from_option && fl > 0.0;
    ch.lsb = lsb_override[c] > 0.0 ? lsb_override[c] : (fl > 0.0 ? fl : default_lsb(c));
    if (ch.integer_counts) {
      // Counts stored as integers: with an LSB they are counts x LSB in the channel's unit;
      // without one they stay counts (LSB 1).
      ch.lsb = ch.lsb_from_option || ch.lsb_from_file ? ch.lsb : 1.0;
      ch.scale = ch.lsb;
    }
  }
  if (!any) {
    err = path + ": none of the channels acc_x .. gyro_z is in the file";
    return false;
  }
  return true;
}

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Every sample of channel c through f(const double* v, std::size_t n), chunk by chunk
// (buf.size() samples). The file is read and inflated one chunk ahead on a second thread, so
// that inflating chunk k + 1 overlaps f's work on chunk k (two buffers, handed over under a
// mutex). read_s: the time f's thread waited for data. The reader is used by that thread alone.
template <class F>
bool for_each_chunk(ChunkSource& src, const ChannelData& ch, std::vector<double>& buf,
                    double& read_s, std::string& err, F&& f) {
  if (!src.open(err)) {
    return false;
  }
  struct Slot {
    std::vector<double> v;
    std::size_t n = 0;
    bool full = false;  // filled by the reader, not yet used by f
  };
  Slot slot[2];
  slot[0].v.swap(buf);
  slot[1].v.resize(slot[0].v.size());
  std::mutex m;
  std::condition_variable cv;
  bool stop = false;       // f's side is leaving (error or end)
  std::string read_err;    // the reader's error, set before its last slot is marked full
  const auto read_ahead = [&] {
    for (std::size_t k = 0;; k ^= 1U) {
      {
        std::unique_lock<std::mutex> lock(m);
        cv.wait(lock, [&] { return stop || !slot[k].full; });
        if (stop) {
          return;
        }
      }
      std::size_t got = 0;
      std::string e;
      const bool ok = src.read(slot[k].v.data(), slot[k].v.size(), got, e);
      std::lock_guard<std::mutex> lock(m);
      slot[k].n = ok ? got : 0U;
      if (!ok) {
        read_err = e;
      }
      slot[k].full = true;
      cv.notify_all();
      if (slot[k].n == 0U) {
        return;  // end (checked) or error
      }
    }
  };
  // A chunk to f, integer counts first scaled to the channel's unit.
  const auto deliver = [&ch, &f](double* v, std::size_t n) {
    scale_counts(ch, v, n);
    f(v, n);
  };
  // Read and work in turn on this thread: when no thread is to be had (limits), or when
  // IMU_NO_THREADS is set (qemu-aarch64 user mode hangs on a second thread: the cross tests).
  const auto in_turn = [&]() {
    for (;;) {
      const auto t0 = std::chrono::steady_clock::now();
      std::size_t got = 0;
      const bool ok = src.read(slot[0].v.data(), slot[0].v.size(), got, err);
      read_s += seconds_since(t0);
      if (!ok || got == 0U) {
        buf.swap(slot[0].v);
        return ok;
      }
      deliver(slot[0].v.data(), got);
    }
  };
  if (std::getenv("IMU_NO_THREADS") != nullptr) {
    return in_turn();
  }
  std::thread reader;
  try {
    reader = std::thread(read_ahead);
  } catch (const std::system_error&) {
    return in_turn();
  }
  bool ok = true;
  for (std::size_t k = 0;; k ^= 1U) {
    const auto t0 = std::chrono::steady_clock::now();
    std::size_t n = 0;
    {
      std::unique_lock<std::mutex> lock(m);
      cv.wait(lock, [&] { return slot[k].full; });
      n = slot[k].n;
      if (n == 0U) {
        ok = read_err.empty();
        err = read_err;
        stop = true;
        cv.notify_all();
        break;
      }
    }
    read_s += seconds_since(t0);
    deliver(slot[k].v.data(), n);
    std::lock_guard<std::mutex> lock(m);
    slot[k].full = false;
    cv.notify_all();
  }
  reader.join();
  buf.swap(slot[0].v);
  return ok;
}

// A channel's chunks split into their finite runs for a CountSink, as stream_counts() delivers
// them: a run of non-finite samples between two finite ones is one gap, held until the next
// finite run (those before the first finite sample and after the last are not in the series).
class FiniteRuns {
 public:
  // The finite runs of v[0, n) in order, each v[i, j) by push(i, j) after the gap it ends.
  // Returns the number of finite samples.
  template <class Push>
  std::size_t split(const double* v, std::size_t n, CountSink& sink, Push&& push) {
    std::size_t finite = 0;
    for (std::size_t i = 0; i < n;) {
      std::size_t j = i;
      const bool fin = std::isfinite(v[i]);
      while (j < n && std::isfinite(v[j]) == fin) {
        ++j;
      }
      if (!fin) {
        pending_gap_ += started_ ? j - i : 0U;
      } else {
        begin_run(sink);
        push(i, j);
        finite += j - i;
      }
      i = j;
    }
    return finite;
  }
  // A finite run is pushed next: the gap before it goes first.
  void begin_run(CountSink& sink) {
    if (pending_gap_ > 0U) {
      sink.gap(static_cast<std::size_t>(pending_gap_));
      pending_gap_ = 0;
    }
    started_ = true;
  }

 private:
  std::uint64_t pending_gap_ = 0;
  bool started_ = false;
};

// stream_counts() for a sink that takes the values: the finite runs as they are, the gaps
// between them as for counts.
int stream_values(ChunkSource& src, const std::string& where, ChannelData& ch, CountSink& sink,
                  StreamTiming& timing, std::string& err) {
  std::vector<double> values(8192);
  std::uint64_t total = 0;
  std::uint64_t finite = 0;
  FiniteRuns runs;
  ch.off_grid = 0;
  const bool ok = for_each_chunk(src, ch, values, timing.read_s, err, [&](const double* v,
                                                                          std::size_t n) {
    const auto t0 = std::chrono::steady_clock::now();
    total += n;
    finite += runs.split(v, n, sink,
                         [&](std::size_t i, std::size_t j) { sink.push_values(v + i, j - i); });
    timing.sink_s += seconds_since(t0);
  });
  if (!ok) {
    return kExitRuntime;
  }
  ch.non_finite = total - finite;
  if (finite == 0) {
    err = where + "no finite sample (" + std::to_string(ch.non_finite) + " NaN/Inf)";
    return kExitRuntime;
  }
  return kExitOk;
}

}  // namespace

int stream_counts(const std::string& path, std::size_t c, ChannelData& ch, CountSink& sink,
                  StreamTiming& timing, std::string& err) {
  SensorData sd;
  sd.path = path;
  sd.ch[c] = ch;
  MatChannelSource src(sd, c);
  const int st = stream_counts(src,
                               path + ": variable '" +
                                   (ch.var.empty() ? std::string(kChannelNames[c]) : ch.var) + "': ",
                               ch, sink, timing, err);
  return st;
}

namespace {

constexpr std::size_t kCountChunk = 8192;    // samples per chunk of stream_counts
constexpr double kMaxCounts = 2147483647.0;  // int32's largest count

// After the stream: the counts refused when no sample is finite, when a value overflowed int32
// counts (nothing was pushed after it), or when the LSB puts nearly every sample in one count
// (a second pass counts the majority candidate's exact share). 0, or the exit status with err.
int check_counts(ChunkSource& src, const std::string& where, const ChannelData& ch,
                 const Moments& s, const Moments& q, std::int32_t cand, bool overflow,
                 StreamTiming& timing, std::string& err) {
  const double lsb = ch.lsb;
  if (s.n == 0) {
    err = where + "no finite sample (" + std::to_string(ch.non_finite) + " NaN/Inf)";
    return kExitRuntime;
  }
  const int misfit = ch.lsb_from_option ? kExitUsage : kExitRuntime;
  const std::string lsb_origin =
      ch.lsb_from_option ? "--lsb " : (ch.lsb_from_file ? "the file's LSB " : "the default LSB ");
  if (overflow) {
    err = where + "values up to " + num(s.max_abs) + " do not fit int32 counts at " + lsb_origin +
          num(lsb) + " (the LSB must be at least " + num(s.max_abs / kMaxCounts) + ")";
    return misfit;
  }
  if (q.std_dev() < 0.5 * s.std_dev()) {
    // Only now is the exact share of the majority candidate needed: a second pass.
    std::vector<double> values(kCountChunk);
    std::uint64_t same = 0;
    double second_read_s = 0.0;
    if (!for_each_chunk(src, ch, values, second_read_s, err, [&](const double* v, std::size_t n) {
          for (std::size_t i = 0; i < n; ++i) {
            same += std::isfinite(v[i]) && quantize(v[i], lsb).counts == cand ? 1U : 0U;
          }
        })) {
      return kExitRuntime;
    }
    timing.read_s += second_read_s;
    const double top_share = static_cast<double>(same) / static_cast<double>(s.n);
    if (top_share > 0.99) {
      err = where + lsb_origin + num(lsb) + " puts " + num(100.0 * top_share) +
            " % of the samples in one count (std " + num(s.std_dev()) + " becomes " +
            num(q.std_dev()) + "): the LSB is too coarse for these data";
      return misfit;
    }
  }
  return kExitOk;
}

}  // namespace

int stream_counts(ChunkSource& src, const std::string& where, ChannelData& ch, CountSink& sink,
                  StreamTiming& timing, std::string& err) {
  if (sink.takes_values()) {
    return stream_values(src, where, ch, sink, timing, err);
  }
  std::vector<double> values(kCountChunk);
  std::vector<std::int32_t> counts(kCountChunk);
  std::vector<double> fin(kCountChunk);    // the chunk's finite values
  std::vector<double> quant(kCountChunk);  // and their quantised values (counts x LSB)
  Moments s;
  Moments q;
  std::int32_t cand = 0;
  std::uint64_t votes = 0;
  std::uint64_t total = 0;
  bool overflow = false;   // a finite |value| / LSB beyond int32: nothing more is pushed
  FiniteRuns runs;
  ch.off_grid = 0;
  const double lsb = ch.lsb;
  const bool ok = for_each_chunk(src, ch, values, timing.read_s, err, [&](const double* v,
                                                                          std::size_t n) {
    const auto t0 = std::chrono::steady_clock::now();
    total += n;
    std::size_t m = 0;
    bool all_finite = true;
    for (std::size_t i = 0; i < n; ++i) {
      all_finite = all_finite && std::fabs(v[i]) <= std::numeric_limits<double>::max();  // no NaN
    }
    std::uint64_t off_grid = 0;
    if (all_finite) {
      // The common case, in loops the compiler vectorises: quantise, then the vote (a chain).
      for (std::size_t i = 0; i < n; ++i) {
        const double cnt = v[i] / lsb;
        const std::int32_t k = round_counts(cnt);
        counts[i] = k;
        off_grid += std::fabs(cnt - static_cast<double>(k)) > 1e-6 ? 1U : 0U;
        quant[i] = static_cast<double>(k) * lsb;
      }
      for (std::size_t i = 0; i < n; ++i) {
        const std::int32_t k = counts[i];
        const bool fresh = votes == 0;
        const bool same = k == cand;
        cand = fresh ? k : cand;
        votes = fresh ? 1U : (same ? votes + 1U : votes - 1U);
      }
      m = n;
    }
    for (std::size_t i = 0; i < n && !all_finite; ++i) {
      const double x = v[i];
      if (!std::isfinite(x)) {
        counts[i] = 0;
        all_finite = false;
        continue;
      }
      const double cnt = x / lsb;
      const std::int32_t k = round_counts(cnt);  // saturates; overflow is checked below
      counts[i] = k;
      off_grid += std::fabs(cnt - static_cast<double>(k)) > 1e-6 ? 1U : 0U;
      fin[m] = x;
      quant[m] = static_cast<double>(k) * lsb;
      ++m;
      // Boyer-Moore vote without branches (k == cand is a coin toss on noisy data).
      const bool fresh = votes == 0;
      const bool same = k == cand;
      cand = fresh ? k : cand;
      votes = fresh ? 1U : (same ? votes + 1U : votes - 1U);
    }
    ch.off_grid += off_grid;
    s.add(all_finite ? v : fin.data(), m);
    q.add(quant.data(), m);
    overflow = overflow || s.max_abs / lsb >= kMaxCounts + 0.5;
    const auto t1 = std::chrono::steady_clock::now();
    timing.quantize_s += std::chrono::duration<double>(t1 - t0).count();
    if (all_finite && !overflow) {
      runs.begin_run(sink);
      sink.push(counts.data(), n);
    } else if (!overflow) {
      (void)runs.split(v, n, sink, [&](std::size_t i, std::size_t j) {
        sink.push(counts.data() + i, j - i);
      });
    }
    timing.sink_s += seconds_since(t1);
  });
  if (!ok) {
    return kExitRuntime;
  }
  ch.non_finite = total - s.n;
  return check_counts(src, where, ch, s, q, cand, overflow, timing, err);
}

}  // namespace imu::sim

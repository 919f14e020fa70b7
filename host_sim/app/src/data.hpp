// Loading a sensor recording from a MAT-file and converting it to counts (host code).
//
// What the data may hold, and what is refused (no silent wrong answer):
//  * non-finite samples (NaN, +-Inf) are gaps, never numbers: counted (non_finite), given count 0
//    in the counts and skipped by every consumer (ADEV: mark_missing; run: not sent). Samples
//    before the first / after the last finite one are not part of the series. A channel with no
//    finite sample is an error.
//  * the LSB must represent the data: every finite |value| / LSB must fit int32 counts, and the
//    quantisation must not collapse the data (refused when more than 99 % of the finite samples
//    fall in one count while the std of the quantised values is under half the values' std; data
//    already on a coarse grid keep their std and pass).
//  * the rate must be in [kMinFsHz, kMaxFsHz]; `fs` or else `Fs` is read from the file.
//  * a channel must be a vector (an N x 6 matrix is refused, with how to split it).
#ifndef IMU_SIM_DATA_HPP
#define IMU_SIM_DATA_HPP

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common.hpp"
#include "imu/cli/text_input.hpp"
#include "imu/mat/mat_reader.hpp"

namespace imu::sim {

/// Sampling rates imu-sim accepts (file or --fs): beyond them taus and sample periods are absurd
/// or overflow the sensor clock (ns).
inline constexpr double kMinFsHz = 1e-3;
inline constexpr double kMaxFsHz = 1e6;
/// Samples of one channel: the MAT reader's budget (256 MiB of doubles per variable).
inline constexpr std::uint64_t kMaxSamples = std::uint64_t{1} << 25U;
/// Samples of one channel written by synth and read in chunks by adev: 2e8 (1.6 GB of doubles,
/// 139 h at 400 Hz), within a MAT v5 element (2^31 bytes) and the streaming reader's budget.
inline constexpr std::uint64_t kMaxStreamSamples = 200000000U;

struct ChannelData {
  bool present = false;
  double lsb = 0.0;             ///< value of one count
  bool lsb_from_file = false;   ///< acc_lsb / gyro_lsb read from the file
  bool lsb_from_option = false; ///< given on the command line (a misfit is a usage error)
  std::uint64_t off_grid = 0;   ///< finite samples not an integer multiple of lsb (> 1e-6 lsb)
  std::uint64_t non_finite = 0; ///< NaN / Inf samples: gaps
  std::string var;              ///< the file's variable (empty: the slot's name acc_x .. gyro_z)
  std::size_t column = 0;       ///< its column, for a matrix named NAME:K (K - 1)
  double scale = 1.0;           ///< stored x scale: integer counts (int16 ..) x their LSB
  bool integer_counts = false;  ///< the variable is of an integer class
  bool no_grid = false;         ///< read as values, without an LSB (adev's exact estimator)
};

/// Any variable of the file in a channel slot (`--channel NAME` or `NAME:K` for column K of a
/// matrix): names[c] non-empty replaces slot c's name acc_x .. gyro_z.
struct ChannelVars {
  std::string names[kNumChannels];
  std::size_t columns[kNumChannels] = {};
  bool column_given[kNumChannels] = {};
};

/// The slot of a channel named on the command line (adev and run alike): acc_x..gyro_z are
/// their own; any other variable (NAME, NAME:K column K of a matrix, a struct field P.NAME)
/// takes the acc_z slot, or gyro_z for a gyro* name (its default LSB and unit), and is put in
/// `vars` (renamed set). False with err on a malformed NAME:K.
[[nodiscard]] bool channel_slot(const std::string& name, std::size_t& chan, ChannelVars& vars,
                                bool& renamed, std::string& err);

// NOLINTNEXTLINE(bugprone-reserved-identifier): '__i0' is the compiler's implicit array copy loop
struct SensorData {
  std::string path;
  double fs_hz = 0.0;
  std::size_t n_samples = 0;  ///< length of the present channels (all equal)
  ChannelData ch[kNumChannels];
};

/// Channel c of sd's file as a stream: its variable (ch.var, else acc_x..gyro_z) and column.
[[nodiscard]] mat::Result<mat::ChannelStream> open_channel(const SensorData& sd, std::size_t c);
/// Integer counts (ch.integer_counts) to the channel's unit: v[i] *= ch.scale; else nothing.
void scale_counts(const ChannelData& ch, double* v, std::size_t n);

/// Read the rate (`fs`/`Fs`, or fs_override if > 0), the LSBs (lsb_override[c] if > 0, else the
/// file's acc_lsb / gyro_lsb, else default_lsb(c)), which channels are present and their length
/// (n_samples), from the variables' headers and the scalars; the file is never read whole
/// (mat::scan_variables, mat::stream_scalar). The channels are then read by stream_counts().
/// vars: other variables in the slots (nullptr: acc_x .. gyro_z); a struct field (`imu.acc_z`)
/// takes its struct's fs/Fs and acc_lsb/gyro_lsb before the top-level ones. An integer variable (int16
/// counts from a logger) with an LSB (option or file) is read as counts x LSB; without one its
/// LSB is 1 (counts).
[[nodiscard]] bool load_sensor_meta(const std::string& path, const bool (&want)[kNumChannels],
                                    const bool (&required)[kNumChannels],
                                    const double (&lsb_override)[kNumChannels],
                                    double fs_override, SensorData& out, std::string& err,
                                    const ChannelVars* vars = nullptr);

/// Where stream_counts() delivers a channel: its finite runs as counts, in order, and each run
/// of non-finite samples between two finite ones as one gap (those before the first and after
/// the last finite sample are not part of the series), exactly as adev_with_gaps() splits a
/// whole record.
class CountSink {
 public:
  CountSink() = default;
  CountSink(const CountSink&) = delete;
  CountSink& operator=(const CountSink&) = delete;
  CountSink(CountSink&&) = delete;
  CountSink& operator=(CountSink&&) = delete;
  virtual ~CountSink() = default;
  virtual void push(const std::int32_t* counts, std::size_t n) = 0;
  virtual void gap(std::size_t n) = 0;
  /// True: stream_counts() delivers the finite samples as they are (push_values), not as counts
  /// of the LSB: float data without an LSB, for an estimator that needs no grid.
  [[nodiscard]] virtual bool takes_values() const { return false; }
  /// The finite samples of a run, in the channel's unit (only when takes_values()).
  virtual void push_values(const double* /*values*/, std::size_t /*n*/) {}
};

/// Where a channel's samples come from, pass after pass (stream_counts() may take two): a MAT
/// variable (MatChannelSource) or a text column (TextChannelSource). Read by one thread at a time.
class ChunkSource {
 public:
  ChunkSource() = default;
  ChunkSource(const ChunkSource&) = delete;
  ChunkSource& operator=(const ChunkSource&) = delete;
  ChunkSource(ChunkSource&&) = delete;
  ChunkSource& operator=(ChunkSource&&) = delete;
  virtual ~ChunkSource() = default;
  /// Start a pass at the first sample. False with err.
  [[nodiscard]] virtual bool open(std::string& err) = 0;
  /// Up to n samples: got, 0 at the end. False with err.
  [[nodiscard]] virtual bool read(double* out, std::size_t n, std::size_t& got,
                                  std::string& err) = 0;
};

/// Channel c of sd's file (open_channel()).
class MatChannelSource final : public ChunkSource {
 public:
  MatChannelSource(const SensorData& sd, std::size_t c) : sd_(sd), c_(c) {}
  [[nodiscard]] bool open(std::string& err) override;
  [[nodiscard]] bool read(double* out, std::size_t n, std::size_t& got, std::string& err) override;

 private:
  const SensorData& sd_;
  std::size_t c_;
  std::unique_ptr<mat::ChannelStream> stream_;
};

/// A text file's column (or a ROS bag topic's, `topic`) on its regular grid
/// (imu::cli::TextColumnStream): rows are read as they are needed, never held. samples(): the
/// grid samples the last pass gave.
/// With `read_samples` (the column already read on its grid, in one pass over the file for
/// several columns), the passes are over those samples instead of the file.
class TextChannelSource final : public ChunkSource {
 public:
  TextChannelSource(std::string path, std::string column, double fs_hz, double time_unit_s,
                    std::string topic, const std::vector<double>* read_samples = nullptr)
      : path_(std::move(path)), column_(std::move(column)), fs_hz_(fs_hz),
        time_unit_s_(time_unit_s), topic_(std::move(topic)), read_samples_(read_samples) {}
  [[nodiscard]] bool open(std::string& err) override;
  [[nodiscard]] bool read(double* out, std::size_t n, std::size_t& got, std::string& err) override;
  [[nodiscard]] double fs_hz() const { return stream_.fs_hz(); }
  [[nodiscard]] std::uint64_t samples() const { return samples_; }

 private:
  std::string path_;
  std::string column_;
  double fs_hz_;
  double time_unit_s_;  // 0: the time column's own
  std::string topic_;   // a ROS bag's topic ("": its only sensor_msgs/Imu one)
  const std::vector<double>* read_samples_;
  imu::cli::TextColumnStream stream_;
  std::uint64_t samples_ = 0;
};

/// Seconds spent by stream_counts(): reading/inflating, quantising and checking, in the sink.
struct StreamTiming {
  double read_s = 0.0;
  double quantize_s = 0.0;
  double sink_s = 0.0;
};

/// Channel c (present, ch.lsb set by load_sensor_meta) read from the file in chunks of 8192
/// samples and quantised into `sink`, with these checks (no finite sample, int32
/// overflow, collapse: same messages and statuses) made on running statistics. The sink sees
/// every chunk before the verdict: its result is valid only when 0 is returned. A second pass
/// over the file is made only when the quantised std is under half the values' std (to count
/// the share of the most common count exactly). Fills ch.non_finite and ch.off_grid. Memory: two
/// chunks and the reader's ~0.3 MB, whatever the length.
[[nodiscard]] int stream_counts(const std::string& path, std::size_t c, ChannelData& ch,
                                CountSink& sink, StreamTiming& timing, std::string& err);
/// The same from any source; `where` begins its error messages (e.g. "FILE: variable 'X': ").
/// A sink that takes_values() gets the finite samples as they are: no LSB, so no quantisation,
/// int32 or collapse check (ch.off_grid stays 0).
[[nodiscard]] int stream_counts(ChunkSource& src, const std::string& where, ChannelData& ch,
                                CountSink& sink, StreamTiming& timing, std::string& err);

}  // namespace imu::sim

#endif  // IMU_SIM_DATA_HPP

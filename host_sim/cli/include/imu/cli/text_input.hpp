// Text input for imu-sim: CSV, TSV or whitespace-separated columns with a header row of names,
// as loggers and spreadsheets write them. Lines starting with '#' are comments. An empty field
// or nan/NaN is a missing sample. The header is the first row, or the last '#' line before the
// data when that names every column (EuRoC's "#timestamp [ns],w_RS_S_x [rad s^-1],..."); a unit
// in brackets after a blank is not part of the name. A time column (t, time, timestamp, %time,
// or time/timestamp with a unit suffix: timestamp_us) gives the rate when none is given; its
// unit is the one it states (suffix, bracket, --time-unit), else read from its steps (integer
// times whose steps are under 1 Hz in seconds are ms, us or ns: the first giving 1 Hz or more),
// and and its irregularities become gaps: a step of k sample periods (k >= 1.5)
// inserts k - 1 missing samples, counted and reported. The work is bounded by the file: lines
// of at most kMaxLineBytes, at most kMaxColumns columns, at most kGapAllowance + 4 per row
// missing samples filled in from the time column. Host code.
#ifndef IMU_CLI_TEXT_INPUT_HPP
#define IMU_CLI_TEXT_INPUT_HPP

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "imu/cli/row_source.hpp"

namespace imu::cli {

struct TextTable {
  std::vector<std::string> names;          ///< the header's column names
  std::vector<std::string> units;          ///< the header's bracketed units ("" if none)
  std::vector<std::vector<double>> cols;   ///< one vector per column, NaN where missing
};

/// Longest line read (a longer one is refused with its line number).
inline constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20U;
/// Most columns in a header (a wider one is refused).
inline constexpr std::size_t kMaxColumns = 4096;
/// The slowest rate a time column's unit is read as from its steps (below it in seconds, the
/// times are taken as ms, us or ns).
inline constexpr double kMinDetectedRateHz = 1.0;
/// Missing samples filled in from the time column's steps: at most this plus 4 per row read.
inline constexpr std::uint64_t kGapAllowance = std::uint64_t{1} << 20U;

/// True if the file is text rather than a MAT-file: no "MATLAB" header text, no MAT endian mark
/// at byte 126, no NUL byte in its first 512 bytes (an empty or binary file goes to the MAT
/// reader, which says what is wrong with it).
[[nodiscard]] bool looks_like_text(const std::string& path);

/// The rows of a text table one at a time, the header read by open(): constant memory (one
/// line). The one parser of text input: read_text_table and TextColumnStream are built on it.
class TextRows final : public RowSource {
 public:
  /// Refused with a one-line err: not a regular file, larger than max_bytes, no header (a
  /// first row of names), more than kMaxColumns columns, a line longer than kMaxLineBytes.
  [[nodiscard]] bool open(const std::string& path, std::string& err,
                          std::uint64_t max_bytes = std::uint64_t{2} << 30U);
  [[nodiscard]] const std::vector<std::string>& names() const override { return names_; }
  /// Each column's unit from its header ("w_RS_S_x [rad s^-1]": "rad s^-1"; "" if none).
  [[nodiscard]] const std::vector<std::string>& units() const override { return units_; }
  /// Parse only these columns in next() (the others come back NaN, whatever they hold).
  void only(const std::vector<std::size_t>& columns) override;
  /// Also keep this column's exact value when it is an integer (has_exact(), exact()): epoch
  /// nanoseconds have more digits than a double.
  void exact_integers(std::size_t column) override { exact_column_ = column; }
  [[nodiscard]] bool has_exact() const override { return has_exact_; }
  [[nodiscard]] long long exact() const override { return exact_; }
  /// The next data row as numbers (names().size() of them; NaN for an empty or nan field).
  /// False at the end (err empty) or on a bad row (err names the line: another number of fields
  /// than the header, a field that is not a number, a line longer than kMaxLineBytes).
  [[nodiscard]] bool next(std::vector<double>& row, std::string& err) override;
  [[nodiscard]] std::string origin() const override { return "text input"; }
  [[nodiscard]] std::string note() const override { return std::string(); }

 private:
  // The next line into line_ (without its end): 1, 0 at the end, -1 too long (err set).
  int read_line(std::string& err);
  std::string path_;
  std::ifstream in_;
  std::string line_;
  std::vector<std::string> names_;
  std::vector<std::string> units_;
  std::vector<bool> needed_;  // empty: every column
  std::uint64_t line_no_ = 0;
  char delim_ = ' ';
  bool pending_ = false;  // line_ holds the first data row (the header was a comment line)
  static constexpr std::size_t kNoColumn = ~std::size_t{0};
  std::size_t exact_column_ = kNoColumn;
  long long exact_ = 0;
  bool has_exact_ = false;
};

/// Read the whole table (TextRows into one vector per column). The errors of TextRows, and no
/// data row. O(file size) memory.
[[nodiscard]] bool read_text_table(const std::string& path, TextTable& table, std::string& err,
                                   std::uint64_t max_bytes = std::uint64_t{2} << 30U);

/// The time column of a table: the first whose name is_time_name; names.size() if none.
[[nodiscard]] std::size_t time_column(const std::vector<std::string>& names);
/// t, time, timestamp, %time (rostopic's), or t/time/timestamp with a unit suffix (_s, _ms,
/// _us, _ns): then *unit_s is that unit in seconds, else 0.
[[nodiscard]] bool is_time_name(const std::string& name, double* unit_s);
class Args;
/// --time-unit s|ms|us|ns: unit_s its seconds per unit (0 when the option is absent). False
/// with err on another value.
[[nodiscard]] bool time_unit_option(const Args& a, double& unit_s, std::string& err);
/// Seconds per unit of a time unit's name (s, sec, ms, msec, us, usec, µs, ns, nsec); 0 if none.
[[nodiscard]] double time_unit_s(const std::string& unit);
/// The unit of raw times t[0..n): stated_s if > 0; else seconds unless every time is an integer,
/// then the first of s, ms, us, ns in which the median step matches fs_hz within 2 % (a rate
/// given) or is a rate of kMinDetectedRateHz or more. detected: a unit other than seconds was
/// read from the steps.
void time_scale(const double* t, std::size_t n, double fs_hz, double stated_s, double& unit_s,
                bool& detected);

/// Rows whose time steps decide the rate when no --fs is given: the median step of the time
/// column over its first kRateRows + 1 rows (every command, whole or streamed).
inline constexpr std::size_t kRateRows = 65536;

/// Places rows on the regular grid of period ts_s: a row after a step of k periods (k = the
/// step / ts rounded, k >= 2) comes after k - 1 missing samples (NaN), counted. One rule for the
/// whole table and the stream. Refused, with the row and the reason (never a wrong rate):
/// - a time that does not increase;
/// - a step under half a period (the rate rises there: a 100 Hz log that goes on at 1 kHz);
/// - kRateRunSteps steps in a row of the same k >= 2 (the rate falls there to 1/k);
/// - more than 16 + 1 % of the steps off the grid by over kJitterPeriods (timestamps too
///   irregular for one rate);
/// - missing samples beyond kGapAllowance + 4 per row (a small file that would fill in
///   millions of samples: split it at its gaps).
class TimeGrid {
 public:
  static constexpr double kJitterPeriods = 0.25;
  static constexpr std::uint64_t kRateRunSteps = 64;
  explicit TimeGrid(double ts_s) : ts_s_(ts_s) {}
  /// The missing samples before a row at time t_s (0 for the first row). False with err.
  [[nodiscard]] bool place(double t_s, std::uint64_t row, const std::string& column,
                           std::uint64_t& missing, std::string& err);
  [[nodiscard]] std::uint64_t gap_samples() const { return gap_samples_; }
  /// Steps off the grid by more than kJitterPeriods (within the tolerance).
  [[nodiscard]] std::uint64_t off_grid_steps() const { return off_grid_; }

 private:
  double ts_s_;
  double last_t_s_ = 0.0;
  bool started_ = false;
  std::uint64_t gap_samples_ = 0;
  std::uint64_t off_grid_ = 0;
  std::uint64_t run_k_ = 0;
  std::uint64_t run_ = 0;
};

struct TextChannel {
  std::vector<double> samples;  ///< on a regular grid; NaN: missing (field or time gap)
  double fs_hz = 0.0;           ///< given, or 1 / median step of the time column
  std::uint64_t time_gap_samples = 0;  ///< samples inserted for steps of the time column
  std::string time_column;             ///< the time column used ("" if none)
  double time_unit_s = 1.0;            ///< its unit in seconds
  std::string time_note;               ///< how the unit was found, when read from the steps
};

/// Column `name` of the table on a regular grid. fs_hz > 0: that rate (the time column, if
/// any, still places the samples); else the time column's median step (kRateRows). Refused:
/// unknown name (the names are listed), no rate and no time column, a time column TimeGrid
/// refuses, an fs_hz more than 2 % from the time column's median step.
/// time_unit_s > 0: the time column's unit (--time-unit), else the one it states or its steps'.
[[nodiscard]] bool text_channel(const TextTable& table, const std::string& name, double fs_hz,
                                TextChannel& out, std::string& err, double time_unit_s = 0.0);

/// Columns of a text file (or of any RowSource: open_rows(), a ROS bag's topic) on the same
/// grid as text_channel gives, read row by row: memory independent of the number of rows (the
/// first kRateRows rows are held while the rate is taken from them). Same refusals and
/// messages as TextRows and text_channel. With several columns a sample is one value per
/// column, interleaved in the order the names were given (one pass over the file for all of
/// them). topic: a ROS bag's sensor_msgs/Imu topic ("": its only one; refused for text).
class TextColumnStream {
 public:
  [[nodiscard]] bool open(const std::string& path, const std::string& name, double fs_hz,
                          std::string& err, double time_unit_s = 0.0,
                          const std::string& topic = std::string());
  [[nodiscard]] bool open(const std::string& path, const std::vector<std::string>& names,
                          double fs_hz, std::string& err, double time_unit_s = 0.0,
                          const std::string& topic = std::string());
  /// Up to n samples into out (n x columns() values): got samples, 0 at the end. False on a
  /// bad row (err).
  [[nodiscard]] bool read(double* out, std::size_t n, std::size_t& got, std::string& err);
  [[nodiscard]] std::size_t columns() const { return cols_.size(); }
  [[nodiscard]] double fs_hz() const { return fs_hz_; }
  /// Samples inserted for time steps so far (all of them once read() gave 0).
  [[nodiscard]] std::uint64_t time_gap_samples() const { return grid_.gap_samples(); }
  [[nodiscard]] const std::string& time_name() const { return time_name_; }
  /// How the time column's unit was found, when it was read from the steps, or how a ROS
  /// bag's times were taken (RowSource::note()); "" otherwise.
  [[nodiscard]] const std::string& time_note() const { return time_note_; }
  /// What the rows are (RowSource::origin(): "text input", "ROS bag topic /imu").
  [[nodiscard]] const std::string& origin() const { return source_; }

 private:
  bool next_row(double& t, bool& have, std::string& err);
  void hold(std::vector<double>& to);  // t (raw_time()), then the columns' values of row_
  double raw_time();  // row_'s time from the first row's, in the column's unit
  std::unique_ptr<RowSource> rows_;
  std::vector<double> row_;
  std::vector<double> head_;  // (t, values...) of the rows read for the rate
  std::size_t head_pos_ = 0;  // rows of head_ given out
  std::vector<std::size_t> cols_;
  std::size_t time_ = 0;
  std::string time_name_;
  std::string time_note_;
  std::string source_;  // RowSource::origin()
  double unit_s_ = 1.0;  // the time column's unit in seconds
  bool have_origin_ = false;  // the first row's time (times are taken from it):
  bool origin_exact_ = false;  //   as an integer (origin_i_) or a double (origin_)
  long long origin_i_ = 0;
  double origin_ = 0.0;
  double fs_hz_ = 0.0;
  TimeGrid grid_{1.0};
  std::uint64_t row_no_ = 0;
  std::uint64_t pending_missing_ = 0;  // NaN samples still to give before pending_values_
  std::vector<double> pending_values_;
  std::vector<double> values_;  // of the row next_row gave
  bool have_pending_ = false;
};

/// --channel SPEC on a text table (imu/cli/args.hpp expand_channels): `all` is the IMU channels
/// it holds, else every column but a time column (is_time_name); or a comma list.
[[nodiscard]] bool text_channels(const std::vector<std::string>& names, const std::string& spec,
                                 std::vector<std::string>& out, std::string& err);

}  // namespace imu::cli

#endif  // IMU_CLI_TEXT_INPUT_HPP

// Text input for imu-sim (issue 13): CSV, TSV or whitespace-separated columns with a header row
// of names, as loggers and spreadsheets write them. Lines starting with '#' are comments. An
// empty field or nan/NaN is a missing sample. A column named t, time or timestamp (seconds)
// gives the rate when none is given, and its irregularities become gaps: a step of k sample
// periods (k >= 1.5) inserts k - 1 missing samples, counted and reported. Host code.
#ifndef IMU_CLI_TEXT_INPUT_HPP
#define IMU_CLI_TEXT_INPUT_HPP

#include <cstdint>
#include <string>
#include <vector>

namespace imu::cli {

struct TextTable {
  std::vector<std::string> names;          ///< the header's column names
  std::vector<std::vector<double>> cols;   ///< one vector per column, NaN where missing
};

/// True if the file is text rather than a MAT-file: no "MATLAB" header text, no MAT endian mark
/// at byte 126, no NUL byte in its first 512 bytes (an empty or binary file goes to the MAT
/// reader, which says what is wrong with it).
[[nodiscard]] bool looks_like_text(const std::string& path);

/// Read the whole table. Refused with a one-line err (naming the line): not a regular file,
/// larger than max_bytes, no header, a row with another number of fields, a field that is not a
/// number. O(file size).
[[nodiscard]] bool read_text_table(const std::string& path, TextTable& table, std::string& err,
                                   std::uint64_t max_bytes = std::uint64_t{2} << 30U);

struct TextChannel {
  std::vector<double> samples;  ///< on a regular grid; NaN: missing (field or time gap)
  double fs_hz = 0.0;           ///< given, or 1 / median step of the time column
  std::uint64_t time_gap_samples = 0;  ///< samples inserted for steps of the time column
  std::string time_column;             ///< the time column used ("" if none)
};

/// Column `name` of the table on a regular grid. fs_hz > 0: that rate (the time column, if
/// any, still places the samples); else the time column's median step. Refused: unknown name
/// (the names are listed), no rate and no time column, a time column that does not increase.
[[nodiscard]] bool text_channel(const TextTable& table, const std::string& name, double fs_hz,
                                TextChannel& out, std::string& err);

/// --channel SPEC on a text table (imu/cli/args.hpp expand_channels): `all` is the IMU channels
/// it holds, else every column but a time column (t, time, timestamp); or a comma list.
[[nodiscard]] bool text_channels(const TextTable& table, const std::string& spec,
                                 std::vector<std::string>& out, std::string& err);

}  // namespace imu::cli

#endif  // IMU_CLI_TEXT_INPUT_HPP

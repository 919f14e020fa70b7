// Rows of samples read one at a time, whatever the file's format: a text table (TextRows,
// imu/cli/text_input.hpp) or a ROS bag's sensor_msgs/Imu topic (BagRows, imu/cli/rosbag.hpp).
// The one interface the grid code reads (TextColumnStream: the rate from the time column's
// steps, its gaps and its refusals hold for every format). Host code.
#ifndef IMU_CLI_ROW_SOURCE_HPP
#define IMU_CLI_ROW_SOURCE_HPP

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace imu::cli {

/// A table read row by row, its names known once it is open. Read by one thread at a time.
class RowSource {
 public:
  RowSource() = default;
  RowSource(const RowSource&) = delete;
  RowSource& operator=(const RowSource&) = delete;
  RowSource(RowSource&&) = delete;
  RowSource& operator=(RowSource&&) = delete;
  virtual ~RowSource() = default;
  /// The column names (a time column among them is named as is_time_name() knows it).
  [[nodiscard]] virtual const std::vector<std::string>& names() const = 0;
  /// Each column's unit ("" if none stated).
  [[nodiscard]] virtual const std::vector<std::string>& units() const = 0;
  /// Only these columns need values in next() (the others may come back NaN).
  virtual void only(const std::vector<std::size_t>& columns) = 0;
  /// Keep this column's exact integer value (has_exact(), exact()): epoch nanoseconds have
  /// more digits than a double.
  virtual void exact_integers(std::size_t column) = 0;
  /// The last row's value of the exact_integers() column was an integer: exact() holds it.
  [[nodiscard]] virtual bool has_exact() const = 0;
  [[nodiscard]] virtual long long exact() const = 0;
  /// The next row (names().size() values, NaN where missing). False at the end (err empty) or
  /// on a bad row (err: one line, the file and the place).
  [[nodiscard]] virtual bool next(std::vector<double>& row, std::string& err) = 0;
  /// What the rows are, for reports: "text input", "ROS bag topic '/imu'".
  [[nodiscard]] virtual std::string origin() const = 0;
  /// How the times were taken when that is worth a note ("" otherwise).
  [[nodiscard]] virtual std::string note() const = 0;
};

/// The rows of a file: a ROS bag (looks_like_bag) through BagRows on `topic` ("": its only
/// sensor_msgs/Imu topic), any other file through TextRows. nullptr with a one-line err when
/// the file is refused, or a topic is given for a file that is not a bag.
[[nodiscard]] std::unique_ptr<RowSource> open_rows(const std::string& path,
                                                   const std::string& topic, std::string& err);

}  // namespace imu::cli

#endif  // IMU_CLI_ROW_SOURCE_HPP

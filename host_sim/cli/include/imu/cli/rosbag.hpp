// ROS bag input (ROS bag format 2.0): the sensor_msgs/Imu messages of one topic as rows
// t_ns, acc_x, acc_y, acc_z (linear_acceleration, m/s^2), gyro_x, gyro_y, gyro_z
// (angular_velocity, rad/s), for the grid code of text input (imu/cli/row_source.hpp).
//
// The file: "#ROSBAG V2.0\n", the bag header record (index_pos, conn_count, chunk_count), chunk
// records (compression "none" or "lz4"; "bz2" is refused with the command that converts it)
// holding connection and message data records, each followed by index data records; from
// index_pos the connection records (topic, and in their data the connection header: type,
// md5sum) and the chunk info records. The connections are read from the index; the messages
// chunk by chunk, in the order they were written. A bag without an index (index_pos 0: the
// recording was not closed) is refused with `rosbag reindex`.
//
// The time of a row is the message's header.stamp in exact nanoseconds; when every stamp of
// the topic is zero, the message data record's time (when it was recorded), said in note().
//
// Every malformed input is a one-line error naming the byte offset, never a read out of
// bounds. Memory: one chunk (compressed and decompressed), refused above kMaxBagChunkBytes, and
// the connection list; independent of the number of chunks and messages. Cost: one pass over
// the file per pass over the rows (the first chunk twice when the stamps are looked at).
// Host code.
#ifndef IMU_CLI_ROSBAG_HPP
#define IMU_CLI_ROSBAG_HPP

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "imu/cli/row_source.hpp"

namespace imu::cli {

/// Largest chunk read, compressed or not (a larger one is refused with its size).
inline constexpr std::uint64_t kMaxBagChunkBytes = std::uint64_t{256} << 20U;
/// Largest record header, and record outside a chunk (connection records hold the message
/// definition: a few KiB).
inline constexpr std::uint64_t kMaxBagRecordBytes = std::uint64_t{16} << 20U;
/// Most connections in a bag's index.
inline constexpr std::uint32_t kMaxBagConnections = 65536;
/// The message type read, and the MD5 of its definition (sensor_msgs/Imu of ROS 1).
inline constexpr const char* kImuType = "sensor_msgs/Imu";
inline constexpr const char* kImuMd5 = "6a62c6daae103f4ff57a132d6f95cec2";

/// True if the file begins with "#ROSBAG V2.0\n" (a regular file only: never opens a FIFO).
[[nodiscard]] bool looks_like_bag(const std::string& path);

/// A connection of a bag's index.
struct BagConnection {
  std::uint32_t id = 0;
  std::string topic;
  std::string type;    ///< the message type (sensor_msgs/Imu)
  std::string md5sum;  ///< of the message definition
};

/// A bag's sensor_msgs/Imu topic as rows (RowSource), read chunk by chunk.
class BagRows final : public RowSource {
 public:
  /// Open the bag and pick the topic: `topic`, or the bag's only sensor_msgs/Imu topic when
  /// empty. Refused with a one-line err: not a ROS bag 2.0, no index, truncated, malformed
  /// records, no sensor_msgs/Imu topic (the topics listed), several and no `topic` (listed;
  /// the message names --topic), `topic` not a sensor_msgs/Imu topic of the bag (the Imu
  /// topics listed; names --topic), another definition (md5sum) of sensor_msgs/Imu, no
  /// message on the topic. Reads the first chunks to see whether every stamp is zero.
  [[nodiscard]] bool open(const std::string& path, const std::string& topic, std::string& err);

  [[nodiscard]] const std::vector<std::string>& names() const override { return names_; }
  [[nodiscard]] const std::vector<std::string>& units() const override { return units_; }
  void only(const std::vector<std::size_t>& /*columns*/) override {}
  void exact_integers(std::size_t column) override { exact_column_ = column; }
  /// The time column (0) is always exact.
  [[nodiscard]] bool has_exact() const override { return exact_column_ == 0; }
  [[nodiscard]] long long exact() const override { return t_ns_; }
  /// The next message of the topic: t_ns, acc_x .. gyro_z. False at the end (err empty) or on
  /// a malformed record, chunk or message (err).
  [[nodiscard]] bool next(std::vector<double>& row, std::string& err) override;
  [[nodiscard]] std::string origin() const override;
  [[nodiscard]] std::string note() const override;

  /// The topic read and every connection of the bag.
  [[nodiscard]] const std::string& topic() const { return topic_; }
  [[nodiscard]] const std::vector<BagConnection>& connections() const { return conns_; }

 private:
  struct Record;
  bool read_at(std::uint64_t pos, void* dst, std::size_t n, std::string& err);
  bool read_record(std::uint64_t pos, std::uint64_t limit, Record& r, std::string& err);
  bool read_index(std::string& err);
  bool pick_topic(const std::string& topic, std::string& err);
  bool load_chunk(const Record& r, std::string& err);
  bool next_message(std::string& err);
  std::string at(std::uint64_t pos) const;
  void rewind();

  std::string path_;
  std::ifstream in_;
  std::uint64_t file_size_ = 0;
  std::uint64_t data_start_ = 0;  // the first record after the bag header
  std::uint64_t index_pos_ = 0;
  std::uint64_t pos_ = 0;  // the next top-level record
  std::vector<BagConnection> conns_;
  std::vector<std::uint32_t> selected_;  // the connections of the topic
  std::string topic_;
  std::vector<std::uint8_t> raw_;    // a chunk's stored bytes
  std::vector<std::uint8_t> chunk_;  // its records
  std::size_t chunk_pos_ = 0;
  std::uint64_t chunk_at_ = 0;  // the file offset of the chunk (for messages)
  std::vector<std::uint8_t> header_;
  std::vector<std::string> names_;
  std::vector<std::string> units_;
  std::size_t exact_column_ = 0;
  bool record_time_ = false;  // every stamp is zero: the records' times are used
  long long t_ns_ = 0;       // the time of the last row
  long long stamp_ns_ = 0;   // the last message's header.stamp
  long long record_ns_ = 0;  // and its record's time
  double values_[6] = {};
};

}  // namespace imu::cli

#endif  // IMU_CLI_ROSBAG_HPP

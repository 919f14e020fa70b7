// ROS bag input (see imu/cli/rosbag.hpp). Offsets and fields follow ROS bag format 2.0.
#include "imu/cli/rosbag.hpp"

#include "imu/cli/lz4.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace imu::cli {
namespace {

// ROS bag format 2.0: the version line, and the op codes of the records.
constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr std::size_t kMagicBytes = sizeof kMagic - 1U;
constexpr std::uint8_t kOpMessage = 0x02U;
constexpr std::uint8_t kOpBagHeader = 0x03U;
constexpr std::uint8_t kOpIndexData = 0x04U;
constexpr std::uint8_t kOpChunk = 0x05U;
constexpr std::uint8_t kOpChunkInfo = 0x06U;
constexpr std::uint8_t kOpConnection = 0x07U;
// sensor_msgs/Imu as serialized by ROS 1 (little endian): std_msgs/Header (uint32 seq, time
// stamp as uint32 sec + uint32 nsec, string frame_id as a uint32 length and its bytes), then
// 37 float64: orientation (4), its covariance (9), angular_velocity (3), its covariance (9),
// linear_acceleration (3), its covariance (9).
constexpr std::size_t kImuHeadBytes = 16U;
constexpr std::size_t kImuBodyBytes = 37U * 8U;
constexpr std::size_t kGyroAt = 13U * 8U;  // angular_velocity in the body
constexpr std::size_t kAccAt = 25U * 8U;   // linear_acceleration
constexpr long long kNsPerS = 1000000000LL;

std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8U) |
         (static_cast<std::uint32_t>(p[2]) << 16U) | (static_cast<std::uint32_t>(p[3]) << 24U);
}

std::uint64_t le64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(le32(p)) | (static_cast<std::uint64_t>(le32(p + 4)) << 32U);
}

double le_double(const std::uint8_t* p) {
  const std::uint64_t bits = le64(p);
  double v = 0.0;
  static_assert(sizeof v == sizeof bits, "IEEE 754 binary64");
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// A ROS time (uint32 sec, then uint32 nsec) in nanoseconds.
long long time_ns(const std::uint8_t* p) {
  return static_cast<long long>(le32(p)) * kNsPerS + static_cast<long long>(le32(p + 4));
}
long long time_ns(std::uint64_t sec_nsec) {
  return static_cast<long long>(sec_nsec & 0xFFFFFFFFU) * kNsPerS +
         static_cast<long long>(sec_nsec >> 32U);
}

// A record header (or a connection header): fields of a uint32 length, then name=value. Empty
// string if every field is well formed, else what is wrong.
std::string check_header(const std::uint8_t* h, std::size_t n) {
  std::size_t i = 0;
  while (i < n) {
    if (n - i < 4U) {
      return "a header field's length is cut off";
    }
    const std::uint32_t len = le32(h + i);
    i += 4U;
    if (len > n - i) {
      return "a header field of " + std::to_string(len) + " bytes runs past its header";
    }
    if (std::memchr(h + i, '=', len) == nullptr) {
      return "a header field without '='";
    }
    i += len;
  }
  return std::string();
}

// The value of field `name` in a well-formed header (check_header); false if absent.
bool find_field(const std::uint8_t* h, std::size_t n, const char* name, const std::uint8_t*& v,
                std::size_t& size) {
  const std::size_t name_len = std::strlen(name);
  std::size_t i = 0;
  while (n - i >= 4U) {
    const std::uint32_t len = le32(h + i);
    i += 4U;
    if (len > name_len && h[i + name_len] == '=' && std::memcmp(h + i, name, name_len) == 0) {
      v = h + i + name_len + 1U;
      size = len - name_len - 1U;
      return true;
    }
    i += len;
  }
  return false;
}

// An integer field of exactly `bytes` bytes (1, 4 or 8), little endian, copied into v (the
// header's buffer may be replaced before the value is used); empty string, else what is wrong.
std::string int_field(const std::uint8_t* h, std::size_t n, const char* name, std::size_t bytes,
                      std::uint64_t& v) {
  const std::uint8_t* p = nullptr;
  std::size_t size = 0;
  if (!find_field(h, n, name, p, size) || p == nullptr) {
    return std::string("no '") + name + "' field";
  }
  if (size != bytes) {
    return std::string("the '") + name + "' field has " + std::to_string(size) + " bytes, not " +
           std::to_string(bytes);
  }
  v = 0;
  for (std::size_t k = bytes; k > 0; --k) {
    v = (v << 8U) | p[k - 1U];
  }
  return std::string();
}

std::string string_field(const std::uint8_t* h, std::size_t n, const char* name, std::string& s) {
  const std::uint8_t* v = nullptr;
  std::size_t size = 0;
  if (!find_field(h, n, name, v, size)) {
    return std::string("no '") + name + "' field";
  }
  s.assign(reinterpret_cast<const char*>(v), size);
  return std::string();
}

std::string list(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) {
    out += (out.empty() ? "" : ", ") + s;
  }
  return out;
}

}  // namespace

// A record read from the file: its header in header_, where its data lies.
struct BagRows::Record {
  std::uint64_t pos = 0;
  std::uint8_t op = 0;
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
  std::uint64_t end = 0;
};

bool looks_like_bag(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    return false;
  }
  std::ifstream f(path, std::ios::binary);
  char head[kMagicBytes] = {};
  f.read(head, sizeof head);
  return static_cast<std::size_t>(f.gcount()) == kMagicBytes &&
         std::memcmp(head, kMagic, kMagicBytes) == 0;
}

std::string BagRows::at(std::uint64_t pos) const {
  return path_ + ": ROS bag record at byte " + std::to_string(pos) + ": ";
}

bool BagRows::read_at(std::uint64_t pos, void* dst, std::size_t n, std::string& err) {
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(pos));
  in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(n));
  if (!in_ || static_cast<std::size_t>(in_.gcount()) != n) {
    err = path_ + ": read error at byte " + std::to_string(pos) + " (" + std::to_string(n) +
          " bytes)";
    return false;
  }
  return true;
}

bool BagRows::read_record(std::uint64_t pos, std::uint64_t limit, Record& r, std::string& err) {
  const std::string past = limit == file_size_ ? "the end of the file (truncated)"
                                               : "the index at byte " + std::to_string(limit);
  std::uint8_t word[4];
  if (limit < pos || limit - pos < 8U) {
    err = at(pos) + "runs past " + past;
    return false;
  }
  if (!read_at(pos, word, 4U, err)) {
    return false;
  }
  const std::uint32_t header_len = le32(word);
  if (header_len > kMaxBagRecordBytes) {
    err = at(pos) + "a header of " + std::to_string(header_len) + " bytes, above the " +
          std::to_string(kMaxBagRecordBytes) + "-byte limit";
    return false;
  }
  if (header_len > limit - pos - 8U) {
    err = at(pos) + "its header of " + std::to_string(header_len) + " bytes runs past " + past;
    return false;
  }
  header_.resize(header_len);
  if (!read_at(pos + 4U, header_.data(), header_len, err) ||
      !read_at(pos + 4U + header_len, word, 4U, err)) {
    return false;
  }
  r.pos = pos;
  r.data_pos = pos + 8U + header_len;
  r.data_len = le32(word);
  if (r.data_len > limit - r.data_pos) {
    err = at(pos) + "its data of " + std::to_string(r.data_len) + " bytes runs past " + past;
    return false;
  }
  r.end = r.data_pos + r.data_len;
  std::string why = check_header(header_.data(), header_.size());
  std::uint64_t op = 0;
  if (why.empty()) {
    why = int_field(header_.data(), header_.size(), "op", 1U, op);
  }
  if (!why.empty()) {
    err = at(pos) + why;
    return false;
  }
  r.op = static_cast<std::uint8_t>(op);
  return true;
}

bool BagRows::read_index(std::string& err) {
  conns_.clear();
  std::vector<std::uint8_t> data;
  std::uint64_t chunk_infos = 0;
  for (std::uint64_t pos = index_pos_; pos < file_size_;) {
    Record r;
    if (!read_record(pos, file_size_, r, err)) {
      return false;
    }
    pos = r.end;
    if (r.op == kOpChunkInfo) {
      ++chunk_infos;
      continue;
    }
    if (r.op != kOpConnection) {
      err = at(r.pos) + "a record of op " + std::to_string(r.op) +
            " in the index (connection and chunk info records only)";
      return false;
    }
    if (conns_.size() >= kMaxBagConnections) {
      err = at(r.pos) + "more than " + std::to_string(kMaxBagConnections) + " connections";
      return false;
    }
    BagConnection c;
    std::uint64_t id = 0;
    std::string why = int_field(header_.data(), header_.size(), "conn", 4U, id);
    if (why.empty()) {
      c.id = static_cast<std::uint32_t>(id);
      why = string_field(header_.data(), header_.size(), "topic", c.topic);
    }
    if (why.empty() && r.data_len > kMaxBagRecordBytes) {
      why = "a connection header of " + std::to_string(r.data_len) + " bytes";
    }
    if (why.empty()) {
      data.resize(r.data_len);
      if (!read_at(r.data_pos, data.data(), data.size(), err)) {
        return false;
      }
      why = check_header(data.data(), data.size());
    }
    if (why.empty()) {
      why = string_field(data.data(), data.size(), "type", c.type);
    }
    if (why.empty()) {
      why = string_field(data.data(), data.size(), "md5sum", c.md5sum);
    }
    if (!why.empty()) {
      err = at(r.pos) + "connection: " + why;
      return false;
    }
    conns_.push_back(std::move(c));
  }
  return true;
}

bool BagRows::pick_topic(const std::string& topic, std::string& err) {
  std::vector<std::string> imu_topics;
  std::vector<std::string> all;
  for (const auto& c : conns_) {
    const std::string named = c.topic + " (" + c.type + ")";
    if (std::find(all.begin(), all.end(), named) == all.end()) {
      all.push_back(named);
    }
    if (c.type == kImuType &&
        std::find(imu_topics.begin(), imu_topics.end(), c.topic) == imu_topics.end()) {
      imu_topics.push_back(c.topic);
    }
  }
  if (imu_topics.empty()) {
    err = path_ + ": no " + kImuType + " topic in the ROS bag; its topics: " +
          (all.empty() ? std::string("none") : list(all));
    return false;
  }
  if (topic.empty() && imu_topics.size() > 1) {
    err = path_ + ": " + std::to_string(imu_topics.size()) + " " + kImuType + " topics: " +
          list(imu_topics) + "; choose one with --topic";
    return false;
  }
  topic_ = topic.empty() ? imu_topics[0] : topic;
  if (std::find(imu_topics.begin(), imu_topics.end(), topic_) == imu_topics.end()) {
    err = path_ + ": --topic " + topic_ + ": no " + kImuType + " topic of that name; the " +
          kImuType + " topics: " + list(imu_topics);
    return false;
  }
  selected_.clear();
  for (const auto& c : conns_) {
    if (c.topic != topic_ || c.type != kImuType) {
      continue;
    }
    if (c.md5sum != kImuMd5) {
      err = path_ + ": topic " + topic_ + ": " + kImuType + " of md5sum " + c.md5sum +
            ", another definition than ROS 1's (" + kImuMd5 + ")";
      return false;
    }
    selected_.push_back(c.id);
  }
  return true;
}

bool BagRows::open(const std::string& path, const std::string& topic, std::string& err) {
  path_ = path;
  err.clear();
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    err = path + ": " + std::strerror(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    err = path + ": not a regular file";
    return false;
  }
  file_size_ = static_cast<std::uint64_t>(st.st_size);
  in_.close();
  in_.clear();
  in_.open(path, std::ios::binary);
  if (!in_) {
    err = path + ": " + std::strerror(errno);
    return false;
  }
  char magic[kMagicBytes] = {};
  if (file_size_ < kMagicBytes || !read_at(0, magic, kMagicBytes, err) ||
      std::memcmp(magic, kMagic, kMagicBytes) != 0) {
    err = path + ": not a ROS bag of format 2.0 (it does not begin with #ROSBAG V2.0)";
    return false;
  }
  Record r;
  if (!read_record(kMagicBytes, file_size_, r, err)) {
    return false;
  }
  std::uint64_t index_pos = 0;
  std::uint64_t conns = 0;
  std::string why = r.op == kOpBagHeader ? std::string() : "not the bag header record (op 0x03)";
  if (why.empty()) {
    why = int_field(header_.data(), header_.size(), "index_pos", 8U, index_pos);
  }
  if (why.empty()) {
    why = int_field(header_.data(), header_.size(), "conn_count", 4U, conns);
  }
  if (!why.empty()) {
    err = at(r.pos) + why;
    return false;
  }
  data_start_ = r.end;
  index_pos_ = index_pos;
  if (index_pos_ == 0U) {
    err = path + ": ROS bag without an index (the recording was not closed); run `rosbag "
                 "reindex " + path + "` first";
    return false;
  }
  if (index_pos_ > file_size_) {
    err = path + ": ROS bag truncated: its index is at byte " + std::to_string(index_pos_) +
          ", the file ends at byte " + std::to_string(file_size_);
    return false;
  }
  if (index_pos_ < data_start_) {
    err = at(r.pos) + "index_pos " + std::to_string(index_pos_) + " lies inside the bag header";
    return false;
  }
  if (!read_index(err)) {
    return false;
  }
  if (conns_.size() != conns) {
    err = path + ": ROS bag index holds " + std::to_string(conns_.size()) +
          " connections, its header says " + std::to_string(conns);
    return false;
  }
  if (!pick_topic(topic, err)) {
    return false;
  }
  names_ = {"t_ns", "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"};
  units_ = {"ns", "m/s^2", "m/s^2", "m/s^2", "rad/s", "rad/s", "rad/s"};
  // The clock: the header stamps, unless every one of them is zero (a driver that leaves them
  // unset). Usually the first message settles it.
  record_time_ = false;
  rewind();
  bool any = false;
  bool stamped = false;
  while (!stamped && next_message(err)) {
    any = true;
    stamped = stamp_ns_ != 0;
  }
  if (!err.empty()) {
    return false;
  }
  if (!any) {
    err = path + ": topic " + topic_ + " holds no message";
    return false;
  }
  record_time_ = !stamped;
  rewind();
  return true;
}

void BagRows::rewind() {
  pos_ = data_start_;
  chunk_.clear();
  chunk_pos_ = 0;
}

std::string BagRows::origin() const { return "ROS bag topic " + topic_; }

std::string BagRows::note() const {
  return record_time_ ? "the header stamps of " + topic_ +
                            " are all zero: its times are the bag's record times"
                      : std::string();
}

bool BagRows::load_chunk(const Record& r, std::string& err) {
  std::string compression;
  std::uint64_t size = 0;
  std::string why = string_field(header_.data(), header_.size(), "compression", compression);
  if (why.empty()) {
    why = int_field(header_.data(), header_.size(), "size", 4U, size);
  }
  if (!why.empty()) {
    err = at(r.pos) + "chunk: " + why;
    return false;
  }
  if (compression == "bz2") {
    err = path_ + ": ROS bag chunk compressed with bz2: not read; run `rosbag decompress " +
          path_ + "` (or `rosbag compress --lz4`) first";
    return false;
  }
  if (compression != "none" && compression != "lz4") {
    err = at(r.pos) + "chunk compressed with '" + compression + "' (none and lz4 are read)";
    return false;
  }
  if (size > kMaxBagChunkBytes || r.data_len > kMaxBagChunkBytes) {
    err = at(r.pos) + "a chunk of " + std::to_string(std::max<std::uint64_t>(size, r.data_len)) +
          " bytes, above the " + std::to_string(kMaxBagChunkBytes) + "-byte limit";
    return false;
  }
  const auto n = static_cast<std::size_t>(size);  // at most kMaxBagChunkBytes
  chunk_at_ = r.pos;
  chunk_pos_ = 0;
  chunk_.clear();
  if (compression == "none") {
    if (r.data_len != size) {
      err = at(r.pos) + "an uncompressed chunk of " + std::to_string(r.data_len) +
            " bytes, its header says " + std::to_string(size);
      return false;
    }
    chunk_.resize(n);
    if (!read_at(r.data_pos, chunk_.data(), n, err)) {
      chunk_.clear();
      return false;
    }
    return true;
  }
  raw_.resize(r.data_len);
  if (!read_at(r.data_pos, raw_.data(), raw_.size(), err)) {
    return false;
  }
  const Lz4Status st = lz4_decode_frames(raw_.data(), raw_.size(), n, chunk_);
  if (st != Lz4Status::ok) {
    chunk_.clear();
    err = at(r.pos) + "lz4 chunk: " + describe(st);
    return false;
  }
  if (chunk_.size() != n) {
    err = at(r.pos) + "an lz4 chunk of " + std::to_string(chunk_.size()) +
          " bytes, its header says " + std::to_string(size);
    chunk_.clear();
    return false;
  }
  return true;
}

bool BagRows::next_message(std::string& err) {
  err.clear();
  for (;;) {
    while (chunk_pos_ < chunk_.size()) {
      // A record inside the chunk: header length, header, data length, data.
      const std::uint8_t* p = chunk_.data() + chunk_pos_;
      const std::size_t left = chunk_.size() - chunk_pos_;
      const std::size_t offset = chunk_pos_;
      const auto where = [this, offset]() {
        return path_ + ": ROS bag chunk at byte " + std::to_string(chunk_at_) +
               ", its record at offset " + std::to_string(offset) + ": ";
      };
      std::size_t hl = 0;
      std::size_t dl = 0;
      if (left < 8U || (hl = le32(p)) > left - 8U || (dl = le32(p + 4U + hl)) > left - 8U - hl) {
        err = where() + "runs past the end of its chunk";
        return false;
      }
      const std::uint8_t* h = p + 4U;
      const std::uint8_t* d = p + 8U + hl;
      chunk_pos_ += 8U + hl + dl;
      std::string why = check_header(h, hl);
      std::uint64_t op = 0;
      if (why.empty()) {
        why = int_field(h, hl, "op", 1U, op);
      }
      if (why.empty() && op == kOpConnection) {
        continue;  // the connections were read from the index
      }
      if (why.empty() && op != kOpMessage) {
        why = "a record of op " + std::to_string(op) + " (connection and message data only)";
      }
      std::uint64_t conn = 0;
      std::uint64_t time = 0;
      if (why.empty()) {
        why = int_field(h, hl, "conn", 4U, conn);
      }
      if (why.empty()) {
        why = int_field(h, hl, "time", 8U, time);
      }
      if (!why.empty()) {
        err = where() + why;
        return false;
      }
      if (std::find(selected_.begin(), selected_.end(), static_cast<std::uint32_t>(conn)) ==
          selected_.end()) {
        continue;
      }
      // sensor_msgs/Imu: the frame_id's length decides where the float64 begin.
      const std::size_t frame = dl >= kImuHeadBytes ? le32(d + 12U) : 0U;
      if (dl < kImuHeadBytes + kImuBodyBytes || frame != dl - kImuHeadBytes - kImuBodyBytes) {
        err = where() + "a " + kImuType + " message of " + std::to_string(dl) +
              " bytes (a frame_id of " + std::to_string(frame) + " bytes makes it " +
              std::to_string(kImuHeadBytes + kImuBodyBytes + frame) + ")";
        return false;
      }
      const std::uint8_t* body = d + kImuHeadBytes + frame;
      for (std::size_t k = 0; k < 3U; ++k) {
        values_[k] = le_double(body + kAccAt + 8U * k);
        values_[3U + k] = le_double(body + kGyroAt + 8U * k);
      }
      stamp_ns_ = time_ns(d + 4U);
      record_ns_ = time_ns(time);
      return true;
    }
    if (pos_ >= index_pos_) {
      return false;
    }
    Record r;
    if (!read_record(pos_, index_pos_, r, err)) {
      return false;
    }
    pos_ = r.end;
    if (r.op == kOpChunk) {
      if (!load_chunk(r, err)) {
        return false;
      }
    } else if (r.op == kOpMessage || r.op == kOpConnection) {
      // A record outside any chunk: read as a chunk of that one record.
      if (r.end - r.pos > kMaxBagRecordBytes) {
        err = at(r.pos) + "a record of " + std::to_string(r.end - r.pos) + " bytes outside a chunk";
        return false;
      }
      chunk_at_ = r.pos;
      chunk_pos_ = 0;
      chunk_.resize(static_cast<std::size_t>(r.end - r.pos));
      if (!read_at(r.pos, chunk_.data(), chunk_.size(), err)) {
        return false;
      }
    } else if (r.op != kOpIndexData) {
      err = at(r.pos) + "a record of op " + std::to_string(r.op) +
            " before the index (chunk and index data records only)";
      return false;
    }
  }
}

bool BagRows::next(std::vector<double>& row, std::string& err) {
  if (!next_message(err)) {
    return false;
  }
  t_ns_ = record_time_ ? record_ns_ : stamp_ns_;
  row.resize(names_.size());
  row[0] = static_cast<double>(t_ns_);
  std::copy(values_, values_ + 6, row.begin() + 1);
  return true;
}

}  // namespace imu::cli

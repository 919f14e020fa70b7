// MAT-file level 5 writer. See imu/mat/mat_writer.hpp for the contract.
#include "imu/mat/mat_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>

#include "imu/mat/zlib.hpp"

namespace imu::mat {
namespace {

constexpr std::uint32_t kMiInt8 = 1;
constexpr std::uint32_t kMiUint16 = 4;
constexpr std::uint32_t kMiInt32 = 5;
constexpr std::uint32_t kMiUint32 = 6;
constexpr std::uint32_t kMiDouble = 9;
constexpr std::uint32_t kMiMatrix = 14;
constexpr std::uint32_t kMiCompressed = 15;
constexpr std::uint32_t kMxChar = 4;
constexpr std::uint32_t kMxDouble = 6;
constexpr std::size_t kMaxName = 63;
// Data bytes per variable: half the 32-bit element size, so headers and stored-block overhead fit.
constexpr std::uint64_t kMaxElement = std::numeric_limits<std::uint32_t>::max() / 2U;

// Little-endian 32-bit value at b[at .. at + 3].
void set_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (unsigned i = 0; i < 4U; ++i) {
    b[at + i] = static_cast<std::uint8_t>((v >> (8U * i)) & 0xFFU);
  }
}

void put_u32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  b.resize(b.size() + 4U);
  set_u32(b, b.size() - 4U, v);
}

void pad8(std::vector<std::uint8_t>& b) {
  while (b.size() % 8U != 0U) {
    b.push_back(0);
  }
}

// A data sub-element: small format when it fits in 4 bytes, else tag + data + padding.
void put_sub(std::vector<std::uint8_t>& b, std::uint32_t type, const std::uint8_t* data,
             std::size_t n) {
  if (n <= 4U && n > 0U) {
    put_u32(b, (static_cast<std::uint32_t>(n) << 16U) | type);
    b.insert(b.end(), data, data + n);
    pad8(b);
    return;
  }
  put_u32(b, type);
  put_u32(b, static_cast<std::uint32_t>(n));
  if (n > 0U) {
    b.insert(b.end(), data, data + n);
  }
  pad8(b);
}

// miMATRIX element (tag included) of class `cls`, rows x cols, real part given as raw bytes.
std::vector<std::uint8_t> matrix_element(std::uint32_t cls, std::string_view name, std::size_t rows,
                                         std::size_t cols, std::uint32_t data_type,
                                         const std::uint8_t* data, std::size_t data_bytes) {
  std::vector<std::uint8_t> b;
  b.reserve(64U + name.size() + data_bytes + 8U);
  put_u32(b, kMiMatrix);
  put_u32(b, 0);  // patched below
  put_u32(b, kMiUint32);
  put_u32(b, 8);
  put_u32(b, cls);  // no complex/global/logical flags
  put_u32(b, 0);
  put_u32(b, kMiInt32);
  put_u32(b, 8);
  put_u32(b, static_cast<std::uint32_t>(rows));
  put_u32(b, static_cast<std::uint32_t>(cols));
  put_sub(b, kMiInt8, reinterpret_cast<const std::uint8_t*>(name.data()), name.size());  // NOLINT
  put_sub(b, data_type, data, data_bytes);
  set_u32(b, 4U, static_cast<std::uint32_t>(b.size() - 8U));
  return b;
}

bool fits_int32(std::size_t v) {
  return v <= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
}

}  // namespace

MatWriter::MatWriter(WriterOptions options) : options_(options) {
  std::string text = "MATLAB 5.0 MAT-file, Platform: imu-sim, Created by: imu_mat writer";
  text.resize(116, ' ');  // descriptive text, space padded
  bytes_.assign(text.begin(), text.end());
  bytes_.resize(124, 0);  // subsystem data offset: none
  bytes_.push_back(0x00);  // version 0x0100, little-endian
  bytes_.push_back(0x01);
  bytes_.push_back('I');  // endian indicator: 'I','M' in file order = little-endian
  bytes_.push_back('M');
}

Status MatWriter::check_name(std::string_view name) const {
  const auto bad = [name](const char* why) {
    return MatError{"variable '" + std::string(name) + "': invalid name (" + why + ")"};
  };
  if (name.empty() || name.size() > kMaxName) {
    return bad("1 to 63 characters");
  }
  const auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); };
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  if (!alpha(name[0])) {
    return bad("must start with a letter");
  }
  for (const char c : name) {
    if (!alpha(c) && !digit(c) && c != '_') {
      return bad("letters, digits and '_' only");
    }
  }
  if (std::find(names_.begin(), names_.end(), name) != names_.end()) {
    return MatError{"variable '" + std::string(name) + "': already written"};
  }
  return Status{};
}

void MatWriter::append_variable(std::vector<std::uint8_t>& element) {
  if (options_.compress) {
    const std::vector<std::uint8_t> z = options_.deflate == Deflate::stored
                                            ? zlib_store(element.data(), element.size())
                                            : zlib_compress_fixed(element.data(), element.size());
    put_u32(bytes_, kMiCompressed);
    put_u32(bytes_, static_cast<std::uint32_t>(z.size()));
    bytes_.insert(bytes_.end(), z.begin(), z.end());  // miCOMPRESSED is not padded
  } else {
    bytes_.insert(bytes_.end(), element.begin(), element.end());
  }
}

Status MatWriter::add_matrix(std::string_view name, std::size_t rows, std::size_t cols,
                             const std::vector<double>& values) {
  Status st = check_name(name);
  if (!st.ok()) {
    return st;
  }
  if (!fits_int32(rows) || !fits_int32(cols) ||
      (cols != 0U && rows > static_cast<std::size_t>(kMaxElement / 8U / cols))) {
    return MatError{"variable '" + std::string(name) + "': too large for a MAT v5 element"};
  }
  if (values.size() != rows * cols) {
    return MatError{"variable '" + std::string(name) + "': " + std::to_string(values.size()) +
                    " values for " + std::to_string(rows) + "x" + std::to_string(cols)};
  }
  std::vector<std::uint8_t> raw(values.size() * 8U);
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &values[i], 8);
    for (unsigned k = 0; k < 8U; ++k) {
      raw[8U * i + k] = static_cast<std::uint8_t>((bits >> (8U * k)) & 0xFFU);  // little-endian
    }
  }
  std::vector<std::uint8_t> e =
      matrix_element(kMxDouble, name, rows, cols, kMiDouble, raw.data(), raw.size());
  append_variable(e);
  names_.emplace_back(name);
  return Status{};
}

Result<std::vector<std::uint8_t>> MatWriter::column_start(std::string_view name, std::uint64_t n) {
  Status st = check_name(name);
  if (!st.ok()) {
    return st.error();
  }
  if (options_.compress) {
    return MatError{"variable '" + std::string(name) + "': a column in pieces is written "
                    "uncompressed only"};
  }
  if (!fits_int32(static_cast<std::size_t>(n)) || n > kMaxElement / 8U) {
    return MatError{"variable '" + std::string(name) + "': too large for a MAT v5 element"};
  }
  std::vector<std::uint8_t> b =
      matrix_element(kMxDouble, name, static_cast<std::size_t>(n), 1, kMiDouble, nullptr, 0);
  const auto data_bytes = static_cast<std::uint32_t>(8U * n);
  set_u32(b, b.size() - 4U, data_bytes);  // the miDOUBLE tag's size: the data follow
  set_u32(b, 4U, static_cast<std::uint32_t>(b.size() - 8U) + data_bytes);
  names_.emplace_back(name);
  return b;
}

void MatWriter::encode_doubles(const double* values, std::size_t n, std::uint8_t* out) {
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &values[i], 8);
    for (unsigned k = 0; k < 8U; ++k) {
      out[8U * i + k] = static_cast<std::uint8_t>((bits >> (8U * k)) & 0xFFU);  // little-endian
    }
  }
}

Status MatWriter::add_column(std::string_view name, const std::vector<double>& values) {
  return add_matrix(name, values.size(), 1, values);
}

Status MatWriter::add_scalar(std::string_view name, double value) {
  return add_matrix(name, 1, 1, std::vector<double>{value});
}

Status MatWriter::add_string(std::string_view name, std::string_view text) {
  Status st = check_name(name);
  if (!st.ok()) {
    return st;
  }
  if (text.size() > kMaxElement / 4U) {
    return MatError{"variable '" + std::string(name) + "': too large for a MAT v5 element"};
  }
  std::vector<std::uint8_t> raw;
  raw.reserve(text.size() * 2U);
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x80U) {
      return MatError{"variable '" + std::string(name) + "': text is not 7-bit ASCII"};
    }
    raw.push_back(u);  // miUINT16 code unit, little-endian
    raw.push_back(0);
  }
  std::vector<std::uint8_t> e =
      matrix_element(kMxChar, name, text.empty() ? 0U : 1U, text.size(), kMiUint16, raw.data(),
                     raw.size());
  append_variable(e);
  names_.emplace_back(name);
  return Status{};
}

Status MatWriter::save(const std::string& path) const {
  std::FILE* fp = std::fopen(path.c_str(), "wb");
  if (fp == nullptr) {
    return MatError{path + ": cannot create: " + std::strerror(errno)};
  }
  const std::size_t wrote = std::fwrite(bytes_.data(), 1, bytes_.size(), fp);
  const int closed = std::fclose(fp);
  if (wrote != bytes_.size() || closed != 0) {
    return MatError{path + ": write failed: " + std::strerror(errno)};
  }
  return Status{};
}

}  // namespace imu::mat

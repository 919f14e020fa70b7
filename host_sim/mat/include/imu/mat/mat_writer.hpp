// MAT-file level 5 writer (little-endian, MATLAB -v6 layout; optionally every variable in a
// miCOMPRESSED zlib stream, -v7 layout: one fixed-Huffman LZ77 block, or stored blocks).
// Standard library only, host code.
//
// Writes double matrices (column-major), scalars and ASCII char row vectors, as MATLAB does:
// class double stored as miDOUBLE, char stored as miUINT16, names up to 63 characters
// ([A-Za-z][A-Za-z0-9_]*), 8-byte alignment, small-element format for names of 4 bytes or less.
//
// Cost: the file image is built in memory; add_*() is O(size of the variable), save() one write.
// Not thread-safe on one instance.
#ifndef IMU_MAT_MAT_WRITER_HPP
#define IMU_MAT_MAT_WRITER_HPP

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "imu/mat/result.hpp"

namespace imu::mat {

enum class Deflate : std::uint8_t {
  fixed_huffman,  ///< one fixed-Huffman block with LZ77 (zlib_compress_fixed)
  stored,         ///< stored blocks only (zlib_store): no size gain, simplest stream
};

struct WriterOptions {
  bool compress = false;  ///< wrap each variable in a miCOMPRESSED zlib stream
  Deflate deflate = Deflate::fixed_huffman;  ///< how, when compress is set
};

class MatWriter {
 public:
  explicit MatWriter(WriterOptions options = {});

  /// rows x cols doubles, column-major (`values.size() == rows * cols`).
  /// Fails on a bad or duplicate name, a size mismatch or a variable over 4 GiB.
  [[nodiscard]] Status add_matrix(std::string_view name, std::size_t rows, std::size_t cols,
                                  const std::vector<double>& values);
  /// An N x 1 column vector.
  [[nodiscard]] Status add_column(std::string_view name, const std::vector<double>& values);
  /// A 1 x 1 double.
  [[nodiscard]] Status add_scalar(std::string_view name, double value);
  /// A 1 x N char array; `text` must be 7-bit ASCII.
  [[nodiscard]] Status add_string(std::string_view name, std::string_view text);

  /// A long column written in pieces by the caller (uncompressed, -v6 layout): the bytes that
  /// start an `n` x 1 double column (miMATRIX tag declaring its whole size, flags, dims, name,
  /// miDOUBLE tag of 8 n bytes). The file is then: bytes() up to its 128-byte header, these
  /// bytes, the n samples as encode_doubles() gives them (8 n bytes: already 8-byte aligned,
  /// no padding), then bytes() after the header (this writer's other variables). Fails as
  /// add_matrix() on a bad or duplicate name or a column too large for a MAT v5 element.
  /// Only for a writer without compression (a miCOMPRESSED element needs its compressed size
  /// before its data).
  [[nodiscard]] Result<std::vector<std::uint8_t>> column_start(std::string_view name,
                                                               std::uint64_t n);
  /// n doubles as little-endian miDOUBLE bytes into out[0 .. 8 n).
  static void encode_doubles(const double* values, std::size_t n, std::uint8_t* out);

  /// The complete file image so far (128-byte header + variables).
  [[nodiscard]] const std::vector<std::uint8_t>& bytes() const { return bytes_; }

  /// Write bytes() to `path` (replacing it). Error message names the path and the OS error.
  [[nodiscard]] Status save(const std::string& path) const;

 private:
  [[nodiscard]] Status check_name(std::string_view name) const;
  void append_variable(std::vector<std::uint8_t>& element);

  WriterOptions options_;
  std::vector<std::uint8_t> bytes_;
  std::vector<std::string> names_;
};

}  // namespace imu::mat

#endif  // IMU_MAT_MAT_WRITER_HPP

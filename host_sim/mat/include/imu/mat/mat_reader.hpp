// MAT-file level 5 reader (MATLAB -v6/-v7, Octave, scipy.io.savemat), standard library only.
//
// Supported: little- and big-endian files ("IM"/"MI"), compressed (miCOMPRESSED, zlib) and
// uncompressed (miMATRIX) variables; numeric classes double, single, int8..int64, uint8..uint64
// (and logical) with any numeric storage type (e.g. class double stored as miUINT8 is
// converted); char arrays (miUTF8, miUINT16/miUTF16, miUINT8, miUTF32); the fields of a 1x1
// struct by dotted name (`imu.acc_z`, nested `rec.imu.acc_z`: every read_*() and ChannelStream;
// a missing field's error lists the struct's fields). Other classes (cell, object, sparse,
// function handles, struct arrays) are listed and skipped by their byte size; reading one is an
// error. Complex arrays are an error ("complex not supported"). N-d arrays are seen as
// rows = dims[0], cols = product of the other dimensions. int64/uint64 values beyond 2^53 are
// rounded to the nearest double.
//
// Errors: every failure is a MatError whose message is one line naming the file, the variable
// and the problem (not a MAT-file, v7.3/HDF5 "re-save with -v7", truncated, corrupt zlib stream,
// dimensions that do not fit the data, variable not found with the list of variables, ...).
// Claimed sizes are checked against the bytes actually present (uncompressed) or against the
// inflated size limit (compressed) before anything is allocated from them.
//
// Cost: only the requested variable is decoded. Other uncompressed variables are skipped by
// their tag; other compressed variables cost one partial inflate of at most 512 bytes (their
// name is inside the zlib stream; a longer header, e.g. a name over 63 characters, falls back to
// inflating that variable whole). Reading a compressed N-element double column costs one inflate of the
// variable (about 8 N bytes of scratch) and one copy of the selected column.
//
// Thread safety: a MatFile is immutable after construction; const member functions may run
// concurrently.
#ifndef IMU_MAT_MAT_READER_HPP
#define IMU_MAT_MAT_READER_HPP

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "imu/mat/result.hpp"

namespace imu::mat {

/// Memory budget of one MatFile: what a hostile or mistaken file may make the reader read or
/// allocate. Checked against the sizes the file declares, before anything is read or inflated;
/// exceeding one is an error naming the limit (never an allocation failure).
struct ReadLimits {
  /// open(): the largest file read into memory (bytes).
  std::size_t max_file_bytes = std::size_t{1} << 31U;  // 2 GiB
  /// The largest variable, as inflated (compressed) and as converted to double (8 bytes per
  /// element): 256 MiB, i.e. 2^25 = 33.5 million samples of one channel.
  std::size_t max_variable_bytes = std::size_t{1} << 28U;
  /// ChannelStream: the largest variable it accepts, as declared inflated (2 GiB: 2^28 = 268
  /// million double samples, 186 h at 400 Hz). Not a memory bound (a stream holds ~0.3 MB at
  /// any length) but a cap on claims, so that a small element declaring gigabytes is refused
  /// before any time is spent on it.
  std::uint64_t max_stream_variable_bytes = std::uint64_t{1} << 31U;
};

/// What list_variables() reports for each top-level variable, in file order.
struct VariableInfo {
  std::string name;
  std::string class_name;  ///< "double", "single", "int8".."uint64", "char", "logical", "cell", ...
  std::uint64_t rows = 0;  ///< dims[0]
  std::uint64_t cols = 0;  ///< product of dims[1..]
  std::uint32_t n_dims = 0;
  bool complex = false;
  bool compressed = false;        ///< stored as miCOMPRESSED
  std::uint64_t file_offset = 0;  ///< byte offset of the variable's tag in the file
  std::uint64_t file_bytes = 0;   ///< bytes it takes in the file, tag included
};

namespace detail {
struct Element;  // a top-level data element (implementation detail)
struct Matrix;   // a parsed miMATRIX (implementation detail)
}  // namespace detail

/// A MAT-file image in memory: owned (open()) or borrowed (from_memory()).
class MatFile {
 public:
  /// Read the whole file at `path` into memory and check its 128-byte header. Only a regular
  /// file is opened (a directory, FIFO, socket or device is refused before open(), so a FIFO
  /// cannot block and /dev/zero cannot be read forever); its size is limits.max_file_bytes at
  /// most. POSIX (stat). Cost: one read of the file.
  [[nodiscard]] static Result<MatFile> open(const std::string& path, ReadLimits limits = {});

  /// Use `size` bytes at `data` as a MAT-file image. No copy: the caller keeps the bytes alive
  /// (and unchanged) for the life of the MatFile. `display_name` prefixes error messages.
  [[nodiscard]] static Result<MatFile> from_memory(std::string display_name,
                                                   const std::uint8_t* data, std::size_t size,
                                                   ReadLimits limits = {});

  MatFile(MatFile&& other) noexcept;
  MatFile& operator=(MatFile&& other) noexcept;
  MatFile(const MatFile&) = delete;
  MatFile& operator=(const MatFile&) = delete;
  ~MatFile() = default;

  /// Every top-level variable with its class and size. Fails on the first corrupt element.
  [[nodiscard]] Result<std::vector<VariableInfo>> list_variables() const;

  /// Column `column` of a numeric matrix, converted to double. A vector (rows == 1 or
  /// cols == 1, i.e. row or column vector, or a scalar) is returned whole for column 0.
  [[nodiscard]] Result<std::vector<double>> read_column(std::string_view name,
                                                        std::size_t column = 0) const;

  /// Same, into a caller-owned vector (its capacity is reused). `out` is cleared on error.
  [[nodiscard]] Status read_column_into(std::string_view name, std::size_t column,
                                        std::vector<double>& out) const;

  /// The value of a numeric variable with exactly one element.
  [[nodiscard]] Result<double> read_scalar(std::string_view name) const;

  /// A char array as UTF-8. A multi-row char matrix gives its rows joined by '\n'.
  [[nodiscard]] Result<std::string> read_string(std::string_view name) const;

  [[nodiscard]] const std::string& display_name() const { return name_; }
  [[nodiscard]] bool big_endian() const { return swap_; }

 private:
  MatFile() = default;
  [[nodiscard]] Status find(std::string_view name, detail::Element& elem) const;
  [[nodiscard]] Status load(std::string_view name, const detail::Element& elem,
                            std::vector<std::uint8_t>& scratch, detail::Matrix& m) const;
  /// find() then load(): the common start of every read_*(); m may point into scratch.
  [[nodiscard]] Status find_and_load(std::string_view name, std::vector<std::uint8_t>& scratch,
                                     detail::Matrix& m) const;

  std::string name_;
  std::vector<std::uint8_t> owned_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  bool swap_ = false;  ///< file byte order differs from little-endian
  ReadLimits limits_{};
};

/// One numeric column of a MAT-file variable read from the file in pieces, inflated as it is
/// read: constant memory whatever the length (a 64 KiB input buffer, the inflater's 32 KiB
/// window and 64 KiB chunk, a 64 KiB conversion buffer: about 0.3 MB), the file never read
/// whole. Same classes, conversions, checks and error messages as MatFile::read_column, except
/// the budget: max_stream_variable_bytes instead of max_variable_bytes. POSIX (stat, pread).
///
/// A compressed variable's integrity (Adler-32, no data beyond the declared size) is known only
/// at its end: read() returns the error then, after the samples before it. A consumer must not
/// report results before read() returned 0.
class ChannelStream {
 public:
  /// Find variable `name` in the file at `path` (the other variables' headers are peeked, as
  /// MatFile::find does), check its header and declared sizes, and position at the first sample
  /// of column `column` (a vector is column 0). Cost: one pass over the elements' tags and the
  /// first kilobytes of each compressed variable before it.
  [[nodiscard]] static Result<ChannelStream> open(const std::string& path, std::string_view name,
                                                  std::size_t column = 0, ReadLimits limits = {});
  ChannelStream(ChannelStream&& other) noexcept;
  ChannelStream& operator=(ChannelStream&& other) noexcept;
  ChannelStream(const ChannelStream&) = delete;
  ChannelStream& operator=(const ChannelStream&) = delete;
  ~ChannelStream();

  /// Up to `n` samples, converted to double, into `out` (fewer only at the end). Returns the
  /// count, 0 at the end once the variable was checked whole, or the first error (corrupt or
  /// truncated stream, read error). Cost: O(n) plus the inflate of the bytes behind them.
  [[nodiscard]] Result<std::size_t> read(double* out, std::size_t n);
  /// Samples in the column (from the dimensions).
  [[nodiscard]] std::uint64_t size() const;
  /// The variable's name, class and dimensions.
  [[nodiscard]] const VariableInfo& info() const;

 private:
  struct Impl;
  explicit ChannelStream(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// list_variables(path) without reading the file whole: each variable's tag and header only.
[[nodiscard]] Result<std::vector<VariableInfo>> scan_variables(const std::string& path,
                                                               ReadLimits limits = {});
/// read_scalar(path, name) through a ChannelStream (the file is not read whole).
[[nodiscard]] Result<double> stream_scalar(const std::string& path, std::string_view name,
                                           ReadLimits limits = {});

/// Convenience wrappers: open `path` and do one read.
[[nodiscard]] Result<std::vector<VariableInfo>> list_variables(const std::string& path);
[[nodiscard]] Result<std::vector<double>> read_column(const std::string& path,
                                                      std::string_view name,
                                                      std::size_t column = 0);
[[nodiscard]] Result<double> read_scalar(const std::string& path, std::string_view name);
[[nodiscard]] Result<std::string> read_string(const std::string& path, std::string_view name);

}  // namespace imu::mat

#endif  // IMU_MAT_MAT_READER_HPP

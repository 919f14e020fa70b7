// Outputs written whole or not at all: the bytes go to a temporary file next to `path` (same
// folder, so the rename cannot cross file systems), are flushed and synced, and the file is
// renamed over `path` only when all of it was written. On any failure (full disk, file size
// limit, I/O error) the temporary file is removed and `path` is left as it was. POSIX.
#ifndef IMU_CLI_FILE_OUT_HPP
#define IMU_CLI_FILE_OUT_HPP

#include <cstddef>
#include <string>

namespace imu::cli {

/// The same, written in pieces (an output too long to hold in memory): open(), write() as
/// often as needed, commit(). Until commit() succeeds the bytes are in the temporary file;
/// destroying the writer before (or after a failure) removes it and leaves `path` as it was.
class AtomicFileWriter {
 public:
  AtomicFileWriter() = default;
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  AtomicFileWriter(AtomicFileWriter&&) = delete;
  AtomicFileWriter& operator=(AtomicFileWriter&&) = delete;
  ~AtomicFileWriter();
  /// Create the temporary file next to `path`. False with err as write_file_atomic's.
  [[nodiscard]] bool open(const std::string& path, std::string& err);
  /// Append `size` bytes. False (and the temporary file removed) on a write error.
  [[nodiscard]] bool write(const void* data, std::size_t size, std::string& err);
  /// Flush, sync and rename over `path`. False (temporary file removed) on failure.
  [[nodiscard]] bool commit(std::string& err);

 private:
  void abort();
  std::string path_;
  std::string tmp_;
  int fd_ = -1;
};

/// Write `size` bytes at `data` as the file `path`. False with a one-line err naming the path
/// and the OS error. Cost: one write, one fsync, one rename.
[[nodiscard]] bool write_file_atomic(const std::string& path, const void* data, std::size_t size,
                                     std::string& err);

/// Same for a text.
[[nodiscard]] inline bool write_file_atomic(const std::string& path, const std::string& text,
                                            std::string& err) {
  return write_file_atomic(path, text.data(), text.size(), err);
}

/// Create the directory `path` and its missing parents (mode 0755, like mkdir -p). False with a
/// one-line err if a component cannot be created or `path` is not a directory.
[[nodiscard]] bool make_dirs(const std::string& path, std::string& err);

/// A gnuplot string literal: single-quoted, a quote doubled. For the paths in .gp scripts,
/// which name their files absolutely so that they run from any directory.
[[nodiscard]] std::string gnuplot_str(const std::string& s);

/// gnuplot is on the PATH.
[[nodiscard]] bool gnuplot_available();
/// Render DIR/BASE.gp into DIR/BASE.svg (1000 x svg_height, dynamic) and DIR/BASE.png
/// (1100 x 800; pngcairo if this gnuplot has it), gnuplot's messages in DIR/BASE.gnuplot.log
/// (removed on success). False if gnuplot failed on either. Runs gnuplot twice (std::system).
[[nodiscard]] bool gnuplot_render(const std::string& dir, const std::string& base, int svg_height);

}  // namespace imu::cli

#endif  // IMU_CLI_FILE_OUT_HPP

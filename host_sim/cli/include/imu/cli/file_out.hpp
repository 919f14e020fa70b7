// The one output layer of every command: files written whole or not at all, names from user data
// made safe, paths checked before the work.
//
// A regular file (or a path that does not exist yet) is written atomically: the bytes go to a
// temporary file next to it (same folder, so the rename cannot cross file systems), are flushed
// and synced, and the file is renamed over `path` only when all of it was written. On any
// failure (full disk, file size limit, I/O error) the temporary file is removed and `path` is
// left as it was; the temporary file is also removed when the process is stopped by SIGINT,
// SIGTERM, SIGHUP or SIGPIPE (install_cleanup_handlers). A symbolic link is followed: the file
// it points to is replaced, the link stays. A character device or a FIFO (/dev/null, /dev/stdout,
// a pipe) is written through, never replaced. A directory, a block device or a socket is refused
// with the reason. "-" is standard output. POSIX.
#ifndef IMU_CLI_FILE_OUT_HPP
#define IMU_CLI_FILE_OUT_HPP

#include <cstddef>
#include <string>
#include <vector>

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
  std::string target_;  // the regular file renamed over (`path_`, a link resolved)
  int fd_ = -1;
  int slot_ = -1;         // the signal handler's table slot of tmp_
  bool through_ = false;  // fd_ is the target itself (device, FIFO, stdout): no rename
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

/// A gnuplot string literal: single-quoted, a quote doubled, and every control character
/// (a newline would end the string and start a command) replaced by '?'. Paths in .gp scripts
/// come from check_output_dir, which refuses control characters, so they are never altered.
[[nodiscard]] std::string gnuplot_str(const std::string& s);

/// A name from user data (a channel, a column header, a variable) as one safe file-name
/// component: letters, digits, '.', '_' and '-' kept, every other byte '_', no leading '.'
/// (so never "." or ".."), at most 64 bytes, "_" if nothing is left. Never a path.
[[nodiscard]] std::string safe_component(const std::string& name);
/// safe_component of each name, made distinct: a name whose component another already took
/// ("a-b" and "a:b" both give "a-b") gets "-2", "-3", ... in the order given.
[[nodiscard]] std::vector<std::string> safe_components(const std::vector<std::string>& names);

/// Text from a file or the command line made safe for a terminal or a log line: control
/// characters (C0, DEL, C1) and bytes that are not UTF-8 are written as \xNN, so an escape
/// sequence in a file's bytes is shown, never executed by the terminal.
[[nodiscard]] std::string term_safe(const std::string& s);
/// term_safe for a multi-line text (a report): newlines and tabs kept, the rest as term_safe.
[[nodiscard]] std::string term_safe_text(const std::string& s);

/// Check an output file's path before any work: not empty, no control characters, its folder
/// exists and is a folder, and the path is not a folder, a block device or a socket. "-"
/// (standard output) passes. False with a one-line reason.
[[nodiscard]] bool check_output_path(const std::string& path, std::string& err);
/// Check (and create, like mkdir -p) an output folder before any work: not empty, no control
/// characters in its absolute form (the .gp scripts name it), a folder. False with the reason.
[[nodiscard]] bool check_output_dir(const std::string& path, std::string& err);

/// Remove the atomic writers' temporary files when SIGINT, SIGTERM, SIGHUP or SIGPIPE stops
/// the process (the signal's default action then runs). Call once at the start of main.
/// Async-signal-safe: the handler only unlinks paths registered in a fixed table.
void install_cleanup_handlers();

/// gnuplot is on the PATH.
[[nodiscard]] bool gnuplot_available();
/// Runs gnuplot on the script at `script` (an absolute path, quoted for the shell), its messages
/// discarded. False if gnuplot failed.
[[nodiscard]] bool gnuplot_run(const std::string& script);
/// Render DIR/BASE.gp into DIR/BASE.svg (1000 x svg_height, dynamic) and DIR/BASE.png
/// (1100 x 800; pngcairo if this gnuplot has it), gnuplot's messages in DIR/BASE.gnuplot.log
/// (removed on success). False if gnuplot failed on either. Runs gnuplot twice (std::system).
[[nodiscard]] bool gnuplot_render(const std::string& dir, const std::string& base, int svg_height);

}  // namespace imu::cli

#endif  // IMU_CLI_FILE_OUT_HPP

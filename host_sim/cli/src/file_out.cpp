// Outputs written whole or not at all (see imu/cli/file_out.hpp).
#include "imu/cli/file_out.hpp"

#include "imu/cli/json.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace imu::cli {
namespace {

// write() until done; false with errno set on failure (EINTR retried).
bool write_all(int fd, const unsigned char* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) {
      continue;
    }
    if (w <= 0) {
      if (w == 0) {
        errno = EIO;
      }
      return false;
    }
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

// The temporary files of the writers open now, for the signal handler: a fixed table of
// fixed-size paths (no allocation or lock in the handler). A slot is claimed with a CAS on
// `used`; the handler reads only slots whose `ready` is set.
constexpr std::size_t kTmpSlots = 64;
constexpr std::size_t kTmpPathMax = 4096;
struct TmpSlot {
  std::atomic<bool> used{false};
  std::atomic<bool> ready{false};
  std::array<char, kTmpPathMax> path{};
};
std::array<TmpSlot, kTmpSlots> g_tmp;

// The slot now holding `path`, or -1 (table full or path too long: the file is then only
// removed by the writer itself, as before the handler existed).
int register_tmp(const std::string& path) {
  if (path.size() + 1 > kTmpPathMax) {
    return -1;
  }
  for (std::size_t i = 0; i < kTmpSlots; ++i) {
    bool expected = false;
    if (g_tmp[i].used.compare_exchange_strong(expected, true)) {
      std::memcpy(g_tmp[i].path.data(), path.c_str(), path.size() + 1);
      g_tmp[i].ready.store(true);
      return static_cast<int>(i);
    }
  }
  return -1;
}

void unregister_tmp(int slot) {
  if (slot >= 0) {
    g_tmp[static_cast<std::size_t>(slot)].ready.store(false);
    g_tmp[static_cast<std::size_t>(slot)].used.store(false);
  }
}

extern "C" void on_fatal_signal(int sig) {
  for (TmpSlot& t : g_tmp) {
    if (t.ready.load()) {
      (void)::unlink(t.path.data());
    }
  }
  (void)std::signal(sig, SIG_DFL);
  (void)std::raise(sig);
}

// What a target path is now.
enum class Target { kMissing, kRegular, kThrough, kRefused };

// Classify `path` (a symbolic link followed: `resolved` is the file written). kRefused sets err.
Target classify(const std::string& path, std::string& resolved, std::string& err) {
  resolved = path;
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    return Target::kMissing;
  }
  if (S_ISLNK(st.st_mode)) {
    // Followed: a regular file's real path is renamed over (the link stays); a device or FIFO
    // behind it (/dev/stdout -> /proc/self/fd/1 -> a pipe) is opened through the link itself.
    if (::stat(path.c_str(), &st) != 0) {
      err = "cannot write '" + term_safe(path) + "': a symbolic link to a missing file";
      return Target::kRefused;
    }
    if (S_ISREG(st.st_mode)) {
      char* real = ::realpath(path.c_str(), nullptr);
      if (real == nullptr) {
        err = "cannot write '" + term_safe(path) + "': " + std::strerror(errno);
        return Target::kRefused;
      }
      resolved = real;
      std::free(real);  // NOLINT(cppcoreguidelines-no-malloc): realpath's buffer
    }
  }
  if (S_ISREG(st.st_mode)) {
    return Target::kRegular;
  }
  if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
    return Target::kThrough;
  }
  err = "cannot write '" + term_safe(path) + "': it is " +
        (S_ISDIR(st.st_mode)   ? "a directory"
         : S_ISBLK(st.st_mode) ? "a block device (refused: it would be overwritten)"
                               : "not a regular file, a character device or a FIFO");
  return Target::kRefused;
}

bool has_control(const std::string& s) {
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20U || u == 0x7fU) {
      return true;
    }
  }
  return false;
}

}  // namespace

AtomicFileWriter::~AtomicFileWriter() { abort(); }

void AtomicFileWriter::abort() {
  if (fd_ >= 0 && fd_ != STDOUT_FILENO) {
    (void)::close(fd_);
  }
  fd_ = -1;
  through_ = false;
  if (!tmp_.empty()) {
    (void)std::remove(tmp_.c_str());
    tmp_.clear();
  }
  unregister_tmp(slot_);
  slot_ = -1;
}

bool AtomicFileWriter::open(const std::string& path, std::string& err) {
  abort();
  path_ = path;
  if (path == "-") {
    fd_ = STDOUT_FILENO;
    through_ = true;
    return true;
  }
  if (path.empty() || has_control(path)) {
    err = "cannot write '" + term_safe(path) + "': " +
          (path.empty() ? "empty path" : "control characters in the path");
    return false;
  }
  std::string resolved;
  const Target t = classify(path, resolved, err);
  if (t == Target::kRefused) {
    return false;
  }
  if (t == Target::kThrough) {
    fd_ = ::open(resolved.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    if (fd_ < 0) {
      err = "cannot write '" + term_safe(path) + "': " + std::strerror(errno);
      return false;
    }
    through_ = true;
    return true;
  }
  std::string tmpl = resolved + ".tmp-XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  fd_ = mkstemp(name.data());
  if (fd_ < 0) {
    err = "cannot write '" + term_safe(path) + "': " + std::strerror(errno);
    return false;
  }
  tmp_ = name.data();
  target_ = resolved;
  slot_ = register_tmp(tmp_);
  return true;
}

bool AtomicFileWriter::write(const void* data, std::size_t size, std::string& err) {
  if (fd_ < 0 || !write_all(fd_, static_cast<const unsigned char*>(data), size)) {
    const int e = fd_ < 0 ? EBADF : errno;
    abort();
    err = "cannot write '" + term_safe(path_) + "': " + std::strerror(e) + " (nothing written)";
    return false;
  }
  return true;
}

namespace {

// Single quotes for the shell.
std::string shell_str(const std::string& s) {
  std::string q = "'";
  for (const char ch : s) {
    q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  }
  return q + "'";
}

}  // namespace

bool gnuplot_available() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

bool gnuplot_run(const std::string& script) {
  const std::string cmd = "gnuplot " + shell_str(script) + " 2>/dev/null";
  return std::system(cmd.c_str()) == 0;
}

bool gnuplot_render(const std::string& dir, const std::string& base, int svg_height) {
  static const bool cairo = std::system("gnuplot -e 'set terminal pngcairo' >/dev/null 2>&1") == 0;
  const std::string svg = "set terminal svg size 1000," + std::to_string(svg_height) +
                          " dynamic; set output '" + base + ".svg'";
  const std::string png = std::string("set terminal ") +
                          (cairo ? "pngcairo size 1100,800" : "png size 1100,800") +
                          "; set output '" + base + ".png'";
  const std::string log = base + ".gnuplot.log";
  const std::string cmd = "cd " + shell_str(dir) + " && gnuplot -e " + shell_str(svg) + " " +
                          shell_str(base + ".gp") + " >/dev/null 2>" + shell_str(log) +
                          " && gnuplot -e " + shell_str(png) + " " + shell_str(base + ".gp") +
                          " >/dev/null 2>>" + shell_str(log);
  if (std::system(cmd.c_str()) != 0) {
    return false;
  }
  (void)std::remove((dir + "/" + log).c_str());
  return true;
}

std::string gnuplot_str(const std::string& s) {
  std::string o = "'";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\'') {
      o += "''";
    } else if (u < 0x20U || u == 0x7fU) {
      o += '?';
    } else {
      o += c;
    }
  }
  return o + "'";
}

std::string safe_component(const std::string& name) {
  constexpr std::size_t kMaxLen = 64;
  std::string o;
  for (const char c : name) {
    if (o.size() == kMaxLen) {
      break;
    }
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '_' || c == '-' || (c == '.' && !o.empty());
    o += keep ? c : '_';
  }
  return o.empty() ? std::string("_") : o;
}

std::vector<std::string> safe_components(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  out.reserve(names.size());
  const auto taken = [&out](const std::string& c) {
    for (const std::string& o : out) {
      if (o == c) {
        return true;
      }
    }
    return false;
  };
  for (const std::string& n : names) {
    const std::string base = safe_component(n);
    std::string c = base;
    for (std::size_t k = 2; taken(c); ++k) {
      c = base + "-" + std::to_string(k);
    }
    out.push_back(c);
  }
  return out;
}

std::string term_safe_text(const std::string& s) {
  std::string o;
  std::size_t from = 0;
  for (std::size_t i = 0; i <= s.size(); ++i) {
    if (i == s.size() || s[i] == '\n' || s[i] == '\t') {
      o += term_safe(s.substr(from, i - from));
      if (i < s.size()) {
        o += s[i];
      }
      from = i + 1;
    }
  }
  return o;
}

std::string term_safe(const std::string& s) {
  std::string o;
  const auto hex = [&o](unsigned char u) {
    char buf[8];
    (void)std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned>(u));
    o += buf;
  };
  const std::size_t n = s.size();
  for (std::size_t i = 0; i < n;) {
    const auto u = static_cast<unsigned char>(s[i]);
    if (u < 0x80U) {
      if (u < 0x20U || u == 0x7fU) {
        hex(u);
      } else {
        o += static_cast<char>(u);
      }
      ++i;
      continue;
    }
    // A valid UTF-8 sequence is kept unless it is a C1 control (U+0080..U+009F: C2 80..C2 9F).
    const std::size_t len = utf8_sequence(s, i);
    const bool c1 = len == 2 && u == 0xc2U && static_cast<unsigned char>(s[i + 1]) < 0xa0U;
    if (len == 0 || c1) {
      hex(u);
      ++i;
      continue;
    }
    o.append(s, i, len);
    i += len;
  }
  return o;
}

bool check_output_path(const std::string& path, std::string& err) {
  if (path == "-") {
    return true;
  }
  if (path.empty() || has_control(path)) {
    err = "cannot write '" + term_safe(path) + "': " +
          (path.empty() ? "empty path" : "control characters in the path");
    return false;
  }
  std::string resolved;
  if (classify(path, resolved, err) == Target::kRefused) {
    return false;
  }
  const std::size_t slash = resolved.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : resolved.substr(0, slash);
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    err = "cannot write '" + term_safe(path) + "': its folder '" + term_safe(dir) +
          "' is missing";
    return false;
  }
  if (::access(dir.c_str(), W_OK) != 0 && ::access(resolved.c_str(), W_OK) != 0) {
    err = "cannot write '" + term_safe(path) + "': " + std::strerror(errno);
    return false;
  }
  return true;
}

bool check_output_dir(const std::string& path, std::string& err) {
  if (path.empty()) {
    err = "empty output folder";
    return false;
  }
  char* cwd = ::getcwd(nullptr, 0);
  const std::string abs = path[0] == '/' || cwd == nullptr ? path : std::string(cwd) + "/" + path;
  std::free(cwd);  // NOLINT(cppcoreguidelines-no-malloc): getcwd's buffer
  if (has_control(abs)) {
    err = "output folder '" + term_safe(abs) + "': control characters in the path";
    return false;
  }
  return make_dirs(path, err);
}

void install_cleanup_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_fatal_signal;
  sigemptyset(&sa.sa_mask);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) {
    struct sigaction old {};
    // A signal the caller's parent ignores (nohup, a shell's SIGPIPE policy) stays ignored.
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) {
      continue;
    }
    (void)sigaction(sig, &sa, nullptr);
  }
}

bool make_dirs(const std::string& path, std::string& err) {
  if (path.empty()) {
    return true;
  }
  std::string cur;
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = path.find('/', pos + 1);
    cur = path.substr(0, pos);
    if (cur.empty()) {
      continue;
    }
    if (::mkdir(cur.c_str(), 0755) != 0 && errno != EEXIST) {
      err = "cannot create directory '" + term_safe(cur) + "': " + std::strerror(errno);
      return false;
    }
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    err = "'" + term_safe(path) + "' is not a directory";
    return false;
  }
  return true;
}

bool AtomicFileWriter::commit(std::string& err) {
  if (fd_ < 0) {
    err = "cannot write '" + term_safe(path_) + "': " + std::strerror(EBADF) + " (nothing written)";
    return false;
  }
  if (through_) {
    // Written through to a device, FIFO or stdout: nothing to rename; a close error is a
    // write error (stdout stays open for the process).
    const bool closed = fd_ == STDOUT_FILENO || ::close(fd_) == 0;
    const int e = errno;
    fd_ = -1;
    through_ = false;
    if (!closed) {
      err = "cannot write '" + term_safe(path_) + "': " + std::strerror(e);
      return false;
    }
    return true;
  }
  // mkstemp creates 0600; outputs are ordinary files (0644 less the umask).
  const mode_t mask = umask(0);
  umask(mask);
  const bool ok = fchmod(fd_, 0666 & ~mask) == 0 && fsync(fd_) == 0;
  const int sync_errno = errno;
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  if (!ok || !closed || std::rename(tmp_.c_str(), target_.c_str()) != 0) {
    const int e = !ok ? sync_errno : errno;
    abort();
    err = "cannot write '" + term_safe(path_) + "': " + std::strerror(e) + " (nothing written)";
    return false;
  }
  tmp_.clear();
  unregister_tmp(slot_);
  slot_ = -1;
  return true;
}

bool write_file_atomic(const std::string& path, const void* data, std::size_t size,
                       std::string& err) {
  AtomicFileWriter w;
  return w.open(path, err) && w.write(data, size, err) && w.commit(err);
}

}  // namespace imu::cli

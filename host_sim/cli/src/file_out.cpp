// Outputs written whole or not at all (see imu/cli/file_out.hpp).
#include "imu/cli/file_out.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
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

}  // namespace

AtomicFileWriter::~AtomicFileWriter() { abort(); }

void AtomicFileWriter::abort() {
  if (fd_ >= 0) {
    (void)::close(fd_);
    fd_ = -1;
  }
  if (!tmp_.empty()) {
    (void)std::remove(tmp_.c_str());
    tmp_.clear();
  }
}

bool AtomicFileWriter::open(const std::string& path, std::string& err) {
  abort();
  path_ = path;
  std::string tmpl = path + ".tmp-XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  fd_ = mkstemp(name.data());
  if (fd_ < 0) {
    err = "cannot write '" + path + "': " + std::strerror(errno);
    return false;
  }
  tmp_ = name.data();
  return true;
}

bool AtomicFileWriter::write(const void* data, std::size_t size, std::string& err) {
  if (fd_ < 0 || !write_all(fd_, static_cast<const unsigned char*>(data), size)) {
    const int e = fd_ < 0 ? EBADF : errno;
    abort();
    err = "cannot write '" + path_ + "': " + std::strerror(e) + " (nothing written)";
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
    o += c == '\'' ? std::string("''") : std::string(1, c);
  }
  return o + "'";
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
      err = "cannot create directory '" + cur + "': " + std::strerror(errno);
      return false;
    }
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    err = "'" + path + "' is not a directory";
    return false;
  }
  return true;
}

bool AtomicFileWriter::commit(std::string& err) {
  if (fd_ < 0) {
    err = "cannot write '" + path_ + "': " + std::strerror(EBADF) + " (nothing written)";
    return false;
  }
  // mkstemp creates 0600; outputs are ordinary files (0644 less the umask).
  const mode_t mask = umask(0);
  umask(mask);
  const bool ok = fchmod(fd_, 0666 & ~mask) == 0 && fsync(fd_) == 0;
  const int sync_errno = errno;
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  if (!ok || !closed || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const int e = !ok ? sync_errno : errno;
    abort();
    err = "cannot write '" + path_ + "': " + std::strerror(e) + " (nothing written)";
    return false;
  }
  tmp_.clear();
  return true;
}

bool write_file_atomic(const std::string& path, const void* data, std::size_t size,
                       std::string& err) {
  AtomicFileWriter w;
  return w.open(path, err) && w.write(data, size, err) && w.commit(err);
}

}  // namespace imu::cli

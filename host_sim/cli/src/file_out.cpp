// Outputs written whole or not at all (see imu/cli/file_out.hpp).
#include "imu/cli/file_out.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
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

bool write_file_atomic(const std::string& path, const void* data, std::size_t size,
                       std::string& err) {
  std::string tmpl = path + ".tmp-XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = mkstemp(name.data());
  if (fd < 0) {
    err = "cannot write '" + path + "': " + std::strerror(errno);
    return false;
  }
  const bool wrote = write_all(fd, static_cast<const unsigned char*>(data), size);
  const int write_errno = errno;
  // mkstemp creates 0600; outputs are ordinary files (0644 less the umask).
  const mode_t mask = umask(0);
  umask(mask);
  const bool ok = wrote && fchmod(fd, 0666 & ~mask) == 0 && fsync(fd) == 0;
  const int sync_errno = errno;
  const bool closed = ::close(fd) == 0;
  if (!ok || !closed || std::rename(name.data(), path.c_str()) != 0) {
    const int e = !wrote ? write_errno : (!ok ? sync_errno : errno);
    (void)std::remove(name.data());
    err = "cannot write '" + path + "': " + std::strerror(e) + " (nothing written)";
    return false;
  }
  return true;
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

}  // namespace imu::cli

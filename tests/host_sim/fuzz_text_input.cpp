// libFuzzer target for the text reader (CSV/TSV/blank-separated with a header and a time
// column): the input is the file's bytes, written to a private temporary file and read the
// ways imu-sim reads text: the whole table and one column on its grid, and the streamed columns
// with and without --fs. Built only with IMU_FUZZ=ON and clang (preset "fuzz"). Any crash,
// sanitizer report or allocation over -rss_limit_mb / -malloc_limit_mb is a failure; refusals
// with a message are the expected outcome for most inputs.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/cli/text_input.hpp"

namespace {

const std::string& scratch() {
  static const std::string path = "/tmp/fuzz_text_input." + std::to_string(getpid()) + ".csv";
  return path;
}

void stream_all(const std::string& path, const std::vector<std::string>& names, double fs_hz) {
  imu::cli::TextColumnStream st;
  std::string err;
  if (!st.open(path, names, fs_hz, err)) {
    return;
  }
  std::vector<double> buf(256 * st.columns());
  std::size_t total = 0;
  for (;;) {
    std::size_t got = 0;
    if (!st.read(buf.data(), 256, got, err) || got == 0 || (total += got) > (std::size_t{1} << 24U)) {
      return;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = scratch();
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) {
      return 0;
    }
    if (size > 0) {
      (void)std::fwrite(data, 1, size, f);
    }
    std::fclose(f);
  }
  (void)imu::cli::looks_like_text(path);
  imu::cli::TextTable table;
  std::string err;
  if (imu::cli::read_text_table(path, table, err)) {
    std::vector<std::string> names;
    (void)imu::cli::text_channels(table.names, "all", names, err);
    for (const auto& n : names) {
      imu::cli::TextChannel ch;
      (void)imu::cli::text_channel(table, n, 0.0, ch, err);
      (void)imu::cli::text_channel(table, n, 100.0, ch, err);
    }
    if (!names.empty()) {
      stream_all(path, names, 0.0);
      stream_all(path, {names.front()}, 100.0);
    }
  }
  return 0;
}

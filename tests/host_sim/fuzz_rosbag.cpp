// libFuzzer target for the ROS bag reader and its LZ4 decoder: the input is the file's bytes,
// written to a private temporary file and read the ways imu-sim reads a bag: its rows (the
// only sensor_msgs/Imu topic, and /imu named), and two columns on their grid from the stamps;
// the same bytes are also decoded as LZ4 frames. Built only with IMU_FUZZ=ON and clang
// (preset "fuzz"). Any crash, sanitizer report or allocation over -rss_limit_mb /
// -malloc_limit_mb is a failure; refusals with a message are the expected outcome for most
// inputs. Seeds: small bags of python3-rosbag, uncompressed and LZ4 (fuzz_seeds/rosbag).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/cli/lz4.hpp"
#include "imu/cli/rosbag.hpp"
#include "imu/cli/text_input.hpp"

namespace {

const std::string& scratch() {
  static const std::string path = "/tmp/fuzz_rosbag." + std::to_string(getpid()) + ".bag";
  return path;
}

void rows_all(const std::string& path, const std::string& topic) {
  imu::cli::BagRows rows;
  std::string err;
  if (!rows.open(path, topic, err)) {
    return;
  }
  rows.exact_integers(0);
  std::vector<double> row;
  for (std::size_t n = 0; n < (std::size_t{1} << 20U) && rows.next(row, err); ++n) {
  }
}

void stream_all(const std::string& path) {
  imu::cli::TextColumnStream st;
  std::string err;
  if (!st.open(path, std::vector<std::string>{"acc_z", "gyro_x"}, 0.0, err)) {
    return;
  }
  std::vector<double> buf(256 * st.columns());
  std::size_t total = 0;
  for (;;) {
    std::size_t got = 0;
    if (!st.read(buf.data(), 256, got, err) || got == 0 ||
        (total += got) > (std::size_t{1} << 24U)) {
      return;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> out;
  (void)imu::cli::lz4_decode_frames(data, size, std::size_t{1} << 24U, out);
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
  if (!imu::cli::looks_like_bag(path)) {
    return 0;
  }
  rows_all(path, "");
  rows_all(path, "/imu");
  stream_all(path);
  return 0;
}

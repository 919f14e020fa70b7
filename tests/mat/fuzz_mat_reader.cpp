// libFuzzer target for the MAT reader and the inflater: the input is a file image.
// Built only with IMU_FUZZ=ON and clang (preset "fuzz"). Any crash, sanitizer report, leak or
// allocation over -rss_limit_mb / -malloc_limit_mb is a failure; errors returned as MatError are
// the expected outcome for almost every input.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "imu/mat/mat_reader.hpp"
#include "imu/mat/zlib.hpp"

namespace {

// The input handed to InflateStream in pieces of 1..64 bytes (sizes from the data itself).
class PieceSource final : public imu::mat::ByteSource {
 public:
  PieceSource(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  std::size_t read(std::uint8_t* dst, std::size_t want) override {
    std::size_t k = n_ - pos_;
    k = k < want ? k : want;
    const std::size_t step = 1U + (pos_ < n_ ? d_[pos_] % 64U : 0U);
    k = k < step ? k : step;
    if (k > 0U) {
      std::memcpy(dst, d_ + pos_, k);
    }
    pos_ += k;
    return k;
  }

 private:
  const std::uint8_t* d_;
  std::size_t n_;
  std::size_t pos_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The inflater on its own, bounded like the reader bounds it.
  std::vector<std::uint8_t> out;
  const auto whole = imu::mat::inflate_zlib(data, size, imu::mat::max_inflated_size(size),
                                            imu::mat::InflateMode::whole, out);

  // Differential: the streaming inflater fed in pieces gives the same bytes and the same
  // verdict (a mismatch aborts).
  {
    PieceSource src(data, size);
    imu::mat::InflateStream s(src, true);
    std::vector<std::uint8_t> streamed;
    std::uint8_t piece[777];
    for (std::size_t k = s.read(piece, sizeof piece); k > 0U; k = s.read(piece, sizeof piece)) {
      streamed.insert(streamed.end(), piece, piece + k);
    }
    const bool ok_whole = whole.status == imu::mat::InflateStatus::ok;
    const bool ok_stream = s.status() == imu::mat::InflateStatus::ok;
    if (ok_whole != ok_stream || (ok_whole && streamed != out)) {
      std::abort();
    }
  }

  // Differential round trip: our fixed-Huffman compressor, then our inflater, must give the
  // input back (a mismatch aborts, which libFuzzer reports as a crash).
  const std::size_t n_round = size < 4096U ? size : 4096U;
  const std::vector<std::uint8_t> z = imu::mat::zlib_compress_fixed(data, n_round, 8U);
  const auto r =
      imu::mat::inflate_zlib(z.data(), z.size(), n_round, imu::mat::InflateMode::whole, out);
  if (r.status != imu::mat::InflateStatus::ok || out.size() != n_round ||
      (n_round > 0U && std::memcmp(out.data(), data, n_round) != 0)) {
    std::abort();
  }

  auto file = imu::mat::MatFile::from_memory("fuzz.mat", data, size);
  if (!file.ok()) {
    return 0;
  }
  const imu::mat::MatFile& f = file.value();
  const auto list = f.list_variables();
  static_cast<void>(f.read_column("not_there"));
  if (!list.ok()) {
    return 0;
  }
  std::size_t n = 0;
  for (const auto& v : list.value()) {
    if (++n > 8U) {
      break;
    }
    static_cast<void>(f.read_column(v.name, 0));
    static_cast<void>(f.read_column(v.name, 1));
    static_cast<void>(f.read_scalar(v.name));
    static_cast<void>(f.read_string(v.name));
    if (v.class_name == "struct") {
      // Struct fields by dotted name (the corpus' scipy files hold structvar.a and .b).
      for (const char* field : {".a", ".b", ".a.b", ".b.a"}) {
        static_cast<void>(f.read_column(v.name + field, 0));
        static_cast<void>(f.read_scalar(v.name + field));
      }
    }
  }
  return 0;
}

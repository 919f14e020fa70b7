// Tests of imu/mat/zlib.hpp: RFC 1950/1951 inflate against streams made by an independent
// implementation (CPython's zlib, vectors/ made by gen_zlib_vectors.py, checked by size and a
// CRC-32 computed here), hand-built bad streams, output bounds, and the stored-block writer.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "imu/mat/zlib.hpp"

namespace {

using imu::mat::InflateMode;
using imu::mat::InflateStatus;
using Bytes = std::vector<std::uint8_t>;

// CRC-32 (IEEE, reflected, as zlib.crc32): the test's own reference, not code under test.
std::uint32_t crc32(const Bytes& b) {
  std::uint32_t c = 0xFFFFFFFFU;
  for (const std::uint8_t x : b) {
    c ^= x;
    for (int k = 0; k < 8; ++k) {
      c = (c & 1U) != 0U ? (c >> 1U) ^ 0xEDB88320U : c >> 1U;
    }
  }
  return ~c;
}

Bytes read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

struct Vector {
  std::string name;
  bool raw = false;
  std::size_t size = 0;
  std::uint32_t crc = 0;
  Bytes stream;
};

std::vector<Vector> load_vectors() {
  const std::string dir = IMU_MAT_VECTOR_DIR;
  std::ifstream m(dir + "/manifest.txt");
  std::vector<Vector> v;
  std::string line;
  while (std::getline(m, line)) {
    std::istringstream is(line);
    Vector x;
    std::string kind;
    std::string crc_hex;
    is >> x.name >> kind >> x.size >> crc_hex;
    x.raw = kind == "raw";
    x.crc = static_cast<std::uint32_t>(std::stoul(crc_hex, nullptr, 16));
    x.stream = read_file(dir + "/" + x.name + ".zz");
    v.push_back(std::move(x));
  }
  return v;
}

imu::mat::InflateResult inflate(const Vector& v, std::size_t max_out, InflateMode mode, Bytes& out) {
  return v.raw ? imu::mat::inflate_raw(v.stream.data(), v.stream.size(), max_out, mode, out)
               : imu::mat::inflate_zlib(v.stream.data(), v.stream.size(), max_out, mode, out);
}

// Writes deflate bit fields: Huffman codes MSB first, other fields LSB first (RFC 1951 3.1.1).
class BitWriter {
 public:
  void bits(unsigned value, unsigned n) {
    for (unsigned i = 0; i < n; ++i) {
      put((value >> i) & 1U);
    }
  }
  void code(unsigned code, unsigned n) {
    for (unsigned i = n; i-- > 0U;) {
      put((code >> i) & 1U);
    }
  }
  Bytes zlib() const {
    Bytes z;
    z.reserve(bytes_.size() + 2U);
    z.push_back(0x78);  // CM 8, CINFO 7
    z.push_back(0x01);  // no dictionary, FCHECK
    for (const std::uint8_t b : bytes_) {
      z.push_back(b);
    }
    return z;
  }

 private:
  void put(unsigned bit) {
    if (n_ % 8U == 0U) {
      bytes_.push_back(0);
    }
    bytes_.back() = static_cast<std::uint8_t>(bytes_.back() | (bit << (n_ % 8U)));
    ++n_;
  }
  Bytes bytes_;
  unsigned n_ = 0;
};

InflateStatus inflate_all(const Bytes& z, std::size_t max_out = 1U << 20U) {
  Bytes out;
  return imu::mat::inflate_zlib(z.data(), z.size(), max_out, InflateMode::whole, out).status;
}

TEST(Zlib, Adler32KnownValues) {
  // Reference values: RFC 1950 (empty input -> 1) and the widely published "Wikipedia" example.
  const std::string w = "Wikipedia";
  EXPECT_EQ(imu::mat::adler32(nullptr, 0), 1U);
  EXPECT_EQ(imu::mat::adler32(reinterpret_cast<const std::uint8_t*>(w.data()), w.size()),
            0x11E60398U);
  // Long input crosses the 5552-byte reduction block: chaining must equal one pass.
  Bytes big(100000);
  for (std::size_t i = 0; i < big.size(); ++i) {
    big[i] = static_cast<std::uint8_t>(255U - i % 7U);
  }
  const std::uint32_t one = imu::mat::adler32(big.data(), big.size());
  const std::uint32_t two =
      imu::mat::adler32(big.data() + 7000, big.size() - 7000, imu::mat::adler32(big.data(), 7000));
  EXPECT_EQ(one, two);
}

TEST(Zlib, PythonVectorsInflateExactly) {
  const std::vector<Vector> vectors = load_vectors();
  ASSERT_GE(vectors.size(), 25U) << "manifest missing: " << IMU_MAT_VECTOR_DIR;
  for (const Vector& v : vectors) {
    SCOPED_TRACE(v.name);
    ASSERT_FALSE(v.stream.empty());
    Bytes out;
    const auto r = inflate(v, v.size, InflateMode::whole, out);  // exact bound is enough
    EXPECT_EQ(r.status, InflateStatus::ok) << imu::mat::describe(r.status);
    EXPECT_EQ(r.in_consumed, v.stream.size());
    EXPECT_EQ(out.size(), v.size);
    EXPECT_EQ(crc32(out), v.crc);
  }
}

TEST(Zlib, OutputBoundIsEnforced) {
  for (const Vector& v : load_vectors()) {
    if (v.size < 2U) {
      continue;
    }
    SCOPED_TRACE(v.name);
    Bytes out;
    // One byte short of the true size: whole mode must refuse, never write past the bound.
    auto r = inflate(v, v.size - 1U, InflateMode::whole, out);
    EXPECT_EQ(r.status, InflateStatus::output_limit);
    EXPECT_LE(out.size(), v.size - 1U);
    // Prefix mode stops cleanly at the bound with the first bytes of the full output.
    Bytes full;
    ASSERT_EQ(inflate(v, v.size, InflateMode::whole, full).status, InflateStatus::ok);
    r = inflate(v, v.size / 2U, InflateMode::prefix, out);
    EXPECT_EQ(r.status, InflateStatus::ok);
    ASSERT_EQ(out.size(), v.size / 2U);
    EXPECT_TRUE(std::equal(out.begin(), out.end(), full.begin()));
  }
}

TEST(Zlib, EveryTruncationIsDetected) {
  for (const Vector& v : load_vectors()) {
    if (v.raw || v.stream.size() > 5000U) {
      continue;  // keep the unit test fast: the small streams cover every block type
    }
    SCOPED_TRACE(v.name);
    for (std::size_t cut = 0; cut < v.stream.size(); ++cut) {
      Bytes out;
      const auto r = imu::mat::inflate_zlib(v.stream.data(), cut, v.size, InflateMode::whole, out);
      ASSERT_EQ(r.status, InflateStatus::truncated_input) << "cut at " << cut;
    }
  }
}

// The long vectors (skewed_*: 14-bit codes through the decoder's sub-tables) are cut at a sample
// of places, and at each of their last 64 bytes, where the decoder leaves its fast loop.
TEST(Zlib, LongStreamTruncationIsDetected) {
  for (const Vector& v : load_vectors()) {
    if (v.raw || v.stream.size() <= 5000U) {
      continue;
    }
    SCOPED_TRACE(v.name);
    const std::size_t n = v.stream.size();
    for (std::size_t cut = 0; cut < n; cut += cut + 64U < n ? 997U : 1U) {
      Bytes out;
      const auto r = imu::mat::inflate_zlib(v.stream.data(), cut, v.size, InflateMode::whole, out);
      ASSERT_EQ(r.status, InflateStatus::truncated_input) << "cut at " << cut;
    }
  }
}

// A reused output vector (longer than the result, holding other bytes) gives the same output:
// the inflater overwrites it instead of clearing it first.
TEST(Zlib, ReusedOutputVectorIsReplaced) {
  Bytes out(1U << 20U, 0xA5);
  for (const Vector& v : load_vectors()) {
    SCOPED_TRACE(v.name);
    const auto r = inflate(v, v.size, InflateMode::whole, out);
    ASSERT_EQ(r.status, InflateStatus::ok) << imu::mat::describe(r.status);
    EXPECT_EQ(out.size(), v.size);
    EXPECT_EQ(crc32(out), v.crc);
  }
}

// Matches at every distance 1..40 (the copy loop has separate cases for d = 1, 2..7, 8..15,
// 16..31 and >= 32, each copying whole chunks past the match end) and lengths up to 258.
TEST(Zlib, MatchCopiesAtEveryShortDistance) {
  std::uint32_t x = 777U;
  for (std::size_t d = 1; d <= 40U; ++d) {
    SCOPED_TRACE(d);
    Bytes in;
    for (std::size_t rep = 0; rep < 30U; ++rep) {
      Bytes period(d);
      for (auto& b : period) {
        x = x * 1664525U + 1013904223U;
        b = static_cast<std::uint8_t>(x >> 24U);
      }
      const std::size_t len = 3U + (rep * 37U) % 600U;  // runs shorter and longer than 258
      for (std::size_t i = 0; i < d + len; ++i) {
        in.push_back(period[i % d]);
      }
    }
    const Bytes z = imu::mat::zlib_compress_fixed(in.data(), in.size(), 1U);
    Bytes out;
    const auto r = imu::mat::inflate_zlib(z.data(), z.size(), in.size(), InflateMode::whole, out);
    ASSERT_EQ(r.status, InflateStatus::ok) << imu::mat::describe(r.status);
    EXPECT_EQ(out, in);
  }
}

TEST(Zlib, TrailerMismatchIsDetected) {
  for (const Vector& v : load_vectors()) {
    if (v.raw) {
      continue;
    }
    SCOPED_TRACE(v.name);
    Bytes z = v.stream;
    z.back() ^= 0x01U;
    EXPECT_EQ(inflate_all(z), InflateStatus::adler_mismatch);
  }
}

TEST(Zlib, BadHeaders) {
  EXPECT_EQ(inflate_all({0x78, 0x9D, 0x03, 0x00}), InflateStatus::bad_zlib_header);  // FCHECK
  EXPECT_EQ(inflate_all({0x77, 0x85, 0x03, 0x00}), InflateStatus::bad_zlib_header);  // CM = 7
  EXPECT_EQ(inflate_all({0x88, 0x1C, 0x03, 0x00}), InflateStatus::bad_zlib_header);  // CINFO 8
  // FDICT set, header check valid: (0x78 * 256 + 0xBB) % 31 == 0.
  EXPECT_EQ(inflate_all({0x78, 0xBB, 0, 0, 0, 0, 0x03, 0x00}), InflateStatus::preset_dictionary);
  EXPECT_EQ(inflate_all({0x78}), InflateStatus::truncated_input);
}

TEST(Zlib, BadBlockTypeAndStoredLength) {
  EXPECT_EQ(inflate_all({0x78, 0x01, 0x07}), InflateStatus::bad_block_type);  // BTYPE = 11
  // Stored block with LEN = 5, NLEN = 0 (should be ~5).
  EXPECT_EQ(inflate_all({0x78, 0x01, 0x01, 0x05, 0x00, 0x00, 0x00, 'a', 'b', 'c', 'd', 'e'}),
            InflateStatus::bad_stored_length);
}

TEST(Zlib, FixedBlockDistanceTooFar) {
  BitWriter w;
  w.bits(1, 1);               // BFINAL
  w.bits(1, 2);               // fixed Huffman
  w.code(0x30U + 'a', 8);     // literal 'a'
  w.code(1, 7);               // length symbol 257: length 3
  w.code(1, 5);               // distance symbol 1: distance 2 > 1 byte of output
  w.code(0, 7);               // end of block
  EXPECT_EQ(inflate_all(w.zlib()), InflateStatus::bad_distance);
}

TEST(Zlib, FixedBlockInvalidSymbols) {
  BitWriter lit;
  lit.bits(1, 1);
  lit.bits(1, 2);
  lit.code(0xC0U + (286U - 280U), 8);  // length symbol 286 does not exist
  EXPECT_EQ(inflate_all(lit.zlib()), InflateStatus::bad_symbol);

  BitWriter dist;
  dist.bits(1, 1);
  dist.bits(1, 2);
  dist.code(0x30U + 'a', 8);
  dist.code(1, 7);   // length 3
  dist.code(30, 5);  // distance symbol 30 does not exist
  EXPECT_EQ(inflate_all(dist.zlib()), InflateStatus::bad_symbol);
}

TEST(Zlib, FixedBlockOverlappingCopy) {
  // 'a' then (length 10, distance 1): 11 x 'a'. Hand-built, so the expected output is known.
  BitWriter w;
  w.bits(1, 1);
  w.bits(1, 2);
  w.code(0x30U + 'a', 8);
  w.code(8, 7);  // length symbol 264: length 10
  w.code(0, 5);  // distance symbol 0: distance 1
  w.code(0, 7);  // end of block: 30 bits in all, the last byte is zero-padded
  Bytes z = w.zlib();
  ASSERT_EQ(z.size(), 2U + 4U);
  const Bytes want(11, 'a');
  const std::uint32_t a = imu::mat::adler32(want.data(), want.size());
  for (int s = 24; s >= 0; s -= 8) {
    z.push_back(static_cast<std::uint8_t>(a >> static_cast<unsigned>(s)));
  }
  Bytes out;
  const auto r = imu::mat::inflate_zlib(z.data(), z.size(), 100, InflateMode::whole, out);
  EXPECT_EQ(r.status, InflateStatus::ok) << imu::mat::describe(r.status);
  EXPECT_EQ(out, want);
}

TEST(Zlib, DynamicBlockBadCodeLengths) {
  // Over-subscribed code length code: four symbols of length 1.
  BitWriter over;
  over.bits(1, 1);
  over.bits(2, 2);  // dynamic
  over.bits(0, 5);  // HLIT: 257
  over.bits(0, 5);  // HDIST: 1
  over.bits(0, 4);  // HCLEN: 4 (symbols 16, 17, 18, 0)
  for (int i = 0; i < 4; ++i) {
    over.bits(1, 3);
  }
  over.bits(0, 16);
  EXPECT_EQ(inflate_all(over.zlib()), InflateStatus::bad_code_lengths);

  // Repeat-previous (16) as the very first code length: nothing to repeat.
  BitWriter rep;
  rep.bits(1, 1);
  rep.bits(2, 2);
  rep.bits(0, 5);
  rep.bits(0, 5);
  rep.bits(0, 4);
  rep.bits(1, 3);  // symbol 16: length 1
  rep.bits(0, 3);  // 17: unused
  rep.bits(0, 3);  // 18: unused
  rep.bits(1, 3);  // 0: length 1  -> canonical codes: 0 -> "0", 16 -> "1"
  rep.code(1, 1);  // symbol 16 first
  rep.bits(0, 16);
  EXPECT_EQ(inflate_all(rep.zlib()), InflateStatus::bad_code_lengths);
}

TEST(Zlib, StoreRoundTrips) {
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{65535},
                              std::size_t{65536}, std::size_t{200000}}) {
    SCOPED_TRACE(n);
    Bytes data(n);
    for (std::size_t i = 0; i < n; ++i) {
      data[i] = static_cast<std::uint8_t>((i * 2654435761U) >> 13U);
    }
    const Bytes z = imu::mat::zlib_store(data.data(), data.size());
    EXPECT_EQ(z.size(), n + 6U + 5U * (n == 0U ? 1U : (n + 65534U) / 65535U));
    Bytes out;
    const auto r = imu::mat::inflate_zlib(z.data(), z.size(), n, InflateMode::whole, out);
    EXPECT_EQ(r.status, InflateStatus::ok);
    EXPECT_EQ(r.in_consumed, z.size());
    EXPECT_EQ(out, data);
  }
}

TEST(Zlib, FixedCompressorRoundTrips) {
  std::vector<Bytes> inputs;
  inputs.emplace_back();                 // empty
  inputs.emplace_back(1, 0x42);          // one byte
  inputs.emplace_back(100000, 'a');      // long runs: overlapping distance-1 matches of 258
  Bytes noise(70000);
  std::uint32_t x = 12345U;
  for (auto& b : noise) {
    x = x * 1664525U + 1013904223U;
    b = static_cast<std::uint8_t>(x >> 24U);  // LCG: hardly any matches, 8/9-bit literals
  }
  inputs.push_back(noise);
  Bytes imu;  // quantised doubles: 8-byte patterns at distances that are multiples of 8
  for (int i = 0; i < 40000; ++i) {
    x = x * 1664525U + 1013904223U;
    const double v = -9.81 + 0.0326561445 * static_cast<double>(static_cast<int>(x >> 29U) - 4);
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, 8);
    for (unsigned k = 0; k < 8U; ++k) {
      imu.push_back(static_cast<std::uint8_t>(bits >> (8U * k)));
    }
  }
  inputs.push_back(imu);
  for (const Bytes& in : inputs) {
    SCOPED_TRACE(in.size());
    for (const unsigned chain : {0U, 1U, 32U}) {
      const Bytes z = imu::mat::zlib_compress_fixed(in.data(), in.size(), chain);
      ASSERT_GE(z.size(), 3U);
      EXPECT_EQ(z[2] & 7U, 3U);  // BFINAL = 1, BTYPE = 01 (fixed Huffman)
      Bytes out;
      const auto r = imu::mat::inflate_zlib(z.data(), z.size(), in.size(), InflateMode::whole, out);
      ASSERT_EQ(r.status, InflateStatus::ok) << imu::mat::describe(r.status);
      EXPECT_EQ(r.in_consumed, z.size());
      EXPECT_EQ(out, in);
    }
  }
  // Matching pays off: 'a' runs cost ~1 bit per 100 bytes, IMU-like doubles shrink > 3x.
  EXPECT_LT(imu::mat::zlib_compress_fixed(inputs[2].data(), inputs[2].size()).size(), 1000U);
  EXPECT_LT(imu::mat::zlib_compress_fixed(imu.data(), imu.size()).size(), imu.size() / 3U);
}

TEST(Zlib, SizeBoundFormula) {
  EXPECT_EQ(imu::mat::max_inflated_size(0), 1024U);
  EXPECT_EQ(imu::mat::max_inflated_size(1000), 1032U * 1000U + 1024U);
  EXPECT_EQ(imu::mat::max_inflated_size(static_cast<std::size_t>(-1)), static_cast<std::size_t>(-1));
}

TEST(Zlib, DescribeEveryStatus) {
  for (int s = 0; s <= static_cast<int>(InflateStatus::adler_mismatch); ++s) {
    const std::string d = imu::mat::describe(static_cast<InflateStatus>(s));
    EXPECT_FALSE(d.empty());
    EXPECT_NE(d, "unknown inflate status");
  }
}

}  // namespace

// ---- InflateStream: the same decoder fed and drained in pieces ----
namespace stream_test {

// Hands out a byte vector `step` bytes per read() (1: the worst case for the input refills).
class PieceSource : public imu::mat::ByteSource {
 public:
  PieceSource(const Bytes& b, std::size_t step) : b_(b), step_(step) {}
  std::size_t read(std::uint8_t* dst, std::size_t n) override {
    const std::size_t k = std::min({n, step_, b_.size() - pos_});
    if (k > 0U) {  // (an empty vector's data() may be null: no memcpy from it)
      std::memcpy(dst, b_.data() + pos_, k);
    }
    pos_ += k;
    return k;
  }

 private:
  const Bytes& b_;
  std::size_t step_;
  std::size_t pos_ = 0;
};

// Inflate `z` through an InflateStream, reading `out_step` bytes at a time.
InflateStatus stream_all(const Bytes& z, bool zlib, std::size_t in_step, std::size_t out_step,
                         Bytes& out) {
  PieceSource src(z, in_step);
  imu::mat::InflateStream s(src, zlib);
  out.clear();
  Bytes piece(out_step);
  for (;;) {
    const std::size_t n = s.read(piece.data(), piece.size());
    if (n == 0U) {
      break;
    }
    out.insert(out.end(), piece.begin(), piece.begin() + static_cast<std::ptrdiff_t>(n));
  }
  EXPECT_EQ(s.total_out(), out.size());
  EXPECT_EQ(s.finished(), s.status() == InflateStatus::ok);
  return s.status();
}

}  // namespace stream_test

// Every vector (stored, fixed, dynamic blocks, 14-bit codes, long matches across the 96 kB
// output buffer) gives the same bytes as the whole-buffer inflater, whatever the input and
// output piece sizes.
TEST(ZlibStream, EveryVectorEqualsWholeInflate) {
  for (const Vector& v : load_vectors()) {
    SCOPED_TRACE(v.name);
    for (const std::size_t in_step : {std::size_t{1}, std::size_t{7}, std::size_t{4096},
                                      std::size_t{1} << 20U}) {
      for (const std::size_t out_step : {std::size_t{1}, std::size_t{8}, std::size_t{100000}}) {
        if ((in_step == 1U || out_step == 1U) && v.size > 300000U) {
          continue;  // keep the unit test fast
        }
        Bytes out;
        ASSERT_EQ(stream_test::stream_all(v.stream, !v.raw, in_step, out_step, out),
                  InflateStatus::ok)
            << "in " << in_step << " out " << out_step;
        ASSERT_EQ(out.size(), v.size);
        EXPECT_EQ(crc32(out), v.crc);
      }
    }
  }
}

// A long output (several slides of the 32 kB window) with matches reaching back across a slide.
TEST(ZlibStream, LongOutputAcrossSlides) {
  Bytes in(1U << 20U);
  std::uint32_t x = 5U;
  for (std::size_t i = 0; i < in.size(); ++i) {
    x = x * 1664525U + 1013904223U;
    // a 30000-byte period: every match is 30000 back, across slides of the window
    in[i] = i < 30000U ? static_cast<std::uint8_t>(x >> 24U) : in[i - 30000U];
  }
  for (const Bytes& z : {imu::mat::zlib_compress_fixed(in.data(), in.size()),
                         imu::mat::zlib_store(in.data(), in.size())}) {
    Bytes out;
    ASSERT_EQ(stream_test::stream_all(z, true, 3000U, 77777U, out), InflateStatus::ok);
    EXPECT_EQ(out, in);
  }
}

TEST(ZlibStream, ErrorsAsWholeInflate) {
  for (const Vector& v : load_vectors()) {
    if (v.raw || v.stream.size() > 5000U) {
      continue;
    }
    SCOPED_TRACE(v.name);
    for (std::size_t cut = 0; cut < v.stream.size(); cut += 1U + cut / 16U) {
      const Bytes z(v.stream.begin(), v.stream.begin() + static_cast<std::ptrdiff_t>(cut));
      Bytes out;
      ASSERT_EQ(stream_test::stream_all(z, true, 5U, 4096U, out), InflateStatus::truncated_input)
          << "cut at " << cut;
    }
    Bytes bad = v.stream;
    bad.back() = static_cast<std::uint8_t>(bad.back() ^ 1U);
    Bytes out;
    EXPECT_EQ(stream_test::stream_all(bad, true, 64U, 4096U, out), InflateStatus::adler_mismatch);
  }
  Bytes out;
  EXPECT_EQ(stream_test::stream_all({0x78, 0x9D, 0x03, 0x00}, true, 1U, 8U, out),
            InflateStatus::bad_zlib_header);
  EXPECT_EQ(stream_test::stream_all({0x78, 0xBB, 0x03, 0x00}, true, 1U, 8U, out),
            InflateStatus::preset_dictionary);
}

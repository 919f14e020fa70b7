// The LZ4 decoder (imu/cli/lz4.hpp) against frames written by Debian's lz4 command line tool
// (lz4/make_vectors.sh: linked and independent blocks, content size, block and content
// checksums, a stored block), and against malformed input: every cut and many flipped bytes of
// those frames, and hand-made blocks for each refusal. Nothing may crash or read out of bounds
// (the asan preset runs this test).
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "imu/cli/lz4.hpp"

namespace {

using imu::cli::Lz4Status;
using Bytes = std::vector<std::uint8_t>;

Bytes read_file(const std::string& name) {
  std::ifstream f(std::string(IMU_LZ4_DIR) + "/" + name, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

Lz4Status decode(const Bytes& in, Bytes& out, std::size_t max_out = std::size_t{1} << 24U) {
  return imu::cli::lz4_decode_frames(in.data(), in.size(), max_out, out);
}

TEST(Lz4, FramesOfTheLz4ToolDecodeToTheirContent) {
  const Bytes lines = read_file("lines.txt");
  const Bytes random = read_file("random.bin");
  ASSERT_EQ(lines.size(), 105000U);
  ASSERT_EQ(random.size(), 1000U);
  const std::vector<std::pair<const char*, const Bytes*>> cases = {
      {"lines.lz4", &lines}, {"lines_bx.lz4", &lines}, {"random.lz4", &random}};
  for (const auto& [file, want] : cases) {
    const Bytes in = read_file(file);
    ASSERT_FALSE(in.empty()) << file;
    Bytes out;
    EXPECT_EQ(decode(in, out), Lz4Status::ok) << file;
    EXPECT_TRUE(out == *want) << file;
  }
  // Two frames one after the other, with a skippable frame between: one content.
  Bytes two = read_file("random.lz4");
  const Bytes skip = {0x5A, 0x2A, 0x4D, 0x18, 3, 0, 0, 0, 1, 2, 3};
  two.insert(two.end(), skip.begin(), skip.end());
  const Bytes again = read_file("lines.lz4");
  two.insert(two.end(), again.begin(), again.end());
  Bytes out;
  ASSERT_EQ(decode(two, out), Lz4Status::ok);
  Bytes want = random;
  want.insert(want.end(), lines.begin(), lines.end());
  EXPECT_TRUE(out == want);
}

TEST(Lz4, Xxh32OfKnownInputs) {
  // XXH32 reference values (xxHash's own test of the empty input and "abc", seed 0).
  EXPECT_EQ(imu::cli::xxh32(nullptr, 0), 0x02CC5D05U);
  const std::uint8_t abc[] = {'a', 'b', 'c'};
  EXPECT_EQ(imu::cli::xxh32(abc, 3), 0x32D153FFU);
}

// Every prefix of a frame is refused (cut anywhere, the frame is incomplete), and so is a
// frame with any of many single bytes changed (the checksums and the format see each).
TEST(Lz4, CutAndFlippedFramesAreRefused) {
  for (const char* file : {"lines.lz4", "lines_bx.lz4", "random.lz4"}) {
    const Bytes in = read_file(file);
    Bytes out;
    for (std::size_t n = 0; n < in.size(); n += n < 256 ? 1U : 37U) {
      const Bytes cut(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(n));
      EXPECT_NE(decode(cut, out), Lz4Status::ok) << file << " cut at " << n;
    }
    for (std::size_t at = 4; at < in.size(); at += at < 64 ? 1U : 101U) {
      Bytes bad = in;
      bad[at] ^= 0x5AU;
      EXPECT_NE(decode(bad, out), Lz4Status::ok) << file << " byte " << at;
    }
  }
}

TEST(Lz4, EachMalformedFieldHasItsStatus) {
  const Bytes good = read_file("lines.lz4");  // FLG 0x6C (linked, content size, content sum)
  Bytes out;
  Bytes b = good;
  b[0] = 0x05;
  EXPECT_EQ(decode(b, out), Lz4Status::bad_magic);
  b = good;
  b[4] = 0xAC;  // version 10
  EXPECT_EQ(decode(b, out), Lz4Status::bad_descriptor);
  b = good;
  b[5] = 0x30;  // block size id 3
  EXPECT_EQ(decode(b, out), Lz4Status::bad_descriptor);
  b = good;
  b[4] = 0x6D;  // a dictionary id
  EXPECT_EQ(decode(b, out), Lz4Status::dictionary);
  b = good;
  b[14] ^= 1U;  // HC after FLG, BD and the 8-byte content size
  EXPECT_EQ(decode(b, out), Lz4Status::bad_header_checksum);
  b = good;
  b[15 + 2] = 0x02;  // the first block's size word: 0x20000 + .., above 64 KiB
  EXPECT_EQ(decode(b, out), Lz4Status::block_too_large);
  EXPECT_EQ(decode(good, out, 1000), Lz4Status::output_limit);  // the content size says so
  const Bytes random = read_file("random.lz4");  // no content size: a stored block of 1000
  EXPECT_EQ(decode(random, out, 999), Lz4Status::output_limit);
  EXPECT_EQ(decode(Bytes{}, out), Lz4Status::truncated_input);
}

// Hand-made blocks (LZ4 block format): token (literals << 4 | match - 4), literals, offset.
TEST(Lz4, BlocksDecodeOverlappingMatchesAndRefuseBadOnes) {
  const auto run = [](const Bytes& in, std::size_t capacity, std::size_t window, Bytes& out,
                      std::size_t start = 0) {
    out.assign(capacity, 0);
    std::size_t n = start;
    const Lz4Status st =
        imu::cli::lz4_decode_block(in.data(), in.size(), out.data(), capacity, window, n);
    out.resize(st == Lz4Status::ok ? n : 0);
    return st;
  };
  Bytes out;
  // "ab", then a match of 6 at offset 2 (it overlaps its own output), then the literal "c".
  ASSERT_EQ(run({0x22, 'a', 'b', 2, 0, 0x10, 'c'}, 64, 0, out), Lz4Status::ok);
  EXPECT_EQ(std::string(out.begin(), out.end()), "ababababc");
  // A literal run of 15 + 3 (length bytes) and a match length of 4 + 15 + 1.
  Bytes in = {0xFF, 3};
  in.insert(in.end(), 18, 'x');
  in.insert(in.end(), {1, 0, 1});
  in.push_back(0x10);
  in.push_back('y');
  ASSERT_EQ(run(in, 64, 0, out), Lz4Status::ok);
  EXPECT_EQ(out.size(), 18U + 20U + 1U);
  EXPECT_EQ(run({0x10, 'a', 0, 0}, 64, 0, out), Lz4Status::bad_offset);  // offset 0
  EXPECT_EQ(run({0x10, 'a', 2, 0}, 64, 0, out), Lz4Status::bad_offset);  // before the start
  EXPECT_EQ(run({0x50, 'a', 'b'}, 64, 0, out), Lz4Status::bad_block);    // literals past input
  EXPECT_EQ(run({0x10, 'a', 1}, 64, 0, out), Lz4Status::bad_block);      // offset cut off
  EXPECT_EQ(run({0x1F, 'a', 1, 0, 255}, 64, 0, out), Lz4Status::bad_block);  // length cut off
  EXPECT_EQ(run({0x1F, 'a', 1, 0, 100}, 64, 0, out), Lz4Status::bad_block);  // past capacity
  EXPECT_EQ(run({0x30, 'a', 'b', 'c'}, 2, 0, out), Lz4Status::bad_block);    // literals too
  // A match into the output before the block only when the window allows it.
  EXPECT_EQ(run({0x00, 4, 0}, 64, 4, out, 4), Lz4Status::bad_offset);
  EXPECT_EQ(run({0x00, 4, 0, 0x00}, 64, 0, out, 4), Lz4Status::ok);
}

}  // namespace

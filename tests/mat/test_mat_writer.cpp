// Tests of imu/mat/mat_writer.hpp: exact bytes of a scalar variable computed by hand from the
// MAT-file format (they also equal what scipy.io.savemat writes for fs = 100.0, see the shared
// data), read-back through the reader (plain and compressed), and the error cases. The
// independent check by a stdlib-only Python parser is check_mat_writer.py (ctest
// mat_writer_python_check).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <string>
#include <vector>

#include <unistd.h>

#include "imu/mat/mat_reader.hpp"
#include "imu/mat/mat_writer.hpp"

namespace imu::mat {
// Readable ctest names for the round-trip parameters (found by ADL).
void PrintTo(const WriterOptions& o, std::ostream* os) {
  *os << (!o.compress ? "plain" : o.deflate == Deflate::stored ? "stored" : "fixed_huffman");
}
}  // namespace imu::mat

namespace {

using imu::mat::MatFile;
using imu::mat::MatWriter;
using imu::mat::WriterOptions;
using Bytes = std::vector<std::uint8_t>;

std::uint64_t bits_of(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

void expect_same(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(bits_of(got[i]), bits_of(want[i])) << "index " << i;
  }
}

TEST(MatWriter, ScalarBytesMatchTheFormatByHand) {
  MatWriter w;
  ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
  const Bytes& b = w.bytes();
  ASSERT_EQ(b.size(), 128U + 64U);
  EXPECT_EQ(std::string(b.begin(), b.begin() + 19), "MATLAB 5.0 MAT-file");
  EXPECT_EQ(b[124], 0x00);  // version 0x0100 little-endian
  EXPECT_EQ(b[125], 0x01);
  EXPECT_EQ(b[126], 'I');
  EXPECT_EQ(b[127], 'M');
  const Bytes want = {
      0x0E, 0, 0, 0, 0x38, 0, 0, 0,                    // miMATRIX, 56 bytes
      0x06, 0, 0, 0, 0x08, 0, 0, 0, 0x06, 0, 0, 0, 0, 0, 0, 0,  // flags: mxDOUBLE_CLASS
      0x05, 0, 0, 0, 0x08, 0, 0, 0, 0x01, 0, 0, 0, 0x01, 0, 0, 0,  // dims 1x1
      0x01, 0, 0x02, 0, 'f', 's', 0, 0,                // small element miINT8 "fs"
      0x09, 0, 0, 0, 0x08, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x59, 0x40};  // miDOUBLE 100.0
  EXPECT_EQ(Bytes(b.begin() + 128, b.end()), want);
}

TEST(MatWriter, CompressedScalarIsAStoredZlibStream) {
  MatWriter w(WriterOptions{true, imu::mat::Deflate::stored});
  ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
  const Bytes& b = w.bytes();
  // miCOMPRESSED tag, zlib header 78 01, one final stored block of 64 bytes, Adler-32.
  ASSERT_EQ(b.size(), 128U + 8U + 2U + 5U + 64U + 4U);
  EXPECT_EQ(b[128], 0x0F);
  EXPECT_EQ(b[132], 2U + 5U + 64U + 4U);
  EXPECT_EQ(b[136], 0x78);
  EXPECT_EQ(b[137], 0x01);
  EXPECT_EQ(b[138], 0x01);  // BFINAL, stored
  EXPECT_EQ(b[139], 64U);   // LEN
  EXPECT_EQ(b[141], 0xFF - 64U);  // NLEN low byte
}

// (compress, deflate) combinations.
class WriterRoundTrip : public ::testing::TestWithParam<WriterOptions> {};

TEST_P(WriterRoundTrip, ReaderGetsBackEveryValue) {
  std::vector<double> acc(1000);
  for (std::size_t i = 0; i < acc.size(); ++i) {
    acc[i] = -9.81 + 0.0326561445 * static_cast<double>(static_cast<int>(i % 7U) - 3);
  }
  acc[3] = -0.0;
  acc[4] = 1e-310;  // subnormal survives
  MatWriter w(GetParam());
  ASSERT_TRUE(w.add_column("acc_z", acc).ok());
  ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
  ASSERT_TRUE(w.add_string("units", "m/s^2").ok());
  ASSERT_TRUE(w.add_string("none", "").ok());
  ASSERT_TRUE(w.add_matrix("m", 2, 3, {1, 2, 3, 4, 5, 6}).ok());
  const Bytes& b = w.bytes();
  auto f = MatFile::from_memory("w.mat", b.data(), b.size());
  ASSERT_TRUE(f.ok()) << f.error().message;
  const auto c = f.value().read_column("acc_z");
  ASSERT_TRUE(c.ok()) << c.error().message;
  expect_same(c.value(), acc);
  const auto fs = f.value().read_scalar("fs");
  ASSERT_TRUE(fs.ok());
  EXPECT_EQ(bits_of(fs.value()), bits_of(100.0));
  const auto u = f.value().read_string("units");
  ASSERT_TRUE(u.ok()) << u.error().message;
  EXPECT_EQ(u.value(), "m/s^2");
  const auto e = f.value().read_string("none");
  ASSERT_TRUE(e.ok()) << e.error().message;
  EXPECT_EQ(e.value(), "");
  const auto m1 = f.value().read_column("m", 1);
  ASSERT_TRUE(m1.ok());
  expect_same(m1.value(), {3.0, 4.0});
  const auto list = f.value().list_variables();
  ASSERT_TRUE(list.ok());
  ASSERT_EQ(list.value().size(), 5U);
  EXPECT_EQ(list.value()[0].compressed, GetParam().compress);
}

INSTANTIATE_TEST_SUITE_P(
    Mat, WriterRoundTrip,
    ::testing::Values(WriterOptions{false, imu::mat::Deflate::fixed_huffman},
                      WriterOptions{true, imu::mat::Deflate::fixed_huffman},
                      WriterOptions{true, imu::mat::Deflate::stored}),
    [](const ::testing::TestParamInfo<WriterOptions>& i) {
      return !i.param.compress ? std::string("plain")
             : i.param.deflate == imu::mat::Deflate::stored ? std::string("stored")
                                                             : std::string("fixed_huffman");
    });

// A column written in pieces (column_start + encode_doubles + the other variables) is the same
// file, byte for byte, as add_column() followed by the same variables.
TEST(MatWriter, ColumnInPiecesIsTheSameFile) {
  std::vector<double> v(1001);
  for (std::size_t i = 0; i < v.size(); ++i) {
    v[i] = 1e-6 * static_cast<double>(i * i) - 0.25;
  }
  MatWriter whole;
  ASSERT_TRUE(whole.add_column("acc_z", v).ok());
  ASSERT_TRUE(whole.add_scalar("fs", 100.0).ok());
  ASSERT_TRUE(whole.add_string("source", "test").ok());
  MatWriter small;
  const auto start = small.column_start("acc_z", v.size());
  ASSERT_TRUE(start.ok()) << start.error().message;
  ASSERT_TRUE(small.add_scalar("fs", 100.0).ok());
  ASSERT_TRUE(small.add_string("source", "test").ok());
  EXPECT_FALSE(small.add_scalar("acc_z", 1.0).ok());  // the name is taken
  Bytes file(small.bytes().begin(), small.bytes().begin() + 128);
  file.insert(file.end(), start.value().begin(), start.value().end());
  for (std::size_t at = 0; at < v.size(); at += 300U) {  // in pieces of 300 samples
    const std::size_t n = std::min<std::size_t>(300U, v.size() - at);
    Bytes piece(8U * n);
    MatWriter::encode_doubles(v.data() + at, n, piece.data());
    file.insert(file.end(), piece.begin(), piece.end());
  }
  file.insert(file.end(), small.bytes().begin() + 128, small.bytes().end());
  EXPECT_EQ(file, whole.bytes());
  MatWriter packed(WriterOptions{true});
  EXPECT_FALSE(packed.column_start("x", 10).ok());  // compressed: not in pieces
}

TEST(MatWriter, SaveAndReadBackFromDisk) {
  const std::string path = ::testing::TempDir() + "imu_mat_writer_test_" + std::to_string(::getpid()) + ".mat";
  MatWriter w(WriterOptions{true});
  ASSERT_TRUE(w.add_column("acc_z", {1.0, 2.0, 3.0}).ok());
  ASSERT_TRUE(w.add_scalar("fs", 100.0).ok());
  const auto st = w.save(path);
  ASSERT_TRUE(st.ok()) << st.error().message;
  const auto c = imu::mat::read_column(path, "acc_z");
  ASSERT_TRUE(c.ok()) << c.error().message;
  expect_same(c.value(), {1.0, 2.0, 3.0});
  std::remove(path.c_str());
  const auto bad = w.save("/nonexistent/dir/out.mat");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("/nonexistent/dir/out.mat: cannot create"), std::string::npos);
}

TEST(MatWriter, RejectsBadInput) {
  MatWriter w;
  EXPECT_EQ(w.add_scalar("", 1.0).error().message, "variable '': invalid name (1 to 63 characters)");
  EXPECT_EQ(w.add_scalar("1x", 1.0).error().message,
            "variable '1x': invalid name (must start with a letter)");
  EXPECT_EQ(w.add_scalar("a-b", 1.0).error().message,
            "variable 'a-b': invalid name (letters, digits and '_' only)");
  EXPECT_FALSE(w.add_scalar(std::string(64, 'a'), 1.0).ok());
  EXPECT_TRUE(w.add_scalar(std::string(63, 'a'), 1.0).ok());
  ASSERT_TRUE(w.add_scalar("fs", 1.0).ok());
  EXPECT_EQ(w.add_scalar("fs", 2.0).error().message, "variable 'fs': already written");
  EXPECT_EQ(w.add_matrix("m", 2, 2, {1.0}).error().message, "variable 'm': 1 values for 2x2");
  EXPECT_EQ(w.add_string("s", "caf\xC3\xA9").error().message, "variable 's': text is not 7-bit ASCII");
  EXPECT_FALSE(w.add_matrix("huge", 0x80000000U, 1, {}).ok());
  // Failed calls add nothing.
  auto f = MatFile::from_memory("w.mat", w.bytes().data(), w.bytes().size());
  ASSERT_TRUE(f.ok());
  const auto l = f.value().list_variables();
  ASSERT_TRUE(l.ok());
  EXPECT_EQ(l.value().size(), 2U);
}

}  // namespace

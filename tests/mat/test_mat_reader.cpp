// Tests of imu/mat/mat_reader.hpp: files written by scipy.io.savemat (compressed and not),
// hand-made files (big-endian, class double stored as integers, small data elements), and one
// test per kind of bad file. Expected values are the inputs of gen_mat_vectors.py or bytes built
// here by hand; doubles are compared bit for bit (the reader must convert exactly).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "imu/mat/mat_reader.hpp"
#include "imu/mat/zlib.hpp"

namespace {

using imu::mat::MatFile;
using Bytes = std::vector<std::uint8_t>;

const std::string kDir = IMU_MAT_VECTOR_DIR;

Bytes read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

std::uint64_t bits_of(double v) {
  std::uint64_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// Exact comparison through the bit patterns (no float ==; -0.0 and 0.0 differ, as they should).
void expect_same(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(bits_of(got[i]), bits_of(want[i])) << "index " << i << ": " << got[i] << " vs "
                                                 << want[i];
  }
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// --- hand-built little-endian images (spec layout, independent of the writer) -------------------
void u32(Bytes& b, std::uint32_t v) {
  for (unsigned i = 0; i < 4U; ++i) {
    b.push_back(static_cast<std::uint8_t>(v >> (8U * i)));
  }
}
void pad8(Bytes& b) {
  while (b.size() % 8U != 0U) {
    b.push_back(0);
  }
}
Bytes header() {
  std::string text = "MATLAB 5.0 MAT-file, test image";
  text.resize(116, ' ');
  Bytes b(text.begin(), text.end());
  b.resize(124, 0);
  b.push_back(0x00);
  b.push_back(0x01);
  b.push_back('I');
  b.push_back('M');
  return b;
}
// A miMATRIX element of class double named `name` with the given dims and raw real-part bytes
// stored as miDOUBLE (whatever their count: tests use this to claim dims that do not fit).
Bytes double_matrix(const std::string& name, std::uint32_t rows, std::uint32_t cols,
                    const std::vector<double>& values, std::uint32_t n_override = 0) {
  Bytes body;
  u32(body, 6);  // miUINT32 array flags
  u32(body, 8);
  u32(body, 6);  // mxDOUBLE_CLASS
  u32(body, 0);
  u32(body, 5);  // miINT32 dims
  u32(body, 8);
  u32(body, rows);
  u32(body, cols);
  u32(body, 1);  // miINT8 name
  u32(body, static_cast<std::uint32_t>(name.size()));
  body.insert(body.end(), name.begin(), name.end());
  pad8(body);
  u32(body, 9);  // miDOUBLE real part
  u32(body, static_cast<std::uint32_t>(8U * values.size()));
  for (const double v : values) {
    const std::uint64_t b = bits_of(v);
    u32(body, static_cast<std::uint32_t>(b));
    u32(body, static_cast<std::uint32_t>(b >> 32U));
  }
  Bytes e;
  u32(e, 14);
  u32(e, n_override != 0U ? n_override : static_cast<std::uint32_t>(body.size()));
  e.insert(e.end(), body.begin(), body.end());
  return e;
}
// A miMATRIX element of any class with the real part given as raw bytes of storage `type`.
Bytes raw_matrix(std::uint32_t cls, std::uint32_t rows, std::uint32_t cols, const std::string& name,
                 std::uint32_t type, const Bytes& raw) {
  Bytes body;
  for (const std::uint32_t w : {6U, 8U, cls, 0U, 5U, 8U, rows, cols, 1U}) {
    u32(body, w);
  }
  u32(body, static_cast<std::uint32_t>(name.size()));
  body.insert(body.end(), name.begin(), name.end());
  pad8(body);
  u32(body, type);
  u32(body, static_cast<std::uint32_t>(raw.size()));
  body.insert(body.end(), raw.begin(), raw.end());
  pad8(body);
  Bytes e;
  u32(e, 14);
  u32(e, static_cast<std::uint32_t>(body.size()));
  e.insert(e.end(), body.begin(), body.end());
  return e;
}
Bytes compressed(const Bytes& element) {
  const Bytes z = imu::mat::zlib_store(element.data(), element.size());
  Bytes e;
  u32(e, 15);
  u32(e, static_cast<std::uint32_t>(z.size()));
  e.insert(e.end(), z.begin(), z.end());
  return e;
}
Bytes image(std::initializer_list<Bytes> elements) {
  Bytes b = header();
  for (const Bytes& e : elements) {
    b.insert(b.end(), e.begin(), e.end());
  }
  return b;
}
MatFile open_memory(const Bytes& b, const std::string& name = "t.mat") {
  auto r = MatFile::from_memory(name, b.data(), b.size());
  EXPECT_TRUE(r.ok()) << r.error().message;
  return std::move(r).value();
}
// Column `column` of `var` through a ChannelStream, read `step` samples at a time: the error
// message, or "(no error)" with the values in `out`.
std::string stream_column(const std::string& path, const std::string& var, std::size_t column,
                          std::vector<double>& out, std::size_t step = 3) {
  out.clear();
  auto s = imu::mat::ChannelStream::open(path, var, column);
  if (!s.ok()) {
    return s.error().message;
  }
  std::vector<double> piece(step);
  for (;;) {
    const auto r = s.value().read(piece.data(), piece.size());
    if (!r.ok()) {
      return r.error().message;
    }
    if (r.value() == 0U) {
      break;
    }
    out.insert(out.end(), piece.begin(), piece.begin() + static_cast<std::ptrdiff_t>(r.value()));
  }
  EXPECT_EQ(out.size(), s.value().size());
  return "(no error)";
}

// The same image through a file and a ChannelStream: same error (the path shown as t.mat), or
// the same values.
std::string stream_error_of(const Bytes& b, const std::string& var, std::size_t column,
                            std::vector<double>& out) {
  const std::string path = "/tmp/imu-mat-stream-" + std::to_string(getpid()) + ".mat";
  std::FILE* fp = std::fopen(path.c_str(), "wb");
  EXPECT_NE(fp, nullptr);
  EXPECT_EQ(std::fwrite(b.data(), 1, b.size(), fp), b.size());
  std::fclose(fp);
  std::string e = stream_column(path, var, column, out);
  (void)std::remove(path.c_str());
  for (std::size_t at = e.find(path); at != std::string::npos; at = e.find(path)) {
    e.replace(at, path.size(), "t.mat");
  }
  return e;
}

// The error of reading `var` from the image, which must be the same through MatFile (whole
// file in memory) and ChannelStream (a file read in pieces).
std::string column_error(const Bytes& b, const std::string& var, std::size_t column = 0) {
  std::vector<double> streamed;
  const std::string se = stream_error_of(b, var, column, streamed);
  auto f = MatFile::from_memory("t.mat", b.data(), b.size());
  if (!f.ok()) {
    EXPECT_EQ(se, f.error().message);
    return f.error().message;
  }
  const auto r = f.value().read_column(var, column);
  std::string e = r.ok() ? std::string("(no error)") : r.error().message;
  EXPECT_EQ(se, e) << "ChannelStream and MatFile disagree";
  if (r.ok()) {
    expect_same(streamed, r.value());
  }
  return e;
}

// --- scipy-written files -------------------------------------------------------------------------
class ScipyFile : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    auto r = MatFile::open(kDir + "/" + GetParam());
    ASSERT_TRUE(r.ok()) << r.error().message;
    file_ = std::make_unique<MatFile>(std::move(r).value());
  }
  std::vector<double> col(const std::string& name, std::size_t c = 0) {
    const auto r = file_->read_column(name, c);
    EXPECT_TRUE(r.ok()) << r.error().message;
    return r.ok() ? r.value() : std::vector<double>{};
  }
  std::string err(const std::string& name, std::size_t c = 0) {
    const auto r = file_->read_column(name, c);
    return r.ok() ? std::string("(no error)") : r.error().message;
  }
  std::unique_ptr<MatFile> file_;
};

TEST_P(ScipyFile, ListsEveryVariableInOrder) {
  const auto r = file_->list_variables();
  ASSERT_TRUE(r.ok()) << r.error().message;
  const std::vector<std::string> names = {"cellvar", "structvar", "d_col", "d_row", "d_mat",
                                          "s_col",   "i8",        "u8",    "i16",   "u16",
                                          "i32",     "u32",       "i64",   "u64",   "flag",
                                          "scalar",  "text",      "charmat", "cplx", "empty",
                                          "cube"};
  ASSERT_EQ(r.value().size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ(r.value()[i].name, names[i]);
  }
  const auto& v = r.value();
  EXPECT_EQ(v[0].class_name, "cell");
  EXPECT_EQ(v[1].class_name, "struct");
  EXPECT_EQ(v[4].class_name, "double");
  EXPECT_EQ(v[4].rows, 3U);
  EXPECT_EQ(v[4].cols, 2U);
  EXPECT_EQ(v[5].class_name, "single");
  EXPECT_EQ(v[12].class_name, "int64");
  EXPECT_EQ(v[14].class_name, "logical");
  EXPECT_EQ(v[16].class_name, "char");
  EXPECT_TRUE(v[18].complex);
  EXPECT_EQ(v[20].n_dims, 3U);
  EXPECT_EQ(v[20].cols, 12U);
}

TEST_P(ScipyFile, DoubleColumnRowAndMatrix) {
  expect_same(col("d_col"), {1.5, -2.25, 3e10, -0.0, 1e-300});
  expect_same(col("d_row"), {1.0, 2.0, 3.0, 4.5});  // a row vector is read whole
  expect_same(col("d_mat", 0), {1.0, 3.0, 5.0});
  expect_same(col("d_mat", 1), {2.0, 4.0, 6.0});
  expect_same(col("cube", 5), {10.0, 11.0});  // 2x3x4 seen as 2x12, column-major 0..23
}

TEST_P(ScipyFile, EveryNumericClassConverts) {
  expect_same(col("s_col"), {0.5, -1.25, 3.0});
  expect_same(col("i8"), {-128.0, 0.0, 127.0});
  expect_same(col("u8"), {0.0, 255.0});
  expect_same(col("i16"), {-32768.0, 32767.0});
  expect_same(col("u16"), {65535.0});
  expect_same(col("i32"), {-2147483648.0, 2147483647.0});
  expect_same(col("u32"), {4294967295.0});
  expect_same(col("i64"), {-9007199254740992.0, 123456789.0});
  expect_same(col("u64"), {9007199254740992.0});
  expect_same(col("flag"), {1.0, 0.0, 1.0});
}

TEST_P(ScipyFile, ScalarAndStrings) {
  const auto s = file_->read_scalar("scalar");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(bits_of(s.value()), bits_of(42.0));
  const auto u = file_->read_scalar("u16");
  ASSERT_TRUE(u.ok());
  EXPECT_EQ(bits_of(u.value()), bits_of(65535.0));
  const auto t = file_->read_string("text");
  ASSERT_TRUE(t.ok()) << t.error().message;
  EXPECT_EQ(t.value(), "hello MAT");
  const auto m = file_->read_string("charmat");
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m.value(), "ab\ncd");
}

TEST_P(ScipyFile, WrongKindOrShapeIsAClearError) {
  const std::string f = kDir + "/" + GetParam();
  EXPECT_EQ(err("d_row", 1),
            f + ": variable 'd_row': is a vector (1x4): column 2 does not exist (columns count from 1)");
  EXPECT_EQ(err("d_mat", 2), f + ": variable 'd_mat': has 2 columns (3x2): column 3 does not exist (columns count from 1)");
  EXPECT_TRUE(contains(err("cellvar"), "variable 'cellvar': is a cell array, not numeric"));
  EXPECT_TRUE(contains(err("structvar"), "is a struct array"));
  EXPECT_TRUE(contains(err("text"), "variable 'text': is a char array, not numeric"));
  EXPECT_TRUE(contains(err("cplx"), "variable 'cplx': complex not supported"));
  EXPECT_TRUE(contains(err("empty"), "variable 'empty': is empty (0x0)"));
  const auto s = file_->read_scalar("d_col");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, f + ": variable 'd_col': is 5x1, not a scalar");
  const auto t = file_->read_string("d_col");
  ASSERT_FALSE(t.ok());
  EXPECT_TRUE(contains(t.error().message, "variable 'd_col': is a double array, not char"));
}

TEST_P(ScipyFile, MissingVariableListsTheOthers) {
  const std::string f = kDir + "/" + GetParam();
  EXPECT_EQ(err("acc_q"),
            f + ": variable 'acc_q' not found; variables: cellvar, structvar, d_col, d_row, d_mat, "
                "s_col, i8, u8, i16, u16, i32, u32, i64, u64, flag, scalar, text, charmat, cplx, "
                "empty, cube");
}

TEST_P(ScipyFile, PathApiMatchesMemoryApi) {
  const std::string f = kDir + "/" + GetParam();
  const Bytes b = read_file(f);
  const MatFile m = open_memory(b, f);
  const auto a = imu::mat::read_column(f, "d_mat", 1);
  const auto c = m.read_column("d_mat", 1);
  ASSERT_TRUE(a.ok() && c.ok());
  expect_same(a.value(), c.value());
  const auto s = imu::mat::read_scalar(f, "scalar");
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(bits_of(s.value()), bits_of(42.0));
  const auto t = imu::mat::read_string(f, "text");
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(t.value(), "hello MAT");
  const auto l = imu::mat::list_variables(f);
  ASSERT_TRUE(l.ok());
  EXPECT_EQ(l.value().size(), 21U);
  std::vector<double> reused(1000, 7.0);
  ASSERT_TRUE(m.read_column_into("d_col", 0, reused).ok());
  expect_same(reused, {1.5, -2.25, 3e10, -0.0, 1e-300});
}

// ChannelStream gives the same values, or the same error, as MatFile for every variable and
// column of the scipy files, read 1, 2 or 1000 samples at a time; scan_variables() lists as
// list_variables(); stream_scalar() reads as read_scalar().
TEST_P(ScipyFile, ChannelStreamMatchesMatFile) {
  const std::string f = kDir + "/" + GetParam();
  const auto listed = file_->list_variables();
  const auto scanned = imu::mat::scan_variables(f);
  ASSERT_TRUE(listed.ok() && scanned.ok());
  ASSERT_EQ(listed.value().size(), scanned.value().size());
  for (std::size_t i = 0; i < listed.value().size(); ++i) {
    const auto& a = listed.value()[i];
    const auto& b = scanned.value()[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.class_name, b.class_name);
    EXPECT_EQ(a.rows, b.rows);
    EXPECT_EQ(a.cols, b.cols);
    EXPECT_EQ(a.file_offset, b.file_offset);
    EXPECT_EQ(a.file_bytes, b.file_bytes);
    for (std::size_t c = 0; c < 3U; ++c) {
      for (const std::size_t step : {std::size_t{1}, std::size_t{2}, std::size_t{1000}}) {
        SCOPED_TRACE(a.name + " column " + std::to_string(c) + " step " + std::to_string(step));
        std::vector<double> got;
        const std::string se = stream_column(f, a.name, c, got, step);
        EXPECT_EQ(se, err(a.name, c));
        if (se == "(no error)") {
          expect_same(got, col(a.name, c));
        }
      }
    }
  }
  const auto s = imu::mat::stream_scalar(f, "scalar");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(bits_of(s.value()), bits_of(42.0));
  const auto notscalar = imu::mat::stream_scalar(f, "d_col");
  ASSERT_FALSE(notscalar.ok());
  EXPECT_EQ(notscalar.error().message, f + ": variable 'd_col': is 5x1, not a scalar");
}

// Struct fields by dotted name: the same values, or the same error, through MatFile
// (the struct inflated whole, then descended) and ChannelStream (descended in the stream, the
// fields before skipped), read 1 or 1000 samples at a time.
TEST_P(ScipyFile, StructFieldsByDottedName) {
  const std::string f = kDir + "/" + GetParam();
  expect_same(col("structvar.a"), {1.0, 2.0});
  EXPECT_EQ(err("structvar.c"),
            f + ": variable 'structvar': field 'c' not found; fields: a, b");
  EXPECT_TRUE(contains(err("structvar.b"), "variable 'structvar.b': is a char array, not numeric"))
      << err("structvar.b");
  EXPECT_EQ(err("d_col.x"), f + ": variable 'd_col': is a double array, not a struct: no field 'x'");
  EXPECT_EQ(err("structvar.a.x"),
            f + ": variable 'structvar.a': is a double array, not a struct: no field 'x'");
  for (const char* name : {"structvar.a", "structvar.b", "structvar.c", "d_col.x", "structvar.a.x"}) {
    for (const std::size_t step : {std::size_t{1}, std::size_t{1000}}) {
      SCOPED_TRACE(std::string(name) + " step " + std::to_string(step));
      std::vector<double> got;
      const std::string se = stream_column(f, name, 0, got, step);
      EXPECT_EQ(se, err(name));
      if (se == "(no error)") {
        expect_same(got, col(name));
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Mat, ScipyFile,
                         ::testing::Values("scipy_v5_compressed.mat", "scipy_v5_uncompressed.mat"));

// --- hand-made files -----------------------------------------------------------------------------
TEST(MatReader, BigEndianFile) {
  auto r = MatFile::open(kDir + "/handmade_be.mat");
  ASSERT_TRUE(r.ok()) << r.error().message;
  const MatFile& f = r.value();
  EXPECT_TRUE(f.big_endian());
  const auto c = f.read_column("be_col");
  ASSERT_TRUE(c.ok()) << c.error().message;
  expect_same(c.value(), {1.0, -2.5});
  const auto t = f.read_string("be_text");
  ASSERT_TRUE(t.ok()) << t.error().message;
  EXPECT_EQ(t.value(), "hi");
  const auto i = f.read_column("be_i32");
  ASSERT_TRUE(i.ok()) << i.error().message;
  expect_same(i.value(), {-7.0, 0.0, 2000000000.0});
}

TEST(MatReader, DoubleClassStoredAsIntegersInSmallElements) {
  auto r = MatFile::open(kDir + "/handmade_mixed.mat");
  ASSERT_TRUE(r.ok()) << r.error().message;
  const auto a = r.value().read_column("d_as_u8");
  ASSERT_TRUE(a.ok()) << a.error().message;
  expect_same(a.value(), {1.0, 2.0, 250.0});
  const auto b = r.value().read_column("d_as_i16");
  ASSERT_TRUE(b.ok()) << b.error().message;
  expect_same(b.value(), {-300.0, 301.0});
  const auto s = r.value().read_scalar("d_as_u8_1");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(bits_of(s.value()), bits_of(9.0));
}

TEST(MatReader, HandBuiltCompressedAndPlainAgree) {
  const Bytes plain = image({double_matrix("x", 3, 1, {1.0, 2.0, 3.0})});
  const Bytes packed = image({compressed(double_matrix("x", 3, 1, {1.0, 2.0, 3.0}))});
  for (const Bytes* b : {&plain, &packed}) {
    const MatFile f = open_memory(*b);
    const auto c = f.read_column("x");
    ASSERT_TRUE(c.ok()) << c.error().message;
    expect_same(c.value(), {1.0, 2.0, 3.0});
  }
}

TEST(MatReader, HeaderLongerThanThePeekFallsBackToWholeInflate) {
  const std::string name(600, 'n');  // longer than MATLAB allows, but a valid element
  const Bytes b = image({compressed(double_matrix(name, 2, 1, {1.0, 2.0})),
                         compressed(double_matrix("after", 1, 1, {5.0}))});
  const MatFile f = open_memory(b);
  const auto c = f.read_column(name);
  ASSERT_TRUE(c.ok()) << c.error().message;
  expect_same(c.value(), {1.0, 2.0});
  const auto a = f.read_scalar("after");
  ASSERT_TRUE(a.ok()) << a.error().message;
  EXPECT_EQ(bits_of(a.value()), bits_of(5.0));
}

TEST(MatReader, CharEncodingsToUtf8) {
  // U+00E9 and U+1F600 (surrogate pair D83D DE00 in UTF-16), per storage type.
  const Bytes utf16 = {'a', 0, 0xE9, 0, 0x3D, 0xD8, 0x00, 0xDE};            // miUINT16, 1x4
  const Bytes utf8 = {'a', 0xC3, 0xA9, 0xF0, 0x9F, 0x98, 0x80};              // miUTF8, 1x3
  const Bytes latin1 = {'a', 0xE9};                                          // miUINT8, 1x2
  const Bytes utf32 = {'a', 0, 0, 0, 0x00, 0xF6, 0x01, 0x00};                // miUTF32, 1x2
  const Bytes b = image({raw_matrix(4, 1, 4, "u16", 4, utf16), raw_matrix(4, 1, 3, "u8", 16, utf8),
                         raw_matrix(4, 1, 2, "l1", 2, latin1), raw_matrix(4, 1, 2, "u32", 18, utf32)});
  const MatFile f = open_memory(b);
  const std::string want16 = "a\xC3\xA9\xF0\x9F\x98\x80";
  EXPECT_EQ(f.read_string("u16").value(), want16);
  EXPECT_EQ(f.read_string("u8").value(), want16);
  EXPECT_EQ(f.read_string("l1").value(), "a\xC3\xA9");
  EXPECT_EQ(f.read_string("u32").value(), "a\xF0\x9F\x98\x80");
  // Char stored as miDOUBLE is not a valid char array.
  const Bytes bad = image({raw_matrix(4, 1, 1, "c", 9, Bytes(8, 0))});
  const auto r = open_memory(bad).read_string("c");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "t.mat: variable 'c': corrupt: storage type miDOUBLE (9) is not valid for class char");
}

// --- bad files: one test per kind ------------------------------------------------------------------
TEST(MatReaderErrors, NotAMatFile) {
  const std::string text(300, 'x');
  const Bytes b(text.begin(), text.end());
  auto r = MatFile::from_memory("notes.txt", b.data(), b.size());
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(contains(r.error().message, "notes.txt: not a MAT-file")) << r.error().message;
  const Bytes tiny = {'M', 'A', 'T'};
  r = MatFile::from_memory("tiny.mat", tiny.data(), tiny.size());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message,
            "tiny.mat: not a MAT-file: 3 bytes, shorter than the 128-byte level 5 header");
  Bytes bad_version = header();
  bad_version[124] = 0x00;
  bad_version[125] = 0x02;
  r = MatFile::from_memory("v.mat", bad_version.data(), bad_version.size());
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(contains(r.error().message, "unsupported MAT-file version 0x0200"));
}

TEST(MatReaderErrors, MissingFile) {
  const auto r = imu::mat::read_column("/nonexistent/dir/x.mat", "acc_z");
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(contains(r.error().message, "/nonexistent/dir/x.mat: cannot open"));
}

TEST(MatReaderErrors, Version4File) {
  const auto r = MatFile::open(kDir + "/scipy_v4.mat");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message,
            kDir + "/scipy_v4.mat: MATLAB v4 MAT-file is not supported: re-save with -v7");
}

TEST(MatReaderErrors, Version73Hdf5) {
  // What MATLAB -v7.3 writes: a 512-byte user block starting with the MATLAB text, then HDF5.
  std::string text = "MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 .";
  text.resize(116, ' ');
  Bytes b(text.begin(), text.end());
  b.resize(128, 0);
  b[124] = 0x00;
  b[125] = 0x02;
  b[126] = 'I';
  b[127] = 'M';
  b.resize(512, 0);
  const Bytes sig = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1A, '\n'};
  b.insert(b.end(), sig.begin(), sig.end());
  b.resize(2048, 0);
  auto r = MatFile::from_memory("v73.mat", b.data(), b.size());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "v73.mat: MATLAB v7.3 (HDF5) MAT-file is not supported: re-save with -v7");
  // The HDF5 signature alone is enough (text overwritten).
  std::fill(b.begin(), b.begin() + 116, static_cast<std::uint8_t>(' '));
  r = MatFile::from_memory("v73.mat", b.data(), b.size());
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(contains(r.error().message, "re-save with -v7"));
}

TEST(MatReaderErrors, Truncated) {
  const Bytes full = read_file(kDir + "/scipy_v5_compressed.mat");
  const Bytes cut(full.begin(), full.end() - 20);
  const std::string e = column_error(cut, "cube");
  EXPECT_TRUE(contains(e, "t.mat: truncated: variable 'cube' element at offset ")) << e;
  EXPECT_TRUE(contains(e, "remain")) << e;
  // Variables before the cut stay readable.
  const MatFile f = open_memory(cut);
  EXPECT_TRUE(f.read_column("d_col").ok());
  // Uncompressed: cut inside the last variable, and a stray partial tag.
  const Bytes plain = image({double_matrix("a", 2, 1, {1.0, 2.0}), double_matrix("b", 1, 1, {3.0})});
  EXPECT_TRUE(contains(column_error(Bytes(plain.begin(), plain.end() - 3), "b"),
                       "truncated: variable 'b' element at offset"));
  // Cut inside the header of a compressed variable: no name to give, the offset still says where.
  const Bytes packed = image({compressed(double_matrix("a", 2, 1, {1.0, 2.0}))});
  const std::string h = column_error(Bytes(packed.begin(), packed.begin() + 128 + 8 + 7), "a");
  // 91 = zlib header 2 + stored block header 5 + 80-byte miMATRIX element + Adler-32 4.
  EXPECT_EQ(h, "t.mat: truncated: element at offset 128 declares 91 bytes, only 7 remain");
  Bytes stray = plain;
  stray.push_back(14);
  stray.push_back(0);
  EXPECT_TRUE(contains(column_error(stray, "zz"), "truncated: 2 stray bytes at offset"));
}

TEST(MatReaderErrors, CorruptZlibStream) {
  const Bytes good = image({compressed(double_matrix("x", 3, 1, {1.0, 2.0, 3.0}))});
  Bytes adler = good;
  adler.back() ^= 0x55U;  // last byte of the Adler-32 trailer
  EXPECT_EQ(column_error(adler, "x"),
            "t.mat: variable 'x': corrupt zlib stream (Adler-32 check failed)");
  Bytes head = good;
  head[128 + 8 + 1] ^= 0x01U;  // zlib FLG byte: header check fails
  EXPECT_EQ(column_error(head, "x"),
            "t.mat: element at offset 128: corrupt zlib stream (bad zlib header)");
  Bytes block = good;
  block[128 + 8 + 2] = 0x07;  // first block header: BTYPE 11
  EXPECT_TRUE(contains(column_error(block, "x"), "corrupt zlib stream (invalid block type)"));
}

TEST(MatReaderErrors, DimensionsDoNotFitTheData) {
  const Bytes b = image({double_matrix("acc", 1000, 1, {1.0, 2.0})});
  EXPECT_EQ(column_error(b, "acc"),
            "t.mat: variable 'acc': dimensions 1000x1 do not fit the data (2 elements of miDOUBLE)");
  const Bytes z = image({compressed(double_matrix("acc", 1000, 1, {1.0, 2.0}))});
  EXPECT_EQ(column_error(z, "acc"),
            "t.mat: variable 'acc': dimensions 1000x1 do not fit the data (2 elements of miDOUBLE)");
}

TEST(MatReaderErrors, HugeDimensionsAllocateNothing) {
  // 2^31-1 squared elements (2^65 bytes) claimed over 16 bytes of data: must fail on the sizes,
  // not by trying to allocate (an allocation of that size aborts under ASan, throws otherwise).
  const Bytes b = image({double_matrix("big", 0x7FFFFFFFU, 0x7FFFFFFFU, {1.0, 2.0})});
  EXPECT_TRUE(contains(column_error(b, "big"), "dimensions 2147483647x2147483647 do not fit"));
  const Bytes z = image({compressed(double_matrix("big", 0x7FFFFFFFU, 0x7FFFFFFFU, {1.0, 2.0}))});
  EXPECT_TRUE(contains(column_error(z, "big"), "dimensions 2147483647x2147483647 do not fit"));
  // A compressed matrix that claims 4 GiB inside a few bytes of zlib stream.
  const Bytes claim = image({compressed(double_matrix("big", 1, 1, {1.0}, 0xFFFFFFF0U))});
  EXPECT_TRUE(contains(column_error(claim, "big"), "compressed bytes can hold")) << column_error(claim, "big");
}

TEST(MatReaderErrors, StreamShorterThanItsConsistentClaim) {
  // Dims, real-part size and miMATRIX size all claim 1e6 doubles (8 MB), the zlib stream (valid,
  // padded with junk after its end so the 1032:1 bound admits the claim) holds only the header.
  Bytes e = double_matrix("acc_z", 1000000, 1, {});
  const std::uint32_t real = 8000000U;
  const std::size_t tag = e.size() - 4U;  // size field of the (empty) miDOUBLE real part
  for (unsigned i = 0; i < 4U; ++i) {
    e[tag + i] = static_cast<std::uint8_t>(real >> (8U * i));
  }
  const auto n = static_cast<std::uint32_t>(e.size() - 8U + real);
  for (unsigned i = 0; i < 4U; ++i) {
    e[4U + i] = static_cast<std::uint8_t>(n >> (8U * i));
  }
  Bytes c = compressed(e);
  c.resize(c.size() + 9000U, 0x5A);
  const auto z = static_cast<std::uint32_t>(c.size() - 8U);
  for (unsigned i = 0; i < 4U; ++i) {
    c[4U + i] = static_cast<std::uint8_t>(z >> (8U * i));
  }
  EXPECT_EQ(column_error(image({c}), "acc_z"),
            "t.mat: variable 'acc_z': truncated: zlib stream inflates to " +
                std::to_string(e.size()) + " bytes, the matrix declares " +
                std::to_string(n + 8U));
}

TEST(MatReaderErrors, StreamInflatesBeyondDeclaredSize) {
  Bytes e = double_matrix("x", 2, 1, {1.0, 2.0});
  e.resize(e.size() + 16U, 0xAB);  // the stream holds 16 bytes more than the miMATRIX declares
  EXPECT_EQ(column_error(image({compressed(e)}), "x"),
            "t.mat: variable 'x': corrupt zlib stream (inflates beyond the declared size)");
  // Declaring 8 bytes less than the sub-elements take is a corrupt matrix.
  Bytes shorter = double_matrix("x", 2, 1, {1.0, 2.0});
  const auto n = static_cast<std::uint32_t>(shorter.size() - 8U - 8U);
  for (unsigned i = 0; i < 4U; ++i) {
    shorter[4U + i] = static_cast<std::uint8_t>(n >> (8U * i));
  }
  EXPECT_TRUE(contains(column_error(image({compressed(shorter)}), "x"),
                       "miDOUBLE sub-element claims 16 bytes, only 8 remain in the matrix"));
}

// A directory (allocation sized from ftell), /dev/zero (read until bad_alloc) and a FIFO (open()
// blocks with no writer) are refused from stat(), before anything is opened or read.
TEST(MatReaderErrors, NonRegularFilesAreRefusedBeforeOpening) {
  char tmpl[] = "/tmp/imu-mat-test-XXXXXX";
  const char* dir = mkdtemp(tmpl);
  ASSERT_NE(dir, nullptr);
  const std::string fifo = std::string(dir) + "/fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::pair<std::string, std::string> cases[] = {
      {dir, "is a directory, not a MAT-file"},
      {fifo, "is a FIFO, not a MAT-file"},
      {"/dev/zero", "is a device, not a MAT-file"},
  };
  for (const auto& c : cases) {
    const auto r = MatFile::open(c.first);
    ASSERT_FALSE(r.ok()) << c.first;
    EXPECT_EQ(r.error().message, c.first + ": " + c.second);
  }
  (void)unlink(fifo.c_str());
  (void)rmdir(dir);
}

// ReadLimits: a variable larger than the budget (as inflated, or as doubles) and a file larger
// than the budget are errors naming the budget, found from the declared sizes.
TEST(MatReaderErrors, MemoryBudgetIsCheckedBeforeReading) {
  const std::vector<double> v(1000, 1.5);  // 8000 bytes of doubles, 8056 as a matrix element
  imu::mat::ReadLimits small;
  small.max_variable_bytes = 4000;
  for (const Bytes& b : {image({double_matrix("x", 1000, 1, v)}),
                         image({compressed(double_matrix("x", 1000, 1, v))})}) {
    auto f = MatFile::from_memory("t.mat", b.data(), b.size(), small);
    ASSERT_TRUE(f.ok()) << f.error().message;
    const auto r = f.value().read_column("x");
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(contains(r.error().message, "more than the reader's budget of 4000 bytes"))
        << r.error().message;
    // The default budget (256 MiB) reads it.
    auto g = MatFile::from_memory("t.mat", b.data(), b.size());
    ASSERT_TRUE(g.ok());
    EXPECT_TRUE(g.value().read_column("x").ok());
  }
  const Bytes b = image({double_matrix("x", 1000, 1, v)});
  const std::string path = "/tmp/imu-mat-budget-" + std::to_string(getpid()) + ".mat";
  std::FILE* fp = std::fopen(path.c_str(), "wb");
  ASSERT_NE(fp, nullptr);
  ASSERT_EQ(std::fwrite(b.data(), 1, b.size(), fp), b.size());
  std::fclose(fp);
  imu::mat::ReadLimits tiny_file;
  tiny_file.max_file_bytes = 1000;
  const auto r = MatFile::open(path, tiny_file);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, path + ": " + std::to_string(b.size()) +
                                   " bytes, more than the reader's budget of 1000 bytes");
  EXPECT_TRUE(MatFile::open(path).ok());
  (void)std::remove(path.c_str());
}

TEST(MatReaderErrors, VariableNotFound) {
  const Bytes b = image({double_matrix("acc_x", 1, 1, {1.0}), double_matrix("acc_y", 1, 1, {2.0})});
  EXPECT_EQ(column_error(b, "acc_q"), "t.mat: variable 'acc_q' not found; variables: acc_x, acc_y");
  EXPECT_EQ(column_error(image({}), "acc_q"), "t.mat: variable 'acc_q' not found; variables: (none)");
}

TEST(MatReaderErrors, CorruptMatrixHeader) {
  Bytes b = image({double_matrix("x", 1, 1, {1.0})});
  b[128 + 8] = 7;  // array flags tag type: not miUINT32
  EXPECT_TRUE(contains(column_error(b, "x"), "array flags are not an 8-byte miUINT32 element"));
  Bytes neg = image({double_matrix("x", 1, 1, {1.0})});
  neg[128 + 8 + 16 + 8 + 3] = 0x80;  // rows = negative
  EXPECT_TRUE(contains(column_error(neg, "x"), "negative dimension"));
}

}  // namespace

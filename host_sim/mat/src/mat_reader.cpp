// MAT-file level 5 reader. See imu/mat/mat_reader.hpp for the contract.
#include "imu/mat/mat_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <utility>

#include "imu/mat/zlib.hpp"

namespace imu::mat {
namespace {

// Data types (MAT-file format, table 1-1).
constexpr std::uint32_t kMiInt8 = 1;
constexpr std::uint32_t kMiUint8 = 2;
constexpr std::uint32_t kMiInt16 = 3;
constexpr std::uint32_t kMiUint16 = 4;
constexpr std::uint32_t kMiInt32 = 5;
constexpr std::uint32_t kMiUint32 = 6;
constexpr std::uint32_t kMiSingle = 7;
constexpr std::uint32_t kMiDouble = 9;
constexpr std::uint32_t kMiInt64 = 12;
constexpr std::uint32_t kMiUint64 = 13;
constexpr std::uint32_t kMiMatrix = 14;
constexpr std::uint32_t kMiCompressed = 15;
constexpr std::uint32_t kMiUtf8 = 16;
constexpr std::uint32_t kMiUtf16 = 17;
constexpr std::uint32_t kMiUtf32 = 18;

// Array classes.
constexpr std::uint32_t kMxStruct = 2;
constexpr std::uint32_t kMxChar = 4;
constexpr std::uint32_t kMxDouble = 6;
constexpr std::uint32_t kMxUint64 = 15;

constexpr std::size_t kHeaderBytes = 128;
// Partial inflate of a compressed variable's header: 8 + 16 + (8 + 4 * 32 dims) + (8 + 64 name)
// + 8 = 240 bytes at most for valid names; longer headers fall back to a whole inflate.
constexpr std::size_t kPeekBytes = 512;
constexpr std::size_t kMaxDims = 32;
// Second, longer peek when a header does not fit in kPeekBytes (names up to ~65,000 characters).
constexpr std::size_t kLongHeaderBytes = std::size_t{1} << 16U;
constexpr std::array<std::uint8_t, 8> kHdf5Signature = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1A, '\n'};

bool host_little_endian() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1U;
}

const char* class_name(std::uint32_t cls, bool logical) {
  if (logical) {
    return "logical";
  }
  switch (cls) {
    case 1: return "cell";
    case 2: return "struct";
    case 3: return "object";
    case 4: return "char";
    case 5: return "sparse";
    case 6: return "double";
    case 7: return "single";
    case 8: return "int8";
    case 9: return "uint8";
    case 10: return "int16";
    case 11: return "uint16";
    case 12: return "int32";
    case 13: return "uint32";
    case 14: return "int64";
    case 15: return "uint64";
    case 16: return "function_handle";
    case 17: return "opaque";
    default: return "unknown";
  }
}

const char* type_name(std::uint32_t type) {
  switch (type) {
    case kMiInt8: return "miINT8";
    case kMiUint8: return "miUINT8";
    case kMiInt16: return "miINT16";
    case kMiUint16: return "miUINT16";
    case kMiInt32: return "miINT32";
    case kMiUint32: return "miUINT32";
    case kMiSingle: return "miSINGLE";
    case kMiDouble: return "miDOUBLE";
    case kMiInt64: return "miINT64";
    case kMiUint64: return "miUINT64";
    case kMiMatrix: return "miMATRIX";
    case kMiCompressed: return "miCOMPRESSED";
    case kMiUtf8: return "miUTF8";
    case kMiUtf16: return "miUTF16";
    case kMiUtf32: return "miUTF32";
    default: return "unknown type";
  }
}

// Bytes per element of a numeric storage type; 0 if not numeric.
std::size_t numeric_size(std::uint32_t type) {
  switch (type) {
    case kMiInt8:
    case kMiUint8: return 1;
    case kMiInt16:
    case kMiUint16: return 2;
    case kMiInt32:
    case kMiUint32:
    case kMiSingle: return 4;
    case kMiDouble:
    case kMiInt64:
    case kMiUint64: return 8;
    default: return 0;
  }
}

// Bytes per code unit of a char storage type; 0 if not usable for char.
std::size_t char_unit_size(std::uint32_t type) {
  switch (type) {
    case kMiInt8:
    case kMiUint8:
    case kMiUtf8: return 1;
    case kMiUint16:
    case kMiInt16:
    case kMiUtf16: return 2;
    case kMiUint32:
    case kMiInt32:
    case kMiUtf32: return 4;
    default: return 0;
  }
}

std::uint64_t load_uint(const std::uint8_t* p, std::size_t n, bool big_endian) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = big_endian ? i : n - 1U - i;
    v = (v << 8U) | p[k];
  }
  return v;
}

std::uint32_t load_u32(const std::uint8_t* p, bool big_endian) {
  return static_cast<std::uint32_t>(load_uint(p, 4, big_endian));
}

template <class T>
T load_as(const std::uint8_t* p, bool big_endian) {
  static_assert(sizeof(T) <= 8, "scalar types only");
  const std::uint64_t bits = load_uint(p, sizeof(T), big_endian);
  T v{};
  if constexpr (sizeof(T) == 1) {
    const auto b = static_cast<std::uint8_t>(bits);
    std::memcpy(&v, &b, 1);
  } else if constexpr (sizeof(T) == 2) {
    const auto b = static_cast<std::uint16_t>(bits);
    std::memcpy(&v, &b, 2);
  } else if constexpr (sizeof(T) == 4) {
    const auto b = static_cast<std::uint32_t>(bits);
    std::memcpy(&v, &b, 4);
  } else {
    std::memcpy(&v, &bits, 8);
  }
  return v;
}

template <class T>
void convert_as(const std::uint8_t* p, std::size_t n, bool big_endian, double* out) {
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = static_cast<double>(load_as<T>(p + i * sizeof(T), big_endian));
  }
}

// Convert n elements of numeric storage `type` to double.
void convert(const std::uint8_t* p, std::uint32_t type, std::size_t n, bool big_endian, double* out) {
  switch (type) {
    case kMiDouble:
      if (!big_endian && host_little_endian()) {
        std::memcpy(out, p, n * sizeof(double));  // fast path: the file's bytes are host doubles
      } else {
        convert_as<double>(p, n, big_endian, out);
      }
      break;
    case kMiSingle: convert_as<float>(p, n, big_endian, out); break;
    case kMiInt8: convert_as<std::int8_t>(p, n, big_endian, out); break;
    case kMiUint8: convert_as<std::uint8_t>(p, n, big_endian, out); break;
    case kMiInt16: convert_as<std::int16_t>(p, n, big_endian, out); break;
    case kMiUint16: convert_as<std::uint16_t>(p, n, big_endian, out); break;
    case kMiInt32: convert_as<std::int32_t>(p, n, big_endian, out); break;
    case kMiUint32: convert_as<std::uint32_t>(p, n, big_endian, out); break;
    case kMiInt64: convert_as<std::int64_t>(p, n, big_endian, out); break;
    case kMiUint64: convert_as<std::uint64_t>(p, n, big_endian, out); break;
    default: break;  // unreachable: the caller checked numeric_size(type) != 0
  }
}

void append_utf8(std::string& s, std::uint32_t cp) {
  if (cp > 0x10FFFFU || (cp >= 0xD800U && cp <= 0xDFFFU)) {
    cp = 0xFFFDU;  // replacement character for values that are not Unicode scalars
  }
  if (cp < 0x80U) {
    s.push_back(static_cast<char>(cp));
  } else if (cp < 0x800U) {
    s.push_back(static_cast<char>(0xC0U | (cp >> 6U)));
    s.push_back(static_cast<char>(0x80U | (cp & 0x3FU)));
  } else if (cp < 0x10000U) {
    s.push_back(static_cast<char>(0xE0U | (cp >> 12U)));
    s.push_back(static_cast<char>(0x80U | ((cp >> 6U) & 0x3FU)));
    s.push_back(static_cast<char>(0x80U | (cp & 0x3FU)));
  } else {
    s.push_back(static_cast<char>(0xF0U | (cp >> 18U)));
    s.push_back(static_cast<char>(0x80U | ((cp >> 12U) & 0x3FU)));
    s.push_back(static_cast<char>(0x80U | ((cp >> 6U) & 0x3FU)));
    s.push_back(static_cast<char>(0x80U | (cp & 0x3FU)));
  }
}

// One sub-element tag inside a matrix payload.
struct Sub {
  std::uint32_t type = 0;
  std::size_t bytes = 0;     // declared data bytes
  std::size_t data_off = 0;  // offset of the data in the payload
  std::size_t next = 0;      // offset of the next tag (after 8-byte padding, clamped)
};

enum class Parse : std::uint8_t { ok, need_more, corrupt };

// Read the tag at `off`. `allow_short_data`: the data may extend past the view (partial view of
// a compressed variable); the tag itself must be inside it.
Parse read_sub(const std::uint8_t* p, std::size_t n, std::size_t off, bool big_endian,
               bool partial, bool allow_short_data, Sub& s, std::string& problem) {
  if (off > n || n - off < 8U) {
    problem = "matrix element ends inside a sub-element tag";
    return partial ? Parse::need_more : Parse::corrupt;
  }
  const std::uint32_t w0 = load_u32(p + off, big_endian);
  if ((w0 >> 16U) != 0U) {  // small data element: type and size packed in 4 bytes
    s.type = w0 & 0xFFFFU;
    s.bytes = w0 >> 16U;
    if (s.bytes > 4U) {
      problem = "small data element claims more than 4 bytes";
      return Parse::corrupt;
    }
    s.data_off = off + 4U;
    s.next = off + 8U;
    return Parse::ok;
  }
  s.type = w0;
  s.bytes = load_u32(p + off + 4U, big_endian);
  s.data_off = off + 8U;
  if (s.bytes > n - s.data_off) {
    if (partial) {
      if (allow_short_data) {
        s.next = n;
        return Parse::ok;
      }
      return Parse::need_more;
    }
    problem = std::string(type_name(s.type)) + " sub-element claims " + std::to_string(s.bytes) +
              " bytes, only " + std::to_string(n - s.data_off) + " remain in the matrix";
    return Parse::corrupt;
  }
  const std::size_t padded = s.bytes + ((8U - s.bytes % 8U) % 8U);
  s.next = padded > n - s.data_off ? n : s.data_off + padded;
  return Parse::ok;
}

std::string dims_text(const std::vector<std::uint64_t>& dims) {
  std::string t;
  for (std::size_t i = 0; i < dims.size(); ++i) {
    if (i > 0U) {
      t += 'x';
    }
    t += std::to_string(dims[i]);
  }
  return t;
}

// A level 4 file starts with a 20-byte header: type MOPT (M 0..4, O = 0, P 0..5, T 0..2),
// rows, cols, imagf (0/1), name length including the NUL, in either byte order.
bool looks_like_v4(const std::uint8_t* data, std::size_t size) {
  if (size < 20U) {
    return false;
  }
  for (const bool be : {false, true}) {
    const std::uint32_t mopt = load_u32(data, be);
    const std::uint32_t imagf = load_u32(data + 12, be);
    const std::uint32_t namlen = load_u32(data + 16, be);
    if (mopt < 5000U && (mopt / 100U) % 10U == 0U && (mopt / 10U) % 10U <= 5U && mopt % 10U <= 2U &&
        imagf <= 1U && namlen >= 2U && namlen <= 64U && size >= 20U + namlen &&
        data[20U + namlen - 1U] == 0U) {
      return true;
    }
  }
  return false;
}

}  // namespace

// A top-level data element.
namespace detail {
struct Element {
  std::size_t offset = 0;  // tag offset in the file
  std::uint32_t type = 0;
  std::size_t payload_off = 0;
  std::size_t payload_bytes = 0;
  std::size_t next = 0;
};

// A parsed matrix: header, and (full parse) the location of the real part.
struct Matrix {
  std::uint32_t cls = 0;
  bool complex = false;
  bool logical = false;
  std::vector<std::uint64_t> dims;
  std::uint64_t rows = 0;
  std::uint64_t cols = 0;
  std::uint64_t n_elems = 0;
  bool n_overflow = false;
  std::string name;
  bool has_data = false;  // numeric or char: a real-part tag was read
  std::uint32_t data_type = 0;
  std::size_t data_bytes = 0;
  const std::uint8_t* data = nullptr;  // only after a full parse
  const std::uint8_t* payload = nullptr;  // the parsed bytes (p of parse_matrix)
  std::size_t payload_bytes = 0;          // and their count (a prefix when partial)
  std::size_t header_end = 0;             // offset in the payload after the name
};
}  // namespace detail

using detail::Element;
using detail::Matrix;

namespace {

// Parse a miMATRIX payload of n bytes (partial: n is only a prefix of it).

Parse parse_matrix(const std::uint8_t* p, std::size_t n, bool big_endian, bool partial,
                   Matrix& m, std::string& problem) {
  Sub s;
  Parse r = read_sub(p, n, 0, big_endian, partial, false, s, problem);
  if (r != Parse::ok) {
    return r;
  }
  if (s.type != kMiUint32 || s.bytes != 8U) {
    problem = "array flags are not an 8-byte miUINT32 element";
    return Parse::corrupt;
  }
  const std::uint32_t flags = load_u32(p + s.data_off, big_endian);
  m.cls = flags & 0xFFU;
  m.complex = (flags & 0x800U) != 0U;
  m.logical = (flags & 0x200U) != 0U;

  r = read_sub(p, n, s.next, big_endian, partial, false, s, problem);
  if (r != Parse::ok) {
    return r;
  }
  if (s.type != kMiInt32 || s.bytes % 4U != 0U || s.bytes < 8U) {
    problem = "dimensions are not a miINT32 element of at least 2 values";
    return Parse::corrupt;
  }
  if (s.bytes / 4U > kMaxDims) {
    problem = std::to_string(s.bytes / 4U) + " dimensions (more than " + std::to_string(kMaxDims) +
              " not supported)";
    return Parse::corrupt;
  }
  m.dims.clear();
  m.n_elems = 1;
  m.n_overflow = false;
  for (std::size_t i = 0; i < s.bytes / 4U; ++i) {
    const auto d = static_cast<std::int32_t>(load_u32(p + s.data_off + 4U * i, big_endian));
    if (d < 0) {
      problem = "negative dimension " + std::to_string(d);
      return Parse::corrupt;
    }
    const auto du = static_cast<std::uint64_t>(d);
    m.dims.push_back(du);
    if (du != 0U && m.n_elems > std::numeric_limits<std::uint64_t>::max() / du) {
      m.n_overflow = true;
    }
    m.n_elems *= du;  // meaningful only when !n_overflow (or when a dimension is 0)
  }
  if (std::find(m.dims.begin(), m.dims.end(), 0U) != m.dims.end()) {
    m.n_overflow = false;
    m.n_elems = 0;
  }
  m.rows = m.dims[0];
  m.cols = 1;
  for (std::size_t i = 1; i < m.dims.size(); ++i) {
    m.cols = m.dims[i] != 0U && m.cols > std::numeric_limits<std::uint64_t>::max() / m.dims[i]
                 ? std::numeric_limits<std::uint64_t>::max()
                 : m.cols * m.dims[i];
  }

  r = read_sub(p, n, s.next, big_endian, partial, false, s, problem);
  if (r != Parse::ok) {
    return r;
  }
  if (s.type != kMiInt8 && s.type != kMiUint8 && s.type != kMiUtf8) {
    problem = "array name is not a miINT8 element";
    return Parse::corrupt;
  }
  m.name.assign(reinterpret_cast<const char*>(p + s.data_off), s.bytes);  // NOLINT: bytes as text
  const std::size_t nul = m.name.find('\0');
  if (nul != std::string::npos) {
    m.name.resize(nul);
  }
  m.payload = p;
  m.payload_bytes = n;
  m.header_end = s.next;

  m.has_data = false;
  const bool numeric = (m.cls >= kMxDouble && m.cls <= kMxUint64) || m.cls == kMxChar;
  if (!numeric) {
    return Parse::ok;  // other classes: header only, skipped by size
  }
  if (s.next >= n && !partial) {
    problem = "real part is missing";
    return Parse::corrupt;
  }
  r = read_sub(p, n, s.next, big_endian, partial, true, s, problem);
  if (r != Parse::ok) {
    return r;
  }
  m.has_data = true;
  m.data_type = s.type;
  m.data_bytes = s.bytes;
  m.data = p + s.data_off;
  return Parse::ok;
}

}  // namespace

MatFile::MatFile(MatFile&& other) noexcept
    : name_(std::move(other.name_)),
      owned_(std::move(other.owned_)),
      data_(other.data_),
      size_(other.size_),
      swap_(other.swap_),
      limits_(other.limits_) {}

MatFile& MatFile::operator=(MatFile&& other) noexcept {
  if (this != &other) {
    name_ = std::move(other.name_);
    owned_ = std::move(other.owned_);  // moving a vector keeps its buffer: data_ stays valid
    data_ = other.data_;
    size_ = other.size_;
    swap_ = other.swap_;
    limits_ = other.limits_;
  }
  return *this;
}

Result<MatFile> MatFile::from_memory(std::string display_name, const std::uint8_t* data,
                                     std::size_t size, ReadLimits limits) {
  const auto fail = [&display_name](const std::string& what) {
    return MatError{display_name + ": " + what};
  };
  const auto starts_with = [data, size](std::size_t at, const std::uint8_t* sig, std::size_t n) {
    return size >= at + n && std::memcmp(data + at, sig, n) == 0;
  };
  static constexpr char kV73[] = "MATLAB 7.3";
  if (starts_with(0, kHdf5Signature.data(), kHdf5Signature.size()) ||
      starts_with(512, kHdf5Signature.data(), kHdf5Signature.size()) ||
      starts_with(0, reinterpret_cast<const std::uint8_t*>(kV73), sizeof(kV73) - 1U)) {  // NOLINT
    return fail("MATLAB v7.3 (HDF5) MAT-file is not supported: re-save with -v7");
  }
  const bool level5 = size >= kHeaderBytes && ((data[126] == 'I' && data[127] == 'M') ||
                                               (data[126] == 'M' && data[127] == 'I'));
  if (!level5 && looks_like_v4(data, size)) {
    return fail("MATLAB v4 MAT-file is not supported: re-save with -v7");
  }
  if (size < kHeaderBytes) {
    return fail("not a MAT-file: " + std::to_string(size) +
                " bytes, shorter than the 128-byte level 5 header");
  }
  bool big_endian = false;
  if (data[126] == 'I' && data[127] == 'M') {
    big_endian = false;
  } else if (data[126] == 'M' && data[127] == 'I') {
    big_endian = true;
  } else {
    return fail("not a MAT-file: no level 5 header (endian indicator 'IM'/'MI' missing; "
                "v4 and other formats are not supported)");
  }
  const auto version = static_cast<unsigned>(load_uint(data + 124, 2, big_endian));
  if (version != 0x0100U) {
    char text[64];
    std::snprintf(text, sizeof text, "unsupported MAT-file version 0x%04x (expected 0x0100)",
                  version);
    return fail(text);
  }
  MatFile f;
  f.name_ = std::move(display_name);
  f.data_ = data;
  f.size_ = size;
  f.swap_ = big_endian;
  f.limits_ = limits;
  return f;
}

namespace {

const char* file_kind(mode_t mode) {
  if (S_ISDIR(mode)) {
    return "a directory";
  }
  if (S_ISFIFO(mode)) {
    return "a FIFO";
  }
  if (S_ISCHR(mode) || S_ISBLK(mode)) {
    return "a device";
  }
  if (S_ISSOCK(mode)) {
    return "a socket";
  }
  return "not a regular file";
}

// The whole of a regular file, at most `limit` bytes (a file that grew meanwhile is cut there
// and then fails the MAT-file checks). Nothing is opened before stat() says "regular file".
Status read_regular_file(const std::string& path, std::size_t limit,
                         std::vector<std::uint8_t>& bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return MatError{path + ": cannot open: " + std::strerror(errno)};
  }
  if (!S_ISREG(st.st_mode)) {
    return MatError{path + ": is " + file_kind(st.st_mode) + ", not a MAT-file"};
  }
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size > limit) {
    return MatError{path + ": " + std::to_string(size) + " bytes, more than the reader's budget of " +
                    std::to_string(limit) + " bytes"};
  }
  std::FILE* fp = std::fopen(path.c_str(), "rb");
  if (fp == nullptr) {
    return MatError{path + ": cannot open: " + std::strerror(errno)};
  }
  bytes.resize(static_cast<std::size_t>(size));
  const std::size_t got = std::fread(bytes.data(), 1, bytes.size(), fp);
  const bool read_error = std::ferror(fp) != 0;
  std::fclose(fp);
  if (read_error) {
    return MatError{path + ": read error"};
  }
  bytes.resize(got);  // shorter if the file shrank meanwhile
  return Status{};
}

}  // namespace

Result<MatFile> MatFile::open(const std::string& path, ReadLimits limits) {
  std::vector<std::uint8_t> bytes;
  const Status st = read_regular_file(path, limits.max_file_bytes, bytes);
  if (!st.ok()) {
    return st.error();
  }
  Result<MatFile> r = from_memory(path, bytes.data(), bytes.size(), limits);
  if (!r.ok()) {
    return r;
  }
  MatFile f = std::move(r).value();
  f.owned_ = std::move(bytes);  // the buffer does not move: data_ stays valid
  f.data_ = f.owned_.data();
  return f;
}

namespace {

// Read the top-level element tag at `off`.
// The name of a variable from the first `avail` bytes of its element ("" if they do not show it).
std::string name_from_prefix(const std::uint8_t* p, std::size_t avail, std::uint32_t type,
                             bool big_endian) {
  std::vector<std::uint8_t> scratch;
  if (type == kMiCompressed) {
    // Status ignored on purpose: whatever inflated before the fault may hold the header.
    static_cast<void>(inflate_zlib(p, avail, kPeekBytes, InflateMode::prefix, scratch));
    if (scratch.size() < 8U || load_u32(scratch.data(), big_endian) != kMiMatrix) {
      return {};
    }
    p = scratch.data() + 8;
    avail = scratch.size() - 8U;
  } else if (type != kMiMatrix) {
    return {};
  }
  Matrix m;
  std::string ignored;
  return parse_matrix(p, avail, big_endian, true, m, ignored) == Parse::ok ? m.name
                                                                            : std::string();
}

Status next_element(const std::string& file, const std::uint8_t* data, std::size_t size,
                    std::size_t off, bool big_endian, std::uint32_t& type, std::size_t& payload,
                    std::size_t& bytes, std::size_t& next) {
  if (size - off < 8U) {
    return MatError{file + ": truncated: " + std::to_string(size - off) +
                    " stray bytes at offset " + std::to_string(off) + " (an element tag is 8)"};
  }
  type = load_u32(data + off, big_endian);
  bytes = load_u32(data + off + 4U, big_endian);
  payload = off + 8U;
  if (bytes > size - payload) {
    const std::string name = name_from_prefix(data + payload, size - payload, type, big_endian);
    const std::string who = name.empty() ? std::string() : "variable '" + name + "' ";
    return MatError{file + ": truncated: " + who + "element at offset " + std::to_string(off) +
                    " declares " + std::to_string(bytes) + " bytes, only " +
                    std::to_string(size - payload) + " remain"};
  }
  std::size_t padded = bytes;
  if (type != kMiCompressed) {
    padded += (8U - bytes % 8U) % 8U;  // uncompressed elements are 8-byte aligned
  }
  next = padded > size - payload ? size : payload + padded;
  return Status{};
}

// Parse the header of the element (partial inflate when compressed) into m.
Status peek_header(const std::string& file, const std::uint8_t* data, bool big_endian,
                   std::uint32_t type, std::size_t offset, std::size_t payload, std::size_t bytes,
                   std::vector<std::uint8_t>& scratch, Matrix& m) {
  const std::string where = file + ": element at offset " + std::to_string(offset) + ": ";
  std::string problem;
  if (type == kMiMatrix) {
    const Parse r = parse_matrix(data + payload, bytes, big_endian, true, m, problem);
    if (r != Parse::ok) {
      return MatError{where + (r == Parse::need_more ? "matrix header is truncated" : problem)};
    }
    return Status{};
  }
  // miCOMPRESSED: inflate just enough to see the inner miMATRIX header.
  const std::size_t cap = std::min(kPeekBytes, max_inflated_size(bytes));
  InflateResult ir = inflate_zlib(data + payload, bytes, cap, InflateMode::prefix, scratch);
  if (ir.status != InflateStatus::ok) {
    // Name the variable if what inflated before the fault shows it.
    std::string subject = where;
    if (scratch.size() >= 8U && load_u32(scratch.data(), big_endian) == kMiMatrix) {
      Matrix partial_m;
      std::string ignored;
      if (parse_matrix(scratch.data() + 8, scratch.size() - 8U, big_endian, true, partial_m,
                       ignored) == Parse::ok &&
          !partial_m.name.empty()) {
        subject = file + ": variable '" + partial_m.name + "': ";
      }
    }
    return MatError{subject + "corrupt zlib stream (" + describe(ir.status) + ")"};
  }
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (scratch.size() < 8U) {
      return MatError{where + "compressed data holds " + std::to_string(scratch.size()) +
                      " bytes, not a matrix"};
    }
    const std::uint32_t inner = load_u32(scratch.data(), big_endian);
    if (inner != kMiMatrix) {
      return MatError{where + "compressed data holds a " + type_name(inner) +
                      " element, not miMATRIX"};
    }
    const std::size_t inner_bytes = load_u32(scratch.data() + 4, big_endian);
    const bool partial = scratch.size() - 8U < inner_bytes;
    const std::size_t view = std::min(inner_bytes, scratch.size() - 8U);
    const Parse r = parse_matrix(scratch.data() + 8, view, big_endian, partial, m, problem);
    if (r == Parse::ok) {
      return Status{};
    }
    if (r == Parse::corrupt || attempt == 1 || scratch.size() < cap) {
      return MatError{where + (r == Parse::need_more ? "matrix header is truncated" : problem)};
    }
    // Header longer than the peek (very long name or many dimensions): inflate more of it,
    // kLongHeaderBytes at most (not the whole variable: its size is not checked yet).
    ir = inflate_zlib(data + payload, bytes, std::min(kLongHeaderBytes, max_inflated_size(bytes)),
                      InflateMode::prefix, scratch);
    if (ir.status != InflateStatus::ok) {
      return MatError{where + "corrupt zlib stream (" + describe(ir.status) + ")"};
    }
  }
  return MatError{where + "matrix header is truncated"};
}

}  // namespace

namespace {

// Check the real part of a numeric or char matrix against its dimensions.
Status check_data(const std::string& where, const Matrix& m, std::size_t unit) {
  if (m.complex) {
    return MatError{where + "complex not supported (" + class_name(m.cls, m.logical) + " " +
                    dims_text(m.dims) + ")"};
  }
  if (unit == 0U) {
    return MatError{where + "corrupt: storage type " + type_name(m.data_type) + " (" +
                    std::to_string(m.data_type) + ") is not valid for class " +
                    class_name(m.cls, m.logical)};
  }
  const bool utf8 = m.data_type == kMiUtf8;
  if (m.data_bytes % unit != 0U) {
    return MatError{where + "corrupt: " + std::to_string(m.data_bytes) + " bytes of " +
                    type_name(m.data_type) + " is not a whole number of elements"};
  }
  const std::uint64_t have = m.data_bytes / unit;
  if (m.n_overflow || (!utf8 && have != m.n_elems) || (utf8 && have < m.n_elems)) {
    return MatError{where + "dimensions " + dims_text(m.dims) + " do not fit the data (" +
                    std::to_string(have) + " elements of " + type_name(m.data_type) + ")"};
  }
  return Status{};
}

// Where column `column` of the numeric matrix m starts (elements) and how many it holds (a
// vector has only column 0), or why m cannot be read as numbers.
Status numeric_column(const std::string& where, const Matrix& m, std::size_t column,
                      std::uint64_t& first, std::uint64_t& count) {
  if (!m.has_data || m.cls == kMxChar) {
    return MatError{where + "is a " + class_name(m.cls, m.logical) +
                    " array, not numeric (double, single, int8..uint64)"};
  }
  Status st = check_data(where, m, numeric_size(m.data_type));
  if (!st.ok()) {
    return st;
  }
  if (m.n_elems == 0U) {
    return MatError{where + "is empty (" + dims_text(m.dims) + ")"};
  }
  first = 0;
  count = m.n_elems;
  if (m.rows == 1U || m.cols == 1U) {
    if (column != 0U) {
      return MatError{where + "is a vector (" + dims_text(m.dims) + "): column " +
                      std::to_string(column + 1U) + " does not exist (columns count from 1)"};
    }
  } else {
    if (column >= m.cols) {
      return MatError{where + "has " + std::to_string(m.cols) + " columns (" +
                      dims_text(m.dims) + "): column " + std::to_string(column + 1U) +
                      " does not exist (columns count from 1)"};
    }
    first = static_cast<std::uint64_t>(column) * m.rows;
    count = m.rows;
  }
  return Status{};
}

// Storage unit of the real part for the matrix's class (0: not valid for it).
std::size_t data_unit(const Matrix& m) {
  return m.cls == kMxChar ? char_unit_size(m.data_type) : numeric_size(m.data_type);
}

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) {
    out += (out.empty() ? "" : ", ") + n;
  }
  return out.empty() ? std::string("(none)") : out;
}

// "<at>[corrupt: ]field 'NAME': WHAT", for the struct walks' errors.
MatError field_error(const std::string& at, std::string_view name, std::string_view what,
                     bool corrupt) {
  std::string m = at;
  m += corrupt ? "corrupt: field '" : "field '";
  m += name;
  m += "': ";
  m += what;
  return MatError{m};
}

// The field names of a struct, from its sub-elements at `off` in p[0..n) (after the name): the
// field-name length (one miINT32) and the names (miINT8, length x fields, NUL-padded). `next`:
// the offset of the first field's miMATRIX tag.
Parse struct_field_names(const std::uint8_t* p, std::size_t n, std::size_t off, bool big_endian,
                         std::vector<std::string>& names, std::size_t& next,
                         std::string& problem) {
  Sub s;
  Parse r = read_sub(p, n, off, big_endian, false, false, s, problem);
  if (r != Parse::ok) {
    return r;
  }
  if (s.type != kMiInt32 || s.bytes != 4U) {
    problem = "the struct's field-name length is not one miINT32";
    return Parse::corrupt;
  }
  const std::uint32_t len = load_u32(p + s.data_off, big_endian);
  r = read_sub(p, n, s.next, big_endian, false, false, s, problem);
  if (r != Parse::ok) {
    return r;
  }
  if ((s.type != kMiInt8 && s.type != kMiUint8) || (len == 0U && s.bytes != 0U) ||
      (len != 0U && s.bytes % len != 0U)) {
    problem = "the struct's field names are not miINT8 names of the declared length";
    return Parse::corrupt;
  }
  names.clear();
  for (std::size_t i = 0; len != 0U && i < s.bytes / len; ++i) {
    std::string name(reinterpret_cast<const char*>(p + s.data_off + i * len), len);  // NOLINT
    name.resize(std::min(name.find('\0'), name.size()));
    names.push_back(std::move(name));
  }
  next = s.next;
  return Parse::ok;
}

// A dotted name (`imu.acc_z`) as its top-level variable and its field path.
void split_dotted(std::string_view name, std::string_view& top, std::string_view& fields) {
  const std::size_t dot = name.find('.');
  top = name.substr(0, dot);
  fields = dot == std::string_view::npos ? std::string_view() : name.substr(dot + 1);
}

// The next field of a field path (`a.b` -> `a`, rest `b`).
std::string_view next_field(std::string_view& rest) {
  const std::size_t dot = rest.find('.');
  const std::string_view field = rest.substr(0, dot);
  rest = dot == std::string_view::npos ? std::string_view() : rest.substr(dot + 1);
  return field;
}

// A struct can be descended into: class struct, one element.
Status check_struct(const Matrix& st, std::string_view field, const std::string& where) {
  if (st.cls != kMxStruct) {
    return MatError{where + "is a " + class_name(st.cls, st.logical) +
                    " array, not a struct: no field '" + std::string(field) + "'"};
  }
  if (st.n_elems != 1U) {
    return MatError{where + "is a " + dims_text(st.dims) +
                    " struct array: only the fields of a 1x1 struct are read"};
  }
  return Status{};
}

// Field `field` of struct `st`, whose payload is whole in memory, parsed into `out`.
Status struct_field(const Matrix& st, std::string_view field, bool big_endian,
                    const std::string& where, Matrix& out) {
  Status ok = check_struct(st, field, where);
  if (!ok.ok()) {
    return ok;
  }
  std::vector<std::string> names;
  std::size_t off = 0;
  std::string problem;
  if (struct_field_names(st.payload, st.payload_bytes, st.header_end, big_endian, names, off,
                         problem) != Parse::ok) {
    return MatError{where + "corrupt: " + problem};
  }
  for (const auto& name : names) {
    Sub s;
    if (read_sub(st.payload, st.payload_bytes, off, big_endian, false, false, s, problem) !=
        Parse::ok) {
      return field_error(where, name, problem, true);
    }
    if (s.type != kMiMatrix) {
      return field_error(where, name, std::string("a ") + type_name(s.type) +
                                          " element, not miMATRIX", true);
    }
    if (name == field) {
      if (parse_matrix(st.payload + s.data_off, s.bytes, big_endian, false, out, problem) !=
          Parse::ok) {
        return field_error(where, name, problem, true);
      }
      out.name = name;
      return Status{};
    }
    off = s.next;
  }
  return MatError{where + "field '" + std::string(field) + "' not found; fields: " +
                  join_names(names)};
}

}  // namespace

Result<std::vector<VariableInfo>> MatFile::list_variables() const {
  std::vector<VariableInfo> vars;
  std::vector<std::uint8_t> scratch;
  std::size_t off = kHeaderBytes;
  while (off < size_) {
    std::uint32_t type = 0;
    std::size_t payload = 0;
    std::size_t bytes = 0;
    std::size_t next = 0;
    Status st = next_element(name_, data_, size_, off, swap_, type, payload, bytes, next);
    if (!st.ok()) {
      return st.error();
    }
    if (type == kMiMatrix || type == kMiCompressed) {
      Matrix m;
      st = peek_header(name_, data_, swap_, type, off, payload, bytes, scratch, m);
      if (!st.ok()) {
        return st.error();
      }
      if (!m.name.empty()) {
        VariableInfo v;
        v.name = m.name;
        v.class_name = class_name(m.cls, m.logical);
        v.rows = m.rows;
        v.cols = m.cols;
        v.n_dims = static_cast<std::uint32_t>(m.dims.size());
        v.complex = m.complex;
        v.compressed = type == kMiCompressed;
        v.file_offset = off;
        v.file_bytes = next - off;
        vars.push_back(std::move(v));
      }
    }
    off = next;
  }
  return vars;
}

Status MatFile::find(std::string_view name, Element& elem) const {
  std::vector<std::uint8_t> scratch;
  std::string seen;
  std::size_t off = kHeaderBytes;
  while (off < size_) {
    Element e;
    e.offset = off;
    Status st = next_element(name_, data_, size_, off, swap_, e.type, e.payload_off,
                             e.payload_bytes, e.next);
    if (!st.ok()) {
      return st;
    }
    if (e.type == kMiMatrix || e.type == kMiCompressed) {
      Matrix m;
      st = peek_header(name_, data_, swap_, e.type, off, e.payload_off, e.payload_bytes, scratch, m);
      if (!st.ok()) {
        return st;
      }
      if (m.name == name && !m.name.empty()) {
        elem = e;
        return Status{};
      }
      if (!m.name.empty()) {
        seen += (seen.empty() ? "" : ", ") + m.name;
      }
    }
    off = e.next;
  }
  return MatError{name_ + ": variable '" + std::string(name) + "' not found; variables: " +
                  (seen.empty() ? std::string("(none)") : seen)};
}

Status MatFile::load(std::string_view name, const Element& elem, std::vector<std::uint8_t>& scratch,
                     Matrix& m) const {
  const std::string where = name_ + ": variable '" + std::string(name) + "': ";
  std::string problem;
  const std::uint8_t* p = data_ + elem.payload_off;
  std::size_t n = elem.payload_bytes;
  if (elem.type == kMiCompressed) {
    // The header was peeked by find(): re-peek to get the declared sizes, check them, and only
    // then inflate the whole variable.
    Status st = peek_header(name_, data_, swap_, elem.type, elem.offset, elem.payload_off,
                            elem.payload_bytes, scratch, m);
    if (!st.ok()) {
      return st;
    }
    if (m.has_data) {
      st = check_data(where, m, data_unit(m));  // before inflating anything sized by the claim
      if (!st.ok()) {
        return st;
      }
    }
    const std::size_t inner_bytes = load_u32(scratch.data() + 4, swap_);
    const std::size_t limit = max_inflated_size(elem.payload_bytes);
    if (inner_bytes > limit - 8U) {
      return MatError{where + "corrupt: declares " + std::to_string(inner_bytes) +
                      " bytes, more than " + std::to_string(elem.payload_bytes) +
                      " compressed bytes can hold"};
    }
    if (!m.has_data && m.cls != kMxStruct) {
      return Status{};  // cell, object, ...: the caller rejects the class, nothing to inflate
    }
    if (inner_bytes > limits_.max_variable_bytes) {
      return MatError{where + "declares " + std::to_string(inner_bytes) +
                      " bytes inflated, more than the reader's budget of " +
                      std::to_string(limits_.max_variable_bytes) + " bytes per variable"};
    }
    // Bound: the declared size. Initial buffer: the declared size only up to 16 x the compressed
    // size (IMU data inflates ~14x); beyond that the buffer grows with what actually inflates,
    // so a consistent but false claim of gigabytes costs nothing until the stream delivers.
    const std::size_t want = inner_bytes + 8U;
    const std::size_t hint = std::min(want, 16U * elem.payload_bytes + (std::size_t{1} << 16U));
    const InflateResult ir = inflate_zlib(p, n, want, InflateMode::whole, scratch, hint);
    if (ir.status != InflateStatus::ok) {
      return MatError{where + "corrupt zlib stream (" + describe(ir.status) + ")"};
    }
    if (scratch.size() < want) {
      return MatError{where + "truncated: zlib stream inflates to " +
                      std::to_string(scratch.size()) + " bytes, the matrix declares " +
                      std::to_string(want)};
    }
    p = scratch.data() + 8;
    n = inner_bytes;
  }
  const Parse r = parse_matrix(p, n, swap_, false, m, problem);
  if (r != Parse::ok) {
    return MatError{where + "corrupt: " + problem};
  }
  return Status{};
}


Status MatFile::read_column_into(std::string_view name, std::size_t column,
                                 std::vector<double>& out) const {
  out.clear();
  const std::string where = name_ + ": variable '" + std::string(name) + "': ";
  std::vector<std::uint8_t> scratch;
  Matrix m;
  Status st = find_and_load(name, scratch, m);
  if (!st.ok()) {
    return st;
  }
  std::uint64_t first = 0;
  std::uint64_t count = 0;
  st = numeric_column(where, m, column, first, count);
  if (!st.ok()) {
    return st;
  }
  if (count > limits_.max_variable_bytes / sizeof(double)) {
    return MatError{where + std::to_string(count) + " elements (" + dims_text(m.dims) +
                    ") are more than the reader's budget of " +
                    std::to_string(limits_.max_variable_bytes) + " bytes as double"};
  }
  const std::size_t unit = numeric_size(m.data_type);
  out.resize(static_cast<std::size_t>(count));
  convert(m.data + first * unit, m.data_type, out.size(), swap_, out.data());
  return Status{};
}

Result<std::vector<double>> MatFile::read_column(std::string_view name, std::size_t column) const {
  std::vector<double> out;
  Status st = read_column_into(name, column, out);
  if (!st.ok()) {
    return st.error();
  }
  return out;
}

Status MatFile::find_and_load(std::string_view name, std::vector<std::uint8_t>& scratch,
                              Matrix& m) const {
  std::string_view top;
  std::string_view rest;
  split_dotted(name, top, rest);
  Element elem;
  Status st = find(top, elem);
  if (st.ok()) {
    st = load(top, elem, scratch, m);
  }
  // A struct field (`imu.acc_z`, nested `a.b.c`): the struct is loaded whole, then descended.
  std::string path(top);
  while (st.ok() && !rest.empty()) {
    const std::string_view field = next_field(rest);
    Matrix f;
    st = struct_field(m, field, swap_, name_ + ": variable '" + path + "': ", f);
    m = std::move(f);
    path += "." + std::string(field);
  }
  return st;
}

Result<double> MatFile::read_scalar(std::string_view name) const {
  const std::string where = name_ + ": variable '" + std::string(name) + "': ";
  std::vector<std::uint8_t> scratch;
  Matrix m;
  Status st = find_and_load(name, scratch, m);
  if (!st.ok()) {
    return st.error();
  }
  if (!m.has_data || m.cls == kMxChar) {
    return MatError{where + "is a " + class_name(m.cls, m.logical) + " array, not a numeric scalar"};
  }
  st = check_data(where, m, numeric_size(m.data_type));
  if (!st.ok()) {
    return st.error();
  }
  if (m.n_elems != 1U) {
    return MatError{where + "is " + dims_text(m.dims) + ", not a scalar"};
  }
  double v = 0.0;
  convert(m.data, m.data_type, 1, swap_, &v);
  return v;
}

Result<std::string> MatFile::read_string(std::string_view name) const {
  const std::string where = name_ + ": variable '" + std::string(name) + "': ";
  std::vector<std::uint8_t> scratch;
  Matrix m;
  Status st = find_and_load(name, scratch, m);
  if (!st.ok()) {
    return st.error();
  }
  if (m.cls != kMxChar) {
    return MatError{where + "is a " + class_name(m.cls, m.logical) + " array, not char"};
  }
  const std::size_t unit = char_unit_size(m.data_type);
  st = check_data(where, m, unit);
  if (!st.ok()) {
    return st.error();
  }
  std::string text;
  if (m.data_type == kMiUtf8) {
    if (m.rows <= 1U || m.data_bytes == m.n_elems) {
      const auto* c = reinterpret_cast<const char*>(m.data);  // NOLINT: bytes as text
      if (m.rows <= 1U) {
        return std::string(c, m.data_bytes);
      }
      for (std::uint64_t r = 0; r < m.rows; ++r) {
        if (r > 0U) {
          text += '\n';
        }
        for (std::uint64_t col = 0; col < m.cols; ++col) {
          text += c[col * m.rows + r];
        }
      }
      return text;
    }
    return MatError{where + "multi-row char array with non-ASCII UTF-8 is not supported"};
  }
  const std::uint64_t rows = std::max<std::uint64_t>(m.rows, 1U);
  const std::uint64_t cols = m.rows == 0U ? 0U : m.cols;
  for (std::uint64_t r = 0; r < rows && m.n_elems > 0U; ++r) {
    if (r > 0U) {
      text += '\n';
    }
    for (std::uint64_t col = 0; col < cols; ++col) {
      const std::uint64_t i = col * m.rows + r;
      auto cp = static_cast<std::uint32_t>(load_uint(m.data + i * unit, unit, swap_));
      if (unit == 1U) {
        cp &= 0xFFU;  // Latin-1
      }
      if (unit == 2U && cp >= 0xD800U && cp < 0xDC00U && col + 1U < cols) {
        const auto lo = static_cast<std::uint32_t>(
            load_uint(m.data + (i + m.rows) * unit, unit, swap_));
        if (lo >= 0xDC00U && lo < 0xE000U) {  // UTF-16 surrogate pair
          cp = 0x10000U + ((cp - 0xD800U) << 10U) + (lo - 0xDC00U);
          ++col;
        }
      }
      append_utf8(text, cp);
    }
  }
  return text;
}

Result<std::vector<VariableInfo>> list_variables(const std::string& path) {
  Result<MatFile> f = MatFile::open(path);
  if (!f.ok()) {
    return f.error();
  }
  return f.value().list_variables();
}

Result<std::vector<double>> read_column(const std::string& path, std::string_view name,
                                        std::size_t column) {
  Result<MatFile> f = MatFile::open(path);
  if (!f.ok()) {
    return f.error();
  }
  return f.value().read_column(name, column);
}

Result<double> read_scalar(const std::string& path, std::string_view name) {
  Result<MatFile> f = MatFile::open(path);
  if (!f.ok()) {
    return f.error();
  }
  return f.value().read_scalar(name);
}

Result<std::string> read_string(const std::string& path, std::string_view name) {
  Result<MatFile> f = MatFile::open(path);
  if (!f.ok()) {
    return f.error();
  }
  return f.value().read_string(name);
}

// ---- Streaming: ChannelStream, scan_variables, stream_scalar ----

namespace {

// An open file descriptor, closed with its owner.
class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  Fd(Fd&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}
  Fd& operator=(Fd&& o) noexcept {
    if (this != &o) {
      reset();
      fd_ = std::exchange(o.fd_, -1);
    }
    return *this;
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { reset(); }
  [[nodiscard]] int get() const { return fd_; }

 private:
  void reset() {
    if (fd_ >= 0) {
      static_cast<void>(::close(fd_));
      fd_ = -1;
    }
  }
  int fd_ = -1;
};

// Up to n bytes at `off` (fewer at the end of the file or on a read error: `error` set).
std::size_t pread_full(int fd, std::uint8_t* dst, std::size_t n, std::uint64_t off, bool& error) {
  std::size_t got = 0;
  while (got < n) {
    const ssize_t r = ::pread(fd, dst + got, n - got, static_cast<off_t>(off + got));
    if (r < 0 && errno == EINTR) {
      continue;
    }
    if (r <= 0) {
      error = error || r < 0;
      break;
    }
    got += static_cast<std::size_t>(r);
  }
  return got;
}

// A byte range of a file as a ByteSource (pread: no shared file position).
class FileRegion final : public ByteSource {
 public:
  FileRegion(int fd, std::uint64_t off, std::uint64_t n) : fd_(fd), off_(off), left_(n) {}
  std::size_t read(std::uint8_t* dst, std::size_t n) override {
    const auto k = static_cast<std::size_t>(std::min<std::uint64_t>(n, left_));
    if (k == 0U) {
      return 0;
    }
    const std::size_t got = pread_full(fd_, dst, k, off_, error_);
    off_ += got;
    left_ = got < k ? 0U : left_ - got;
    return got;
  }
  [[nodiscard]] bool error() const { return error_; }

 private:
  int fd_;
  std::uint64_t off_;
  std::uint64_t left_;
  bool error_ = false;
};

// Read from an InflateStream until n bytes or its end.
std::size_t read_full(InflateStream& s, std::uint8_t* dst, std::size_t n) {
  std::size_t got = 0;
  while (got < n) {
    const std::size_t k = s.read(dst + got, n - got);
    if (k == 0U) {
      break;
    }
    got += k;
  }
  return got;
}

// A top-level element found by the walk, with its header parsed and, for the data, where the
// real part starts: in the file (uncompressed) or in the inflated stream (compressed, whose
// first `peek.size()` inflated bytes are kept, the stream positioned after them).
struct Found {
  Element e;
  Matrix m;
  std::vector<std::uint8_t> peek;
  std::size_t data_at = 0;  // offset of the real part's data in peek (may equal peek.size())
  std::unique_ptr<FileRegion> src;
  std::unique_ptr<InflateStream> inf;
};

// A MAT-file on disk, walked element by element with pread (never read whole).
struct DiskFile {
  std::string name;
  Fd fd;
  std::uint64_t size = 0;
  bool swap = false;
  ReadLimits limits{};

  Status open(const std::string& path, ReadLimits lim) {
    name = path;
    limits = lim;
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
      return MatError{path + ": cannot open: " + std::strerror(errno)};
    }
    if (!S_ISREG(st.st_mode)) {
      return MatError{path + ": is " + file_kind(st.st_mode) + ", not a MAT-file"};
    }
    fd = Fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));  // NOLINT(cppcoreguidelines-pro-type-vararg)
    if (fd.get() < 0) {
      return MatError{path + ": cannot open: " + std::strerror(errno)};
    }
    size = static_cast<std::uint64_t>(st.st_size);
    // The header checks of from_memory() on the first kilobyte (the HDF5 signature may sit at
    // byte 512).
    std::vector<std::uint8_t> head(static_cast<std::size_t>(std::min<std::uint64_t>(size, 1024U)));
    bool err = false;
    head.resize(pread_full(fd.get(), head.data(), head.size(), 0, err));
    if (err) {
      return MatError{path + ": read error"};
    }
    Result<MatFile> f = MatFile::from_memory(path, head.data(), head.size(), lim);
    if (!f.ok()) {
      return f.error();
    }
    swap = f.value().big_endian();
    return Status{};
  }

  // The element at `off`: its tag (e), and for a matrix its header (m) with the bytes peeked.
  Status element(std::uint64_t off, Found& f) const {
    f = Found{};
    Element& e = f.e;
    e.offset = static_cast<std::size_t>(off);
    if (size - off < 8U) {
      return MatError{name + ": truncated: " + std::to_string(size - off) +
                      " stray bytes at offset " + std::to_string(off) + " (an element tag is 8)"};
    }
    std::array<std::uint8_t, 8> tag{};
    bool err = false;
    if (pread_full(fd.get(), tag.data(), 8, off, err) != 8U) {
      return MatError{name + ": read error at offset " + std::to_string(off)};
    }
    e.type = load_u32(tag.data(), swap);
    const std::uint64_t bytes = load_u32(tag.data() + 4, swap);
    e.payload_off = static_cast<std::size_t>(off + 8U);
    e.payload_bytes = static_cast<std::size_t>(bytes);
    const std::uint64_t avail = size - off - 8U;
    if (bytes > avail) {
      std::vector<std::uint8_t> pre(static_cast<std::size_t>(std::min<std::uint64_t>(avail, kPeekBytes)));
      pre.resize(pread_full(fd.get(), pre.data(), pre.size(), off + 8U, err));
      const std::string var = name_from_prefix(pre.data(), pre.size(), e.type, swap);
      const std::string who = var.empty() ? std::string() : "variable '" + var + "' ";
      return MatError{name + ": truncated: " + who + "element at offset " + std::to_string(off) +
                      " declares " + std::to_string(bytes) + " bytes, only " +
                      std::to_string(avail) + " remain"};
    }
    std::uint64_t padded = bytes;
    if (e.type != kMiCompressed) {
      padded += (8U - bytes % 8U) % 8U;
    }
    e.next = static_cast<std::size_t>(padded > avail ? size : off + 8U + padded);
    if (e.type == kMiMatrix) {
      return peek_plain(f);
    }
    if (e.type == kMiCompressed) {
      return peek_compressed(f);
    }
    return Status{};
  }

  Status peek_plain(Found& f) const {
    const std::string where = name + ": element at offset " + std::to_string(f.e.offset) + ": ";
    std::string problem;
    Parse r = Parse::need_more;
    for (const std::size_t cap : {kPeekBytes, kLongHeaderBytes}) {
      const std::size_t n = std::min(cap, f.e.payload_bytes);
      f.peek.resize(n);
      bool err = false;
      if (pread_full(fd.get(), f.peek.data(), n, f.e.payload_off, err) != n) {
        return MatError{name + ": read error at offset " + std::to_string(f.e.payload_off)};
      }
      // As peek_header (partial: a prefix of the payload).
      r = parse_matrix(f.peek.data(), n, swap, true, f.m, problem);
      if (r != Parse::need_more || n == f.e.payload_bytes) {
        break;
      }
    }
    if (r != Parse::ok) {
      return MatError{where + (r == Parse::need_more ? "matrix header is truncated" : problem)};
    }
    f.data_at = f.m.has_data ? static_cast<std::size_t>(f.m.data - f.peek.data()) : 0U;
    return Status{};
  }

  Status peek_compressed(Found& f) const {
    const std::string where = name + ": element at offset " + std::to_string(f.e.offset) + ": ";
    f.src = std::make_unique<FileRegion>(fd.get(), f.e.payload_off, f.e.payload_bytes);
    f.inf = std::make_unique<InflateStream>(*f.src, true);
    std::string problem;
    std::size_t cap = std::min(kPeekBytes, max_inflated_size(f.e.payload_bytes));
    f.peek.resize(cap);
    std::size_t got = read_full(*f.inf, f.peek.data(), cap);
    f.peek.resize(got);
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (got < cap && f.inf->status() != InflateStatus::ok) {
        std::string subject = where;  // name the variable if the bytes before the fault show it
        if (got >= 8U && load_u32(f.peek.data(), swap) == kMiMatrix) {
          Matrix partial_m;
          std::string ignored;
          if (parse_matrix(f.peek.data() + 8, got - 8U, swap, true, partial_m, ignored) ==
                  Parse::ok &&
              !partial_m.name.empty()) {
            subject = name + ": variable '" + partial_m.name + "': ";
          }
        }
        return MatError{subject + "corrupt zlib stream (" + describe(f.inf->status()) + ")"};
      }
      if (got < 8U) {
        return MatError{where + "compressed data holds " + std::to_string(got) +
                        " bytes, not a matrix"};
      }
      const std::uint32_t inner = load_u32(f.peek.data(), swap);
      if (inner != kMiMatrix) {
        return MatError{where + "compressed data holds a " + type_name(inner) +
                        " element, not miMATRIX"};
      }
      const std::size_t inner_bytes = load_u32(f.peek.data() + 4, swap);
      const bool partial = got - 8U < inner_bytes;
      const std::size_t view = std::min(inner_bytes, got - 8U);
      const Parse r = parse_matrix(f.peek.data() + 8, view, swap, partial, f.m, problem);
      if (r == Parse::ok) {
        f.data_at = f.m.has_data ? static_cast<std::size_t>(f.m.data - f.peek.data()) : 0U;
        return Status{};
      }
      if (r == Parse::corrupt || attempt == 1 || got < cap) {
        return MatError{where + (r == Parse::need_more ? "matrix header is truncated" : problem)};
      }
      // A header longer than the peek: kLongHeaderBytes at most.
      const std::size_t more = std::min(kLongHeaderBytes, max_inflated_size(f.e.payload_bytes));
      f.peek.resize(more);
      got += read_full(*f.inf, f.peek.data() + got, more - got);
      f.peek.resize(got);
      cap = more;
    }
    return MatError{where + "matrix header is truncated"};
  }
};

constexpr std::size_t kConvertBytes = std::size_t{1} << 16U;

}  // namespace

struct ChannelStream::Impl {
  DiskFile file;
  Found f;
  VariableInfo info;
  std::string where;
  std::size_t unit = 0;
  std::uint64_t count = 0;         // samples of the column
  std::uint64_t delivered = 0;     // samples handed out
  std::uint64_t skip_bytes = 0;    // bytes of the columns before this one, not yet skipped
  std::size_t peek_pos = 0;        // next unread byte of f.peek (data bytes)
  std::uint64_t inner_bytes = 0;   // compressed: declared miMATRIX payload size
  std::uint64_t file_pos = 0;      // uncompressed: file offset of the next data byte
  bool checked = false;
  std::vector<std::uint8_t> buf;

  // n data bytes into dst, in order: what the peek holds after the header, then the stream.
  Status pull(std::uint8_t* dst, std::size_t n) {
    std::size_t got = 0;
    if (peek_pos < f.peek.size()) {
      got = std::min(n, f.peek.size() - peek_pos);
      std::memcpy(dst, f.peek.data() + peek_pos, got);
      peek_pos += got;
    }
    if (got == n) {
      return Status{};
    }
    if (f.inf) {
      got += read_full(*f.inf, dst + got, n - got);
      if (got < n) {
        return stream_error();
      }
      return Status{};
    }
    bool err = false;
    const std::size_t k = pread_full(file.fd.get(), dst + got, n - got, file_pos, err);
    file_pos += k;
    if (got + k < n) {
      return MatError{where + (err ? "read error" : "truncated: the file ended inside the data")};
    }
    return Status{};
  }

  // Moves f to the file's top-level variable `top`; the error lists the variables seen.
  Status find_variable(const std::string& path, std::string_view top) {
    std::string seen;
    std::uint64_t off = kHeaderBytes;
    while (off < file.size) {
      Status st = file.element(off, f);
      if (!st.ok()) {
        return st;
      }
      if ((f.e.type == kMiMatrix || f.e.type == kMiCompressed) && !f.m.name.empty()) {
        if (f.m.name == top) {
          return Status{};
        }
        seen += (seen.empty() ? "" : ", ") + f.m.name;
      }
      off = f.e.next;
    }
    return MatError{path + ": variable '" + std::string(top) + "' not found; variables: " +
                    (seen.empty() ? std::string("(none)") : seen)};
  }

  // The stream reads `column` of the numeric matrix f.m (numeric_column): count, unit and the
  // bytes skipped before it.
  Status select_column(std::size_t column) {
    std::uint64_t first = 0;
    Status st = numeric_column(where, f.m, column, first, count);
    if (!st.ok()) {
      return st;
    }
    unit = numeric_size(f.m.data_type);
    skip_bytes = first * unit;
    return Status{};
  }

  Status stream_error() const {
    if (f.src->error()) {
      return MatError{where + "read error"};
    }
    if (f.inf->status() != InflateStatus::ok) {
      return MatError{where + "corrupt zlib stream (" + describe(f.inf->status()) + ")"};
    }
    return MatError{where + "truncated: zlib stream inflates to " +
                    std::to_string(f.inf->total_out()) + " bytes, the matrix declares " +
                    std::to_string(inner_bytes + 8U)};
  }

  Status skip(std::uint64_t n) {
    while (n > 0U) {
      const auto k = static_cast<std::size_t>(std::min<std::uint64_t>(n, buf.size()));
      Status st = pull(buf.data(), k);
      if (!st.ok()) {
        return st;
      }
      n -= k;
    }
    return Status{};
  }

  // One whole sub-element (tag and padded data) appended to `out`: at most `cap` data bytes.
  Status pull_sub(std::vector<std::uint8_t>& out, std::size_t cap, const char* what) {
    const std::size_t at = out.size();
    out.resize(at + 8U);
    Status st = pull(out.data() + at, 8U);
    if (!st.ok()) {
      return st;
    }
    const std::uint32_t w0 = load_u32(out.data() + at, file.swap);
    if ((w0 >> 16U) != 0U) {
      return Status{};  // small data element: tag and data in 8 bytes
    }
    const std::size_t bytes = load_u32(out.data() + at + 4U, file.swap);
    if (bytes > cap) {
      return MatError{where + "corrupt: " + what + " declare " + std::to_string(bytes) + " bytes"};
    }
    out.resize(at + 8U + bytes + (8U - bytes % 8U) % 8U);
    return pull(out.data() + at + 8U, out.size() - at - 8U);
  }

  // Descend from the struct f.m, positioned after its name, into its field `field`: the
  // fields before it are skipped (inflated and dropped), the field's header is parsed and the
  // stream left at its real part. f.peek becomes the field's header followed by what was left
  // unread of the old peek, so that pull() keeps the byte order.
  Status descend(std::string_view field, const std::string& at) {
    Status st = check_struct(f.m, field, at);
    if (!st.ok()) {
      return st;
    }
    std::vector<std::uint8_t> head;
    if (!(st = pull_sub(head, 8U, "the field-name length")).ok() ||
        !(st = pull_sub(head, kLongHeaderBytes, "the field names")).ok()) {
      return st;
    }
    std::vector<std::string> names;
    std::size_t unused = 0;
    std::string problem;
    if (struct_field_names(head.data(), head.size(), 0, file.swap, names, unused, problem) !=
        Parse::ok) {
      return MatError{at + "corrupt: " + problem};
    }
    for (const auto& name : names) {
      std::array<std::uint8_t, 8> tag{};
      if (!(st = pull(tag.data(), tag.size())).ok()) {
        return st;
      }
      if (load_u32(tag.data(), file.swap) != kMiMatrix) {
        return field_error(at, name, "not a miMATRIX element", true);
      }
      const std::uint64_t bytes = load_u32(tag.data() + 4, file.swap);
      if (name != field) {
        if (!(st = skip(bytes + (8U - bytes % 8U) % 8U)).ok()) {
          return st;
        }
        continue;
      }
      std::vector<std::uint8_t> hdr(static_cast<std::size_t>(
          std::min<std::uint64_t>(bytes, kLongHeaderBytes)));
      if (!(st = pull(hdr.data(), hdr.size())).ok()) {
        return st;
      }
      Matrix fm;
      const Parse r = parse_matrix(hdr.data(), hdr.size(), file.swap, hdr.size() < bytes, fm,
                                   problem);
      if (r != Parse::ok) {
        return field_error(at, name, r == Parse::need_more ? "matrix header is truncated" : problem,
                           false);
      }
      fm.name = name;
      const std::size_t resume = fm.has_data ? static_cast<std::size_t>(fm.data - hdr.data())
                                             : fm.header_end;
      hdr.insert(hdr.end(), f.peek.begin() + static_cast<std::ptrdiff_t>(peek_pos), f.peek.end());
      // fm's pointers stay valid: inserting may move hdr's bytes, so they are re-based.
      fm.payload = hdr.data();
      fm.data = fm.has_data ? hdr.data() + resume : nullptr;
      fm.payload_bytes = hdr.size();
      f.peek = std::move(hdr);
      f.m = std::move(fm);
      peek_pos = resume;
      f.data_at = resume;
      return Status{};
    }
    return MatError{at + "field '" + std::string(field) + "' not found; fields: " +
                    join_names(names)};
  }

  // After the last sample: a compressed variable is inflated to its end (the columns after
  // this one, padding) and checked: no more than the declared size, Adler-32.
  Status finish() {
    checked = true;
    if (!f.inf) {
      return Status{};
    }
    const std::uint64_t want = inner_bytes + 8U;
    while (f.inf->total_out() <= want && f.inf->read(buf.data(), buf.size()) > 0U) {
    }
    if (f.inf->total_out() > want) {  // (the peek may have read past the end already)
      return MatError{where + "corrupt zlib stream (" + describe(InflateStatus::output_limit) +
                      ")"};
    }
    if (f.inf->status() != InflateStatus::ok || f.src->error()) {
      return stream_error();
    }
    if (f.inf->total_out() < want) {
      return stream_error();
    }
    return Status{};
  }
};

ChannelStream::ChannelStream(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ChannelStream::ChannelStream(ChannelStream&& other) noexcept = default;
ChannelStream& ChannelStream::operator=(ChannelStream&& other) noexcept = default;
ChannelStream::~ChannelStream() = default;
std::uint64_t ChannelStream::size() const { return impl_->count; }
const VariableInfo& ChannelStream::info() const { return impl_->info; }

namespace {

VariableInfo info_of(const Found& f) {
  VariableInfo v;
  v.name = f.m.name;
  v.class_name = class_name(f.m.cls, f.m.logical);
  v.rows = f.m.rows;
  v.cols = f.m.cols;
  v.n_dims = static_cast<std::uint32_t>(f.m.dims.size());
  v.complex = f.m.complex;
  v.compressed = f.e.type == kMiCompressed;
  v.file_offset = f.e.offset;
  v.file_bytes = f.e.next - f.e.offset;
  return v;
}

}  // namespace

Result<ChannelStream> ChannelStream::open(const std::string& path, std::string_view name,
                                          std::size_t column, ReadLimits limits) {
  auto impl = std::make_unique<Impl>();
  Impl& s = *impl;
  Status st = s.file.open(path, limits);
  if (!st.ok()) {
    return st.error();
  }
  std::string_view top;
  std::string_view rest;
  split_dotted(name, top, rest);
  st = s.find_variable(path, top);
  if (!st.ok()) {
    return st.error();
  }
  s.where = path + ": variable '" + std::string(name) + "': ";
  const std::string& where = s.where;
  if (s.f.e.type == kMiCompressed) {
    s.inner_bytes = load_u32(s.f.peek.data() + 4, s.file.swap);
    const std::size_t limit = max_inflated_size(s.f.e.payload_bytes);
    if (s.inner_bytes > limit - 8U) {
      return MatError{where + "corrupt: declares " + std::to_string(s.inner_bytes) +
                      " bytes, more than " + std::to_string(s.f.e.payload_bytes) +
                      " compressed bytes can hold"};
    }
    if (s.inner_bytes > limits.max_stream_variable_bytes) {
      return MatError{where + "declares " + std::to_string(s.inner_bytes) +
                      " bytes inflated, more than the reader's budget of " +
                      std::to_string(limits.max_stream_variable_bytes) + " bytes per variable"};
    }
  }
  s.buf.resize(kConvertBytes);
  if (!s.f.inf) {
    // Uncompressed: the data follow in the file; the peek holds their first bytes.
    s.file_pos = s.f.e.payload_off + s.f.peek.size();
  }
  s.peek_pos = s.f.data_at;
  // A struct field (`imu.acc_z`, nested `a.b.c`): descended in the stream, constant memory.
  std::string at(top);
  while (!rest.empty()) {
    if (s.f.m.cls == kMxStruct) {
      s.peek_pos = static_cast<std::size_t>(s.f.m.payload + s.f.m.header_end - s.f.peek.data());
    }
    const std::string_view field = next_field(rest);
    std::string where_at = path;
    where_at += ": variable '";
    where_at += at;
    where_at += "': ";
    st = s.descend(field, where_at);
    if (!st.ok()) {
      return st.error();
    }
    at += "." + std::string(field);
  }
  st = s.select_column(column);
  if (!st.ok()) {
    return st.error();
  }
  s.info = info_of(s.f);
  s.info.name = std::string(name);
  return ChannelStream(std::move(impl));
}

Result<std::size_t> ChannelStream::read(double* out, std::size_t n) {
  Impl& s = *impl_;
  if (s.skip_bytes > 0U) {
    Status st = s.skip(s.skip_bytes);
    if (!st.ok()) {
      return st.error();
    }
    s.skip_bytes = 0;
  }
  std::size_t done = 0;
  while (done < n && s.delivered < s.count) {
    const auto k = static_cast<std::size_t>(std::min<std::uint64_t>(
        {static_cast<std::uint64_t>(n - done), s.count - s.delivered, s.buf.size() / s.unit}));
    if (s.f.m.data_type == kMiDouble && !s.file.swap && host_little_endian()) {
      // The file's bytes are host doubles: inflate (or read) them straight into `out`.
      Status st = s.pull(static_cast<std::uint8_t*>(static_cast<void*>(out + done)), k * s.unit);
      if (!st.ok()) {
        return st.error();
      }
    } else {
      Status st = s.pull(s.buf.data(), k * s.unit);
      if (!st.ok()) {
        return st.error();
      }
      convert(s.buf.data(), s.f.m.data_type, k, s.file.swap, out + done);
    }
    done += k;
    s.delivered += k;
  }
  if (s.delivered == s.count && !s.checked && done < n) {
    // The caller asked past the end: check the rest of the variable before saying "end".
    Status st = s.finish();
    if (!st.ok()) {
      return st.error();
    }
  }
  return done;
}

Result<std::vector<VariableInfo>> scan_variables(const std::string& path, ReadLimits limits) {
  DiskFile file;
  Status st = file.open(path, limits);
  if (!st.ok()) {
    return st.error();
  }
  std::vector<VariableInfo> vars;
  std::uint64_t off = kHeaderBytes;
  Found f;
  while (off < file.size) {
    st = file.element(off, f);
    if (!st.ok()) {
      return st.error();
    }
    if ((f.e.type == kMiMatrix || f.e.type == kMiCompressed) && !f.m.name.empty()) {
      vars.push_back(info_of(f));
    }
    off = f.e.next;
  }
  return vars;
}

Result<double> stream_scalar(const std::string& path, std::string_view name, ReadLimits limits) {
  Result<ChannelStream> cs = ChannelStream::open(path, name, 0, limits);
  if (!cs.ok()) {
    return cs.error();
  }
  ChannelStream& s = cs.value();
  if (s.size() != 1U) {
    return MatError{path + ": variable '" + std::string(name) + "': is " +
                    std::to_string(s.info().rows) + "x" + std::to_string(s.info().cols) +
                    ", not a scalar"};
  }
  std::array<double, 2> v{};
  Result<std::size_t> r = s.read(v.data(), v.size());  // 2: asks past the end, so it is checked
  if (!r.ok()) {
    return r.error();
  }
  return v[0];
}

}  // namespace imu::mat

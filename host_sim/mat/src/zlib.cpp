// RFC 1951 / RFC 1950 decoder and stored-block encoder. See imu/mat/zlib.hpp for the contract.
#include "imu/mat/zlib.hpp"

#include <algorithm>
#include <array>
#include <cstring>

namespace imu::mat {
namespace {

// The n low bits of code in reverse order (Huffman codes are stored MSB first, read LSB first).
std::uint32_t reverse_bits(std::uint32_t code, unsigned n) {
  std::uint32_t r = 0;
  for (unsigned i = 0; i < n; ++i) {
    r |= ((code >> i) & 1U) << (n - 1U - i);
  }
  return r;
}

// zlib header: CM = 8, CINFO = 7 (32 KiB window); FLEVEL = 0, no dictionary (0x7801 % 31 == 0).
void append_zlib_header(std::vector<std::uint8_t>& z) {
  z.push_back(0x78U);
  z.push_back(0x01U);
}

// zlib trailer: Adler-32 of the uncompressed data, big-endian.
void append_adler32(std::vector<std::uint8_t>& z, const std::uint8_t* data, std::size_t size) {
  const std::uint32_t a = adler32(data, size);
  for (int shift = 24; shift >= 0; shift -= 8) {
    z.push_back(static_cast<std::uint8_t>((a >> static_cast<unsigned>(shift)) & 0xFFU));
  }
}

constexpr unsigned kMaxBits = 15U;   // longest deflate code
constexpr unsigned kFastBits = 10U;  // first-level table index width
constexpr std::size_t kFastSize = std::size_t{1} << kFastBits;
constexpr std::size_t kMaxLitLen = 288U;
constexpr std::size_t kMaxDist = 32U;

// Length symbols 257..285: base length and extra bits (RFC 1951 3.2.5).
constexpr std::array<std::uint16_t, 29> kLenBase = {3,  4,  5,  6,  7,  8,  9,  10, 11, 13,
                                                    15, 17, 19, 23, 27, 31, 35, 43, 51, 59,
                                                    67, 83, 99, 115, 131, 163, 195, 227, 258};
constexpr std::array<std::uint8_t, 29> kLenExtra = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                                    2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
constexpr std::array<std::uint16_t, 30> kDistBase = {
    1,   2,   3,   4,   5,   7,    9,    13,   17,   25,   33,   49,   65,    97,    129,
    193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
constexpr std::array<std::uint8_t, 30> kDistExtra = {0, 0, 0, 0, 1, 1, 2,  2,  3,  3,
                                                     4, 4, 5, 5, 6, 6, 7,  7,  8,  8,
                                                     9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
// Order of the code length code lengths (RFC 1951 3.2.7).
constexpr std::array<std::uint8_t, 19> kClOrder = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                                   11, 4,  12, 3, 13, 2, 14, 1, 15};

// Canonical Huffman code with a first-level lookup table.
// fast[i] = symbol << 4 | length for codes of length <= kFastBits whose bit-reversed code is the
// low bits of i; 0 means "longer code or not a code": use the canonical slow path.
struct Huffman {
  std::array<std::uint16_t, kFastSize> fast{};
  std::array<std::uint16_t, kMaxBits + 1> count{};
  std::array<std::uint16_t, kMaxLitLen> symbol{};
};

// Build from code lengths. Rejects over-subscribed sets and incomplete sets of more than one code.
[[nodiscard]] bool build(Huffman& h, const std::uint8_t* lengths, std::size_t n) {
  h.count.fill(0);
  for (std::size_t s = 0; s < n; ++s) {
    ++h.count[lengths[s]];
  }
  const std::size_t n_codes = n - h.count[0];
  int left = 1;
  for (unsigned len = 1; len <= kMaxBits; ++len) {
    left *= 2;
    left -= h.count[len];
    if (left < 0) {
      return false;  // over-subscribed
    }
  }
  if (left > 0 && n_codes > 1U) {
    return false;  // incomplete: only a single code (or none) may leave the set incomplete
  }
  std::array<std::uint16_t, kMaxBits + 2> offs{};
  for (unsigned len = 1; len <= kMaxBits; ++len) {
    offs[len + 1] = static_cast<std::uint16_t>(offs[len] + h.count[len]);
  }
  for (std::size_t s = 0; s < n; ++s) {
    if (lengths[s] != 0U) {
      h.symbol[offs[lengths[s]]++] = static_cast<std::uint16_t>(s);
    }
  }
  // Canonical codes, then the bit-reversed fast table.
  h.fast.fill(0);
  std::array<unsigned, kMaxBits + 1> next{};
  unsigned code = 0;
  for (unsigned len = 1; len <= kMaxBits; ++len) {
    code = (code + (len == 1U ? 0U : h.count[len - 1U])) << 1U;  // count[0]: unused symbols
    next[len] = code;
  }
  next[0] = 0;
  for (std::size_t s = 0; s < n; ++s) {
    const unsigned len = lengths[s];
    if (len == 0U) {
      continue;
    }
    const unsigned c = next[len]++;
    if (len > kFastBits) {
      continue;
    }
    const std::uint32_t rev = reverse_bits(c, len);
    const auto entry = static_cast<std::uint16_t>((s << 4U) | len);
    for (std::size_t i = rev; i < kFastSize; i += std::size_t{1} << len) {
      h.fast[i] = entry;
    }
  }
  return true;
}

class Inflater {
 public:
  Inflater(const std::uint8_t* in, std::size_t in_size, std::size_t max_out, InflateMode mode,
           std::vector<std::uint8_t>& out, std::size_t size_hint)
      : in_(in), in_size_(in_size), max_out_(max_out), mode_(mode), out_(out) {
    out_.clear();
    cap_ = std::min(max_out_, std::max<std::size_t>(size_hint, 1U << 16U));
    out_.resize(cap_);
  }

  // Decode blocks until the final one. Returns ok or the first error.
  [[nodiscard]] InflateStatus run() {
    bool last = false;
    while (!last && !full_) {
      if (!need(3)) {
        return InflateStatus::truncated_input;
      }
      last = bits(1) != 0U;
      const unsigned type = bits(2);
      InflateStatus st = InflateStatus::ok;
      switch (type) {
        case 0:
          st = stored();
          break;
        case 1:
          st = fixed();
          break;
        case 2:
          st = dynamic();
          break;
        default:
          st = InflateStatus::bad_block_type;
          break;
      }
      if (st != InflateStatus::ok) {
        return st;
      }
    }
    return InflateStatus::ok;
  }

  // Drop the bits of a partial byte; return the index of the next unread input byte.
  std::size_t align_and_position() {
    drop(bitcnt_ % 8U);
    return pos_ - bitcnt_ / 8U;
  }

  void finish() { out_.resize(n_out_); }
  [[nodiscard]] std::size_t produced() const { return n_out_; }
  [[nodiscard]] bool full() const { return full_; }

 private:
  void refill() {
    if (in_size_ - pos_ >= 8U) {
      // Fast path: one 8-byte little-endian load; take the whole bytes that fit in the buffer.
      std::uint64_t w = 0;
      for (unsigned i = 8; i-- > 0U;) {
        w = (w << 8U) | in_[pos_ + i];
      }
      bitbuf_ |= w << bitcnt_;
      pos_ += (63U - bitcnt_) >> 3U;
      bitcnt_ |= 56U;  // bitcnt_ + 8 * ((63 - bitcnt_) / 8) for bitcnt_ < 64
      return;
    }
    while (bitcnt_ <= 56U && pos_ < in_size_) {
      bitbuf_ |= static_cast<std::uint64_t>(in_[pos_++]) << bitcnt_;
      bitcnt_ += 8U;
    }
  }
  [[nodiscard]] bool need(unsigned n) {
    if (bitcnt_ < n) {
      refill();
    }
    return bitcnt_ >= n;
  }
  // Precondition: need(n) returned true, n <= 32.
  unsigned bits(unsigned n) {
    const auto v = static_cast<unsigned>(bitbuf_ & ((std::uint64_t{1} << n) - 1U));
    drop(n);
    return v;
  }
  void drop(unsigned n) {
    bitbuf_ >>= n;
    bitcnt_ -= n;
  }

  // Decode one symbol; -1 truncated, -2 not a code.
  int decode(const Huffman& h) {
    if (bitcnt_ < kMaxBits) {
      refill();
    }
    const std::uint16_t e = h.fast[bitbuf_ & (kFastSize - 1U)];
    if (e != 0U) {
      const unsigned len = e & 15U;
      if (len > bitcnt_) {
        return -1;
      }
      drop(len);
      return e >> 4U;
    }
    // Canonical slow path (codes longer than kFastBits, or invalid codes).
    int code = 0;
    int first = 0;
    int index = 0;
    for (unsigned len = 1; len <= kMaxBits; ++len) {
      if (len > bitcnt_) {
        return -1;
      }
      code |= static_cast<int>((bitbuf_ >> (len - 1U)) & 1U);
      const int count = h.count[len];
      if (code - count < first) {
        drop(len);
        const int k = index + (code - first);  // first <= code < first + count
        return h.symbol[static_cast<std::size_t>(k)];
      }
      index += count;
      first += count;
      first <<= 1;
      code <<= 1;
    }
    return -2;
  }

  // Make room for n more output bytes. Returns false if that passes max_out (then, in prefix
  // mode, fills what fits and marks the output full).
  [[nodiscard]] bool room(std::size_t n) {
    if (n <= cap_ - n_out_) {
      return true;
    }
    if (n <= max_out_ - n_out_) {
      // Geometric growth, never past max_out (n_out_ + n <= max_out_ here).
      const std::size_t doubled = cap_ > max_out_ / 2U ? max_out_ : cap_ * 2U;
      cap_ = std::max(doubled, n_out_ + n);
      out_.resize(cap_);
      return true;
    }
    if (cap_ < max_out_) {
      cap_ = max_out_;
      out_.resize(cap_);
    }
    return false;
  }

  InflateStatus stored() {
    const std::size_t p = align_and_position();
    pos_ = p;
    bitbuf_ = 0;
    bitcnt_ = 0;
    if (in_size_ - pos_ < 4U) {
      return InflateStatus::truncated_input;
    }
    const unsigned len = in_[pos_] | (static_cast<unsigned>(in_[pos_ + 1U]) << 8U);
    const unsigned nlen = in_[pos_ + 2U] | (static_cast<unsigned>(in_[pos_ + 3U]) << 8U);
    pos_ += 4U;
    if (len != (~nlen & 0xFFFFU)) {
      return InflateStatus::bad_stored_length;
    }
    if (in_size_ - pos_ < len) {
      return InflateStatus::truncated_input;
    }
    std::size_t n = len;
    if (!room(n)) {
      if (mode_ == InflateMode::whole) {
        return InflateStatus::output_limit;
      }
      n = cap_ - n_out_;
      full_ = true;
    }
    if (n > 0U) {
      std::memcpy(out_.data() + n_out_, in_ + pos_, n);
    }
    n_out_ += n;
    pos_ += len;
    return InflateStatus::ok;
  }

  InflateStatus fixed() {
    if (!fixed_built_) {
      std::array<std::uint8_t, kMaxLitLen> l{};
      std::fill(l.begin(), l.begin() + 144, std::uint8_t{8});
      std::fill(l.begin() + 144, l.begin() + 256, std::uint8_t{9});
      std::fill(l.begin() + 256, l.begin() + 280, std::uint8_t{7});
      std::fill(l.begin() + 280, l.end(), std::uint8_t{8});
      std::array<std::uint8_t, kMaxDist> d{};
      d.fill(5);
      // The fixed sets are complete or (distance: 32 codes of 5 bits) exactly full.
      static_cast<void>(build(fixed_lit_, l.data(), l.size()));
      static_cast<void>(build(fixed_dist_, d.data(), d.size()));
      fixed_built_ = true;
    }
    return codes(fixed_lit_, fixed_dist_);
  }

  InflateStatus dynamic() {
    if (!need(14)) {
      return InflateStatus::truncated_input;
    }
    const unsigned nlen = bits(5) + 257U;
    const unsigned ndist = bits(5) + 1U;
    const unsigned ncode = bits(4) + 4U;
    if (nlen > 286U || ndist > 30U) {
      return InflateStatus::bad_code_lengths;
    }
    std::array<std::uint8_t, 19> cl{};
    for (unsigned i = 0; i < ncode; ++i) {
      if (!need(3)) {
        return InflateStatus::truncated_input;
      }
      cl[kClOrder[i]] = static_cast<std::uint8_t>(bits(3));
    }
    if (!build(lit_, cl.data(), cl.size())) {
      return InflateStatus::bad_code_lengths;
    }
    std::array<std::uint8_t, kMaxLitLen + kMaxDist> lengths{};
    unsigned index = 0;
    while (index < nlen + ndist) {
      const int sym = decode(lit_);
      if (sym < 0) {
        return sym == -1 ? InflateStatus::truncated_input : InflateStatus::bad_code_lengths;
      }
      if (sym < 16) {
        lengths[index++] = static_cast<std::uint8_t>(sym);
        continue;
      }
      std::uint8_t value = 0;
      unsigned repeat = 0;
      if (sym == 16) {
        if (index == 0U) {
          return InflateStatus::bad_code_lengths;  // nothing to repeat
        }
        value = lengths[index - 1U];
        if (!need(2)) {
          return InflateStatus::truncated_input;
        }
        repeat = 3U + bits(2);
      } else if (sym == 17) {
        if (!need(3)) {
          return InflateStatus::truncated_input;
        }
        repeat = 3U + bits(3);
      } else {
        if (!need(7)) {
          return InflateStatus::truncated_input;
        }
        repeat = 11U + bits(7);
      }
      if (index + repeat > nlen + ndist) {
        return InflateStatus::bad_code_lengths;
      }
      while (repeat-- > 0U) {
        lengths[index++] = value;
      }
    }
    if (lengths[256] == 0U) {
      return InflateStatus::bad_code_lengths;  // no end-of-block code
    }
    if (!build(lit_, lengths.data(), nlen) || !build(dist_, lengths.data() + nlen, ndist)) {
      return InflateStatus::bad_code_lengths;
    }
    return codes(lit_, dist_);
  }

  InflateStatus codes(const Huffman& lit, const Huffman& dist) {
    std::uint8_t* out = out_.data();
    for (;;) {
      int sym = decode(lit);
      if (sym < 0) {
        return sym == -1 ? InflateStatus::truncated_input : InflateStatus::bad_symbol;
      }
      if (sym < 256) {
        if (n_out_ == cap_) {
          if (!room(1)) {
            if (mode_ == InflateMode::whole) {
              return InflateStatus::output_limit;
            }
            full_ = true;
            return InflateStatus::ok;
          }
          out = out_.data();
        }
        out[n_out_++] = static_cast<std::uint8_t>(sym);
        continue;
      }
      if (sym == 256) {
        return InflateStatus::ok;
      }
      sym -= 257;
      if (sym >= 29) {
        return InflateStatus::bad_symbol;
      }
      const auto ls = static_cast<std::size_t>(sym);
      if (!need(kLenExtra[ls])) {
        return InflateStatus::truncated_input;
      }
      std::size_t len = kLenBase[ls] + bits(kLenExtra[ls]);
      const int dsym = decode(dist);
      if (dsym < 0) {
        return dsym == -1 ? InflateStatus::truncated_input : InflateStatus::bad_symbol;
      }
      if (dsym >= 30) {
        return InflateStatus::bad_symbol;
      }
      const auto ds = static_cast<std::size_t>(dsym);
      if (!need(kDistExtra[ds])) {
        return InflateStatus::truncated_input;
      }
      const std::size_t d = kDistBase[ds] + bits(kDistExtra[ds]);
      if (d > n_out_) {
        return InflateStatus::bad_distance;
      }
      if (!room(len)) {
        if (mode_ == InflateMode::whole) {
          return InflateStatus::output_limit;
        }
        len = cap_ - n_out_;
        full_ = true;
      }
      out = out_.data();
      std::uint8_t* dst = out + n_out_;
      const std::uint8_t* src = dst - d;
      if (d >= len) {
        std::memcpy(dst, src, len);
      } else if (d >= 8U) {
        // Overlapping, but each 8-byte chunk reads bytes already written (d >= 8).
        std::size_t i = 0;
        for (; i + 8U <= len; i += 8U) {
          std::memcpy(dst + i, src + i, 8);
        }
        for (; i < len; ++i) {
          dst[i] = src[i];
        }
      } else {
        for (std::size_t i = 0; i < len; ++i) {
          dst[i] = src[i];  // overlapping copy repeats the last d bytes
        }
      }
      n_out_ += len;
      if (full_) {
        return InflateStatus::ok;
      }
    }
  }

  const std::uint8_t* in_;
  std::size_t in_size_;
  std::size_t pos_ = 0;
  std::uint64_t bitbuf_ = 0;
  unsigned bitcnt_ = 0;
  std::size_t max_out_;
  InflateMode mode_;
  std::vector<std::uint8_t>& out_;
  std::size_t cap_ = 0;
  std::size_t n_out_ = 0;
  bool full_ = false;
  bool fixed_built_ = false;
  Huffman lit_{};
  Huffman dist_{};
  Huffman fixed_lit_{};
  Huffman fixed_dist_{};
};

}  // namespace

const char* describe(InflateStatus status) {
  switch (status) {
    case InflateStatus::ok:
      return "ok";
    case InflateStatus::truncated_input:
      return "stream ends early";
    case InflateStatus::bad_zlib_header:
      return "bad zlib header";
    case InflateStatus::preset_dictionary:
      return "preset dictionary not supported";
    case InflateStatus::bad_block_type:
      return "invalid block type";
    case InflateStatus::bad_stored_length:
      return "stored block length check failed";
    case InflateStatus::bad_code_lengths:
      return "invalid Huffman code lengths";
    case InflateStatus::bad_symbol:
      return "invalid Huffman code";
    case InflateStatus::bad_distance:
      return "distance too far back";
    case InflateStatus::output_limit:
      return "inflates beyond the declared size";
    case InflateStatus::adler_mismatch:
      return "Adler-32 check failed";
  }
  return "unknown inflate status";
}

std::uint32_t adler32(const std::uint8_t* data, std::size_t size, std::uint32_t adler) {
  // Per block of n bytes: a' = a + sum d[i], b' = b + n a + sum (n - i) d[i]. The two sums have
  // no loop-carried dependency on a or b, so the compiler can vectorise them. n <= 5552 keeps
  // the 32-bit weighted sum from overflowing: 255 n (n + 1) / 2 < 2^32.
  constexpr std::uint32_t kMod = 65521U;
  constexpr std::uint32_t kBlock = 5552U;
  std::uint32_t a = adler & 0xFFFFU;
  std::uint32_t b = adler >> 16U;
  while (size > 0U) {
    const auto n = static_cast<std::uint32_t>(std::min<std::size_t>(size, kBlock));
    std::uint32_t s1 = 0;
    std::uint32_t s2 = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
      s1 += data[i];
      s2 += (n - i) * data[i];
    }
    b = static_cast<std::uint32_t>((b + static_cast<std::uint64_t>(n) * a + s2) % kMod);
    a = (a + s1) % kMod;
    data += n;
    size -= n;
  }
  return (b << 16U) | a;
}

InflateResult inflate_raw(const std::uint8_t* in, std::size_t in_size, std::size_t max_out,
                          InflateMode mode, std::vector<std::uint8_t>& out, std::size_t size_hint) {
  Inflater inf(in, in_size, max_out, mode, out, size_hint);
  const InflateStatus st = inf.run();
  const std::size_t used = inf.align_and_position();
  inf.finish();
  return InflateResult{st, used};
}

InflateResult inflate_zlib(const std::uint8_t* in, std::size_t in_size, std::size_t max_out,
                           InflateMode mode, std::vector<std::uint8_t>& out, std::size_t size_hint) {
  out.clear();
  if (in_size < 2U) {
    return InflateResult{InflateStatus::truncated_input, in_size};
  }
  const unsigned cmf = in[0];
  const unsigned flg = in[1];
  if ((cmf & 0x0FU) != 8U || (cmf >> 4U) > 7U || ((cmf << 8U) | flg) % 31U != 0U) {
    return InflateResult{InflateStatus::bad_zlib_header, 0};
  }
  if ((flg & 0x20U) != 0U) {
    return InflateResult{InflateStatus::preset_dictionary, 0};
  }
  Inflater inf(in + 2, in_size - 2U, max_out, mode, out, size_hint);
  const InflateStatus st = inf.run();
  const std::size_t used = 2U + inf.align_and_position();
  const bool stopped_early = inf.full();
  inf.finish();
  if (st != InflateStatus::ok) {
    return InflateResult{st, used};
  }
  if (stopped_early) {
    return InflateResult{InflateStatus::ok, used};  // prefix: no trailer to check yet
  }
  if (in_size - used < 4U) {
    return InflateResult{InflateStatus::truncated_input, in_size};
  }
  const std::uint32_t want = (static_cast<std::uint32_t>(in[used]) << 24U) |
                             (static_cast<std::uint32_t>(in[used + 1U]) << 16U) |
                             (static_cast<std::uint32_t>(in[used + 2U]) << 8U) |
                             static_cast<std::uint32_t>(in[used + 3U]);
  if (adler32(out.data(), out.size()) != want) {
    return InflateResult{InflateStatus::adler_mismatch, used + 4U};
  }
  return InflateResult{InflateStatus::ok, used + 4U};
}

std::vector<std::uint8_t> zlib_store(const std::uint8_t* data, std::size_t size) {
  constexpr std::size_t kMaxStored = 65535U;
  std::vector<std::uint8_t> z;
  z.reserve(size + 6U + 5U * (size / kMaxStored + 1U));
  append_zlib_header(z);
  std::size_t done = 0;
  do {
    const std::size_t n = std::min(kMaxStored, size - done);
    const bool last = done + n == size;
    z.push_back(last ? 1U : 0U);  // BFINAL, BTYPE = 00, padded to the byte
    const auto len = static_cast<unsigned>(n);
    const unsigned nlen = ~len & 0xFFFFU;
    z.push_back(static_cast<std::uint8_t>(len & 0xFFU));
    z.push_back(static_cast<std::uint8_t>(len >> 8U));
    z.push_back(static_cast<std::uint8_t>(nlen & 0xFFU));
    z.push_back(static_cast<std::uint8_t>(nlen >> 8U));
    z.insert(z.end(), data + done, data + done + n);
    done += n;
  } while (done < size);
  append_adler32(z, data, size);
  return z;
}

namespace {

// Deflate bit output: fields LSB first; Huffman codes are passed already bit-reversed.
class BitSink {
 public:
  explicit BitSink(std::vector<std::uint8_t>& out) : out_(out) {}
  void put(std::uint32_t value, unsigned n) {
    buf_ |= static_cast<std::uint64_t>(value) << cnt_;
    cnt_ += n;
    while (cnt_ >= 8U) {
      out_.push_back(static_cast<std::uint8_t>(buf_ & 0xFFU));
      buf_ >>= 8U;
      cnt_ -= 8U;
    }
  }
  void flush() {
    if (cnt_ > 0U) {
      out_.push_back(static_cast<std::uint8_t>(buf_ & 0xFFU));
    }
    buf_ = 0;
    cnt_ = 0;
  }

 private:
  std::vector<std::uint8_t>& out_;
  std::uint64_t buf_ = 0;
  unsigned cnt_ = 0;
};

// Fixed literal/length code of symbol s (RFC 1951 3.2.6), written MSB first.
void put_fixed_litlen(BitSink& bs, unsigned s) {
  if (s < 144U) {
    bs.put(reverse_bits(0x30U + s, 8), 8);
  } else if (s < 256U) {
    bs.put(reverse_bits(0x190U + (s - 144U), 9), 9);
  } else if (s < 280U) {
    bs.put(reverse_bits(s - 256U, 7), 7);
  } else {
    bs.put(reverse_bits(0xC0U + (s - 280U), 8), 8);
  }
}

void put_match(BitSink& bs, std::size_t len, std::size_t dist) {
  std::size_t ls = kLenBase.size() - 1U;  // 258 -> symbol 285; 227..257 -> 284
  while (kLenBase[ls] > len) {
    --ls;
  }
  put_fixed_litlen(bs, 257U + static_cast<unsigned>(ls));
  bs.put(static_cast<std::uint32_t>(len - kLenBase[ls]), kLenExtra[ls]);
  std::size_t ds = kDistBase.size() - 1U;
  while (kDistBase[ds] > dist) {
    --ds;
  }
  bs.put(reverse_bits(static_cast<std::uint32_t>(ds), 5), 5);
  bs.put(static_cast<std::uint32_t>(dist - kDistBase[ds]), kDistExtra[ds]);
}

}  // namespace

std::vector<std::uint8_t> zlib_compress_fixed(const std::uint8_t* data, std::size_t size,
                                              unsigned max_chain) {
  constexpr std::size_t kWindow = 32768U;
  constexpr std::size_t kMaxMatch = 258U;
  constexpr unsigned kHashBits = 15U;
  constexpr std::uint32_t kNone = 0xFFFFFFFFU;
  std::vector<std::uint8_t> z;
  z.reserve(size / 4U + 64U);
  append_zlib_header(z);
  BitSink bs(z);
  bs.put(1U, 1);  // BFINAL
  bs.put(1U, 2);  // BTYPE = 01, fixed Huffman
  std::vector<std::uint32_t> head(std::size_t{1} << kHashBits, kNone);
  std::vector<std::uint32_t> prev(kWindow, kNone);
  const auto hash = [data](std::size_t i) {
    const std::uint32_t v = data[i] | (static_cast<std::uint32_t>(data[i + 1U]) << 8U) |
                            (static_cast<std::uint32_t>(data[i + 2U]) << 16U);
    return (v * 2654435761U) >> (32U - kHashBits);
  };
  const auto insert = [&](std::size_t i) {
    if (i + 3U <= size) {
      const std::uint32_t h = hash(i);
      prev[i % kWindow] = head[h];
      head[h] = static_cast<std::uint32_t>(i);
    }
  };
  std::size_t i = 0;
  // Positions are stored as uint32: inputs past 4 GiB are coded as literals only (never
  // reached by a MAT element, whose size is 32-bit).
  while (i < size) {
    std::size_t best_len = 0;
    std::size_t best_dist = 0;
    if (i + 3U <= size && i < kNone) {
      std::uint32_t cand = head[hash(i)];
      const std::size_t max_len = std::min(kMaxMatch, size - i);
      for (unsigned chain = 0; cand != kNone && chain < max_chain; ++chain) {
        const std::size_t d = i - cand;
        if (d == 0U || d > kWindow) {
          break;
        }
        std::size_t l = 0;
        while (l < max_len && data[cand + l] == data[i + l]) {
          ++l;
        }
        if (l > best_len) {
          best_len = l;
          best_dist = d;
          if (l == max_len) {
            break;
          }
        }
        const std::uint32_t next = prev[cand % kWindow];
        if (next == kNone || next >= cand) {
          break;  // chain left the window (slot reused by a newer position)
        }
        cand = next;
      }
    }
    if (best_len >= 3U) {
      put_match(bs, best_len, best_dist);
      for (std::size_t k = 0; k < best_len; ++k) {
        insert(i + k);
      }
      i += best_len;
    } else {
      put_fixed_litlen(bs, data[i]);
      insert(i);
      ++i;
    }
  }
  put_fixed_litlen(bs, 256U);  // end of block
  bs.flush();
  append_adler32(z, data, size);
  return z;
}

}  // namespace imu::mat

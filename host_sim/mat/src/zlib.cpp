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
constexpr unsigned kLitBits = 10U;   // primary table index width, literal/length codes
constexpr unsigned kDistBits = 8U;   // primary table index width, distance codes
constexpr std::size_t kMaxLitLen = 288U;
constexpr std::size_t kMaxDist = 32U;
// Entries of a table: the primary table (2^root) plus every sub-table. A sub-table of width w
// sits under a complete subtree holding at least w + 1 codes, so the sub-tables of n codes hold
// at most n * max(2^w / (w + 1)) entries: 288 * 32 / 6 = 1536 (w <= 5) for literal/length,
// 32 * 128 / 8 = 512 (w <= 7) for distances. build() checks the bound anyway.
constexpr std::size_t kLitTableSize = (std::size_t{1} << kLitBits) + 1536U;
constexpr std::size_t kDistTableSize = (std::size_t{1} << kDistBits) + 512U;
// The fast loop runs while this much output room is left: the longest match (258) plus the
// overshoot of its chunked copy (< 32), plus two literals.
constexpr std::size_t kFastRoom = 320U;
// Streaming (InflateStream): the output buffer is the 32 KiB window plus one chunk; decoding
// stops (at a symbol boundary) when less than the longest match is left, the consumer takes the
// chunk, and the last 32 KiB slide to the front. The input buffer is refilled from the source
// whenever less than kInMargin bytes are left at a symbol or block boundary: more than the
// longest dynamic block header (< 600 bytes) or symbol, so decoding never stops inside one.
constexpr std::size_t kInflateWindow = 32768U;
constexpr std::size_t kStreamChunk = std::size_t{1} << 16U;
constexpr std::size_t kStreamRoom = 258U;
constexpr std::size_t kInMargin = 1024U;
constexpr std::size_t kInBuffer = std::size_t{1} << 16U;

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

// A decoding table entry (32 bits), indexed by the next bits of the stream (LSB first):
//   bits 0-3   length of the code in bits (1..15); 0: the bits are not a code of the set
//   bits 4-7   extra bits that follow the code (kBase), or the index width of a sub-table (kLink)
//   bits 8-10  kind
//   bits 16-31 value: the literal byte or code-length symbol, the base length or distance, or
//              the offset of the sub-table
// One lookup gives everything the decoder needs for a symbol: no symbol-to-base indirection.
constexpr std::uint32_t kKindMask = 7U << 8U;
constexpr std::uint32_t kNotCode = 0U;
constexpr std::uint32_t kLiteral = 1U << 8U;    // also a code-length symbol (0..18)
constexpr std::uint32_t kBase = 2U << 8U;       // length 3..258 or distance 1..32768
constexpr std::uint32_t kEnd = 3U << 8U;        // end of block (256)
constexpr std::uint32_t kLink = 4U << 8U;       // codes longer than the root: a sub-table
constexpr std::uint32_t kBadSymbol = 5U << 8U;  // a code for length 286/287 or distance 30/31

constexpr std::uint32_t make_entry(std::uint32_t kind, std::uint32_t value, unsigned code_bits,
                                   unsigned extra_bits) {
  return (value << 16U) | kind | (extra_bits << 4U) | code_bits;
}
constexpr unsigned code_bits(std::uint32_t e) { return e & 15U; }
constexpr unsigned extra_bits(std::uint32_t e) { return (e >> 4U) & 15U; }
constexpr std::uint32_t value_of(std::uint32_t e) { return e >> 16U; }
constexpr std::uint64_t low_bits(std::uint64_t v, unsigned n) {
  return v & ((std::uint64_t{1} << n) - 1U);
}

enum class Alphabet : std::uint8_t { code_lengths, lit_len, distance };

std::uint32_t symbol_entry(Alphabet alphabet, std::size_t s, unsigned len) {
  const auto sym = static_cast<std::uint32_t>(s);
  switch (alphabet) {
    case Alphabet::code_lengths:
      return make_entry(kLiteral, sym, len, 0);
    case Alphabet::lit_len:
      if (s < 256U) {
        return make_entry(kLiteral, sym, len, 0);
      }
      if (s == 256U) {
        return make_entry(kEnd, 0, len, 0);
      }
      if (s - 257U < kLenBase.size()) {
        return make_entry(kBase, kLenBase[s - 257U], len, kLenExtra[s - 257U]);
      }
      return make_entry(kBadSymbol, sym, len, 0);
    case Alphabet::distance:
      if (s < kDistBase.size()) {
        return make_entry(kBase, kDistBase[s], len, kDistExtra[s]);
      }
      return make_entry(kBadSymbol, sym, len, 0);
  }
  return kNotCode;
}

template <std::size_t N>
using Table = std::array<std::uint32_t, N>;
using LitTable = Table<kLitTableSize>;
using DistTable = Table<kDistTableSize>;

// Build the table of a canonical Huffman code from its code lengths, with `root` index bits.
// Rejects over-subscribed sets and incomplete sets of more than one code (as zlib). Cost:
// O(2^root + n + sub-table entries).
template <std::size_t N>
[[nodiscard]] bool build(Table<N>& t, unsigned root, Alphabet alphabet,
                         const std::uint8_t* lengths, std::size_t n) {
  std::array<std::uint16_t, kMaxBits + 1> count{};
  for (std::size_t s = 0; s < n; ++s) {
    ++count[lengths[s]];
  }
  const std::size_t n_codes = n - count[0];
  int left = 1;
  for (unsigned len = 1; len <= kMaxBits; ++len) {
    left *= 2;
    left -= count[len];
    if (left < 0) {
      return false;  // over-subscribed
    }
  }
  if (left > 0 && n_codes > 1U) {
    return false;  // incomplete: only a single code (or none) may leave the set incomplete
  }
  // First canonical code of each length (RFC 1951 3.2.2).
  std::array<unsigned, kMaxBits + 1> first{};
  unsigned code = 0;
  for (unsigned len = 1; len <= kMaxBits; ++len) {
    code = (code + (len == 1U ? 0U : count[len - 1U])) << 1U;
    first[len] = code;
  }
  const std::size_t root_size = std::size_t{1} << root;
  const std::size_t root_mask = root_size - 1U;
  std::fill(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(root_size), kNotCode);
  // Sub-table width of each root slot: its longest code less the root bits.
  std::array<std::uint8_t, std::size_t{1} << kLitBits> width{};
  std::array<unsigned, kMaxBits + 1> next = first;
  for (std::size_t s = 0; s < n; ++s) {
    const unsigned len = lengths[s];
    if (len > root) {
      const std::size_t slot = reverse_bits(next[len], len) & root_mask;
      width[slot] = static_cast<std::uint8_t>(std::max<unsigned>(width[slot], len - root));
    }
    ++next[len];
  }
  std::size_t used = root_size;
  for (std::size_t slot = 0; slot < root_size; ++slot) {
    if (width[slot] == 0U) {
      continue;
    }
    const std::size_t size = std::size_t{1} << width[slot];
    if (size > N - used) {
      return false;  // cannot happen for a valid set (see the size comment); defensive
    }
    t[slot] = make_entry(kLink, static_cast<std::uint32_t>(used), 0, width[slot]);
    std::fill(t.begin() + static_cast<std::ptrdiff_t>(used),
              t.begin() + static_cast<std::ptrdiff_t>(used + size), kNotCode);
    used += size;
  }
  next = first;
  for (std::size_t s = 0; s < n; ++s) {
    const unsigned len = lengths[s];
    if (len == 0U) {
      continue;
    }
    const std::size_t rev = reverse_bits(next[len]++, len);
    const std::uint32_t e = symbol_entry(alphabet, s, len);
    if (len <= root) {
      for (std::size_t i = rev; i < root_size; i += std::size_t{1} << len) {
        t[i] = e;
      }
    } else {
      const std::uint32_t link = t[rev & root_mask];
      const std::size_t base = value_of(link);
      const std::size_t sub_size = std::size_t{1} << extra_bits(link);
      for (std::size_t i = rev >> root; i < sub_size; i += std::size_t{1} << (len - root)) {
        t[base + i] = e;
      }
    }
  }
  return true;
}

// The entry for the code at the head of `bits` (sub-table resolved).
template <std::size_t N>
std::uint32_t lookup(const Table<N>& t, unsigned root, std::uint64_t bits) {
  std::uint32_t e = t[static_cast<std::size_t>(low_bits(bits, root))];
  if ((e & kKindMask) == kLink) {
    e = t[value_of(e) + static_cast<std::size_t>(low_bits(bits >> root, extra_bits(e)))];
  }
  return e;
}

// 8 bytes, little-endian, from any alignment: one unaligned load (g++ 12 does not merge the
// shift-or byte loop into one load here, which cost ~15 % of the decode time).
std::uint64_t load_le64(const std::uint8_t* p) {
  std::uint64_t w = 0;
  std::memcpy(&w, p, sizeof w);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  w = __builtin_bswap64(w);  // the stream is little-endian; every host target is too
#endif
  return w;
}

class Inflater {
 public:
  Inflater(const std::uint8_t* in, std::size_t in_size, std::size_t max_out, InflateMode mode,
           std::vector<std::uint8_t>& out, std::size_t size_hint)
      : in_(in), in_size_(in_size), max_out_(max_out), mode_(mode), out_(out) {
    // No clear() first: a reused vector keeps its bytes, so resize() does not zero them again
    // (they are overwritten; finish() cuts the vector to what was produced).
    cap_ = std::min(max_out_, std::max<std::size_t>(size_hint, 1U << 16U));
    out_.resize(cap_);
  }

  // Streaming: compressed bytes from `src` through `in_buf` (kInBuffer bytes), output into
  // `out` (kInflateWindow + kStreamChunk bytes, never grown). Decode with pump(), take bytes
  // from pending(), then slide().
  Inflater(ByteSource& src, std::vector<std::uint8_t>& in_buf, std::vector<std::uint8_t>& out)
      : Inflater(in_buf.data(), 0, kInflateWindow + kStreamChunk, InflateMode::whole, out,
                 kInflateWindow + kStreamChunk) {
    src_ = &src;
    in_buf_ = &in_buf;
    src_eof_ = false;
  }

  // Whole mode: decode blocks until the final one (or, in prefix mode, until max_out bytes).
  [[nodiscard]] InflateStatus run() {
    for (;;) {
      const InflateStatus st = step();
      if (st != InflateStatus::ok) {
        return st;
      }
      if (phase_ == Phase::done || full_) {
        return InflateStatus::ok;
      }
    }
  }

  // Streaming: decode until about `want` bytes more were produced (the output buffer has less
  // than kStreamRoom bytes of room below that mark) or the final block ended. Returns ok or the
  // first error. A small `want` (a header peek) decodes little more than asked for.
  [[nodiscard]] InflateStatus pump(std::size_t want) {
    // The decoder's bound is cap_: lower it to the mark (never above the buffer).
    cap_ = std::min(out_.size(), n_out_ + std::max(want, kFastRoom) + kStreamRoom);
    suspended_ = false;
    for (;;) {
      const InflateStatus st = step();
      if (st != InflateStatus::ok) {
        return st;
      }
      if (suspended_ || phase_ == Phase::done) {
        return InflateStatus::ok;
      }
    }
  }
  [[nodiscard]] bool deflate_done() const { return phase_ == Phase::done; }
  [[nodiscard]] bool needs_slide() const { return out_.size() - n_out_ < kStreamRoom + kFastRoom; }
  // Output produced and not yet taken: [delivered_, n_out_).
  [[nodiscard]] const std::uint8_t* pending(std::size_t& n) const {
    n = n_out_ - delivered_;
    return out_.data() + delivered_;
  }
  void take(std::size_t n) { delivered_ += n; }
  // Keep the last kInflateWindow bytes (the most a distance reaches back). Precondition: all
  // taken.
  void slide() {
    if (n_out_ > kInflateWindow) {
      std::memmove(out_.data(), out_.data() + (n_out_ - kInflateWindow), kInflateWindow);
      n_out_ = kInflateWindow;
      delivered_ = kInflateWindow;
    }
  }
  // n byte-aligned input bytes (the zlib header and trailer), partial byte bits dropped first.
  [[nodiscard]] bool read_aligned(std::uint8_t* dst, std::size_t n) {
    pos_ = align_and_position();
    bitbuf_ = 0;
    bitcnt_ = 0;
    fill_input();
    if (in_size_ - pos_ < n) {
      return false;
    }
    std::memcpy(dst, in_ + pos_, n);
    pos_ += n;
    return true;
  }

  // One step of the block state machine.
  [[nodiscard]] InflateStatus step() {
    InflateStatus st = InflateStatus::ok;
    switch (phase_) {
      case Phase::block_start: {
        if (last_) {
          phase_ = Phase::done;
          return InflateStatus::ok;
        }
        fill_input();
        if (!need(3)) {
          return InflateStatus::truncated_input;
        }
        last_ = bits(1) != 0U;
        const unsigned type = bits(2);
        if (type == 0U) {
          st = stored_header();
          phase_ = Phase::stored;
        } else if (type == 1U) {
          build_fixed();
          phase_ = Phase::codes_fixed;
        } else if (type == 2U) {
          st = dynamic();
          phase_ = Phase::codes_dynamic;
        } else {
          st = InflateStatus::bad_block_type;
        }
        return st;
      }
      case Phase::stored:
        st = stored_copy();
        break;
      case Phase::codes_fixed:
        st = codes(fixed_lit_, fixed_dist_);
        break;
      case Phase::codes_dynamic:
        st = codes(lit_, dist_);
        break;
      case Phase::done:
        return InflateStatus::ok;
    }
    if (st == InflateStatus::ok && !suspended_ && !full_) {
      phase_ = Phase::block_start;  // the block ended
    }
    return st;
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
  // Bits of bitbuf_ at and above bitcnt_ are zero or the input's next bits (the 8-byte load
  // puts whole bytes there that a later refill ORs in again at the same place).
  void refill() {
    if (in_size_ - pos_ >= 8U) {
      // Fast path: one 8-byte little-endian load; take the whole bytes that fit in the buffer.
      bitbuf_ |= load_le64(in_ + pos_) << bitcnt_;
      pos_ += (63U - bitcnt_) >> 3U;
      bitcnt_ |= 56U;  // bitcnt_ + 8 * ((63 - bitcnt_) / 8) for bitcnt_ < 64
      return;
    }
    while (bitcnt_ <= 56U && pos_ < in_size_) {
      bitbuf_ |= static_cast<std::uint64_t>(in_[pos_++]) << bitcnt_;
      bitcnt_ += 8U;
    }
  }
  // Streaming: when less than kInMargin input bytes are left, move the rest (and the bytes still
  // in the bit buffer) to the front and read from the source until the buffer is full or the
  // source ends. Whole mode: nothing (src_eof_).
  void fill_input() {
    if (src_eof_ || in_size_ - pos_ >= kInMargin) {
      return;
    }
    std::vector<std::uint8_t>& b = *in_buf_;
    const std::size_t from = pos_ - bitcnt_ / 8U;  // whole bytes in bitbuf_ are not yet used
    const std::size_t keep = in_size_ - from;
    std::memmove(b.data(), b.data() + from, keep);
    pos_ -= from;
    in_size_ = keep;
    while (in_size_ < b.size()) {
      const std::size_t got = src_->read(b.data() + in_size_, b.size() - in_size_);
      if (got == 0U) {
        src_eof_ = true;
        break;
      }
      in_size_ += std::min(got, b.size() - in_size_);
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
    const auto v = static_cast<unsigned>(low_bits(bitbuf_, n));
    drop(n);
    return v;
  }
  void drop(unsigned n) {
    bitbuf_ >>= n;
    bitcnt_ -= n;
  }

  // Decode one code: its entry in `e` and its bits dropped. A bit string that is not a code is
  // `not_code` if 15 bits were available, else truncated_input (the stream may end inside it).
  template <std::size_t N>
  [[nodiscard]] InflateStatus decode(const Table<N>& t, unsigned root, InflateStatus not_code,
                                     std::uint32_t& e) {
    if (bitcnt_ < kMaxBits) {
      refill();
    }
    e = lookup(t, root, bitbuf_);
    const unsigned len = code_bits(e);
    if (len == 0U) {
      return bitcnt_ < kMaxBits ? InflateStatus::truncated_input : not_code;
    }
    if (len > bitcnt_) {
      return InflateStatus::truncated_input;
    }
    drop(len);
    return InflateStatus::ok;
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

  InflateStatus stored_header() {
    pos_ = align_and_position();
    bitbuf_ = 0;
    bitcnt_ = 0;
    fill_input();
    if (in_size_ - pos_ < 4U) {
      return InflateStatus::truncated_input;
    }
    const unsigned len = in_[pos_] | (static_cast<unsigned>(in_[pos_ + 1U]) << 8U);
    const unsigned nlen = in_[pos_ + 2U] | (static_cast<unsigned>(in_[pos_ + 3U]) << 8U);
    pos_ += 4U;
    if (len != (~nlen & 0xFFFFU)) {
      return InflateStatus::bad_stored_length;
    }
    if (src_eof_ && in_size_ - pos_ < len) {
      return InflateStatus::truncated_input;
    }
    stored_left_ = len;
    return InflateStatus::ok;
  }

  // Copy the stored block's bytes: whole mode at once (growing the output), streaming as far
  // as the input buffer and the output room go.
  InflateStatus stored_copy() {
    while (stored_left_ > 0U) {
      fill_input();
      std::size_t n = std::min(stored_left_, in_size_ - pos_);
      if (n == 0U) {
        return InflateStatus::truncated_input;
      }
      if (src_ != nullptr) {
        n = std::min(n, cap_ - n_out_);
        if (n == 0U) {
          suspended_ = true;
          return InflateStatus::ok;
        }
      } else if (!room(n)) {
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
      pos_ += n;
      stored_left_ -= n;
      if (full_) {
        return InflateStatus::ok;
      }
    }
    return InflateStatus::ok;
  }

  void build_fixed() {
    if (!fixed_built_) {
      std::array<std::uint8_t, kMaxLitLen> l{};
      std::fill(l.begin(), l.begin() + 144, std::uint8_t{8});
      std::fill(l.begin() + 144, l.begin() + 256, std::uint8_t{9});
      std::fill(l.begin() + 256, l.begin() + 280, std::uint8_t{7});
      std::fill(l.begin() + 280, l.end(), std::uint8_t{8});
      std::array<std::uint8_t, kMaxDist> d{};
      d.fill(5);
      // The fixed sets are complete or (distance: 32 codes of 5 bits) exactly full.
      static_cast<void>(build(fixed_lit_, kLitBits, Alphabet::lit_len, l.data(), l.size()));
      static_cast<void>(build(fixed_dist_, kDistBits, Alphabet::distance, d.data(), d.size()));
      fixed_built_ = true;
    }
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
    if (!build(lit_, kLitBits, Alphabet::code_lengths, cl.data(), cl.size())) {
      return InflateStatus::bad_code_lengths;
    }
    std::array<std::uint8_t, kMaxLitLen + kMaxDist> lengths{};
    unsigned index = 0;
    while (index < nlen + ndist) {
      std::uint32_t e = 0;
      const InflateStatus st = decode(lit_, kLitBits, InflateStatus::bad_code_lengths, e);
      if (st != InflateStatus::ok) {
        return st;
      }
      const std::uint32_t sym = value_of(e);
      if (sym < 16U) {
        lengths[index++] = static_cast<std::uint8_t>(sym);
        continue;
      }
      std::uint8_t value = 0;
      unsigned repeat = 0;
      if (sym == 16U) {
        if (index == 0U) {
          return InflateStatus::bad_code_lengths;  // nothing to repeat
        }
        value = lengths[index - 1U];
        if (!need(2)) {
          return InflateStatus::truncated_input;
        }
        repeat = 3U + bits(2);
      } else if (sym == 17U) {
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
    if (!build(lit_, kLitBits, Alphabet::lit_len, lengths.data(), nlen) ||
        !build(dist_, kDistBits, Alphabet::distance, lengths.data() + nlen, ndist)) {
      return InflateStatus::bad_code_lengths;
    }
    return InflateStatus::ok;
  }

  // Fast loop, while at least 8 input bytes remain (for the refill) and kFastRoom bytes of
  // output room: one branch-free refill per step gives >= 56 bits, enough for a length code,
  // its extra bits, a distance code and its extra bits (15 + 5 + 15 + 13) or two literals; no
  // per-byte bound checks; match copies in 32-, 16- or 8-byte chunks that may write up to 31 bytes
  // past the match (inside the room, overwritten later or cut by finish()). Returns true at the
  // end of the block. Anything else (a bit string that is not a code, symbols 286/287 or 30/31,
  // a distance before the start of the output) returns false with the state at the start of
  // that symbol: the careful path decodes it again and reports the error as it always did.
  bool fast(const LitTable& lit, const DistTable& dist) {
    // Streaming with more input to come: stop kInMargin bytes before the end of the buffer,
    // so that codes() refills it between symbols.
    const std::size_t reserve = src_eof_ ? 8U : kInMargin;
    if (in_size_ - pos_ < reserve || cap_ - n_out_ < kFastRoom) {
      return false;
    }
    const std::size_t in_last = in_size_ - reserve;  // last position an 8-byte load may start at
    const std::size_t out_last = cap_ - kFastRoom;
    std::uint8_t* const out = out_.data();
    std::uint64_t bb = bitbuf_;
    unsigned bc = bitcnt_;
    std::size_t pos = pos_;
    std::size_t n = n_out_;
    bool end = false;
    while (pos <= in_last && n <= out_last) {
      bb |= load_le64(in_ + pos) << bc;
      pos += (63U - bc) >> 3U;
      bc |= 56U;
      std::uint32_t e = lookup(lit, kLitBits, bb);
      std::uint32_t kind = e & kKindMask;
      if (kind == kLiteral) {
        bb >>= code_bits(e);
        bc -= code_bits(e);
        out[n++] = static_cast<std::uint8_t>(value_of(e));
        e = lookup(lit, kLitBits, bb);  // >= 41 bits left: a second literal needs no refill
        if ((e & kKindMask) == kLiteral) {
          bb >>= code_bits(e);
          bc -= code_bits(e);
          out[n++] = static_cast<std::uint8_t>(value_of(e));
        }
        continue;
      }
      if (kind != kBase) {
        if (kind == kEnd) {
          bb >>= code_bits(e);
          bc -= code_bits(e);
          end = true;
        }
        break;  // end of block, or an error for the careful path
      }
      const unsigned len_bits = code_bits(e) + extra_bits(e);
      const std::size_t len =
          value_of(e) + static_cast<std::size_t>(low_bits(bb >> code_bits(e), extra_bits(e)));
      const std::uint64_t bd = bb >> len_bits;
      const std::uint32_t de = lookup(dist, kDistBits, bd);
      kind = de & kKindMask;
      if (kind != kBase) {
        break;
      }
      const std::size_t d =
          value_of(de) + static_cast<std::size_t>(low_bits(bd >> code_bits(de), extra_bits(de)));
      if (d > n) {
        break;
      }
      const unsigned used = len_bits + code_bits(de) + extra_bits(de);
      bb >>= used;
      bc -= used;
      copy_match(out + n, d, len);
      n += len;
    }
    bitbuf_ = bb;
    bitcnt_ = bc;
    pos_ = pos;
    n_out_ = n;
    return end;
  }

  // dst[i] = dst[i - d] for i < len, writing up to 31 bytes past len. Precondition: d >= 1 and
  // d bytes precede dst, len + 31 bytes of room after it.
  static void copy_match(std::uint8_t* dst, std::size_t d, std::size_t len) {
    std::uint8_t* const stop = dst + len;
    if (d >= 32U) {
      const std::uint8_t* src = dst - d;
      do {
        std::memcpy(dst, src, 32);  // src + 32 <= dst: no overlap
        dst += 32;
        src += 32;
      } while (dst < stop);
    } else if (d >= 16U) {
      const std::uint8_t* src = dst - d;
      do {
        std::memcpy(dst, src, 16);  // src + 16 <= dst: no overlap
        dst += 16;
        src += 16;
      } while (dst < stop);
    } else if (d >= 8U) {
      const std::uint8_t* src = dst - d;
      do {
        std::memcpy(dst, src, 8);
        dst += 8;
        src += 8;
      } while (dst < stop);
    } else if (d == 1U) {
      std::memset(dst, dst[-1], len);
    } else {
      // Period d < 8: the first d * ceil(8 / d) bytes one at a time, then 8-byte chunks from a
      // whole number of periods back (>= 8, so no overlap).
      const std::size_t period = d * ((8U + d - 1U) / d);
      std::size_t i = 0;
      const std::uint8_t* back = dst - d;  // (dst[i - d] would wrap i - d as size_t: UB)
      for (; i < period && i < len; ++i) {
        dst[i] = back[i];
      }
      for (; i < len; i += 8U) {
        std::memcpy(dst + i, dst + i - period, 8);
      }
    }
  }

  InflateStatus codes(const LitTable& lit, const DistTable& dist) {
    for (;;) {
      if (src_ != nullptr) {
        fill_input();
        if (cap_ - n_out_ < kStreamRoom) {
          suspended_ = true;  // the consumer takes the chunk, slide() makes room
          return InflateStatus::ok;
        }
      }
      if (fast(lit, dist)) {
        return InflateStatus::ok;
      }
      if (src_ != nullptr && cap_ - n_out_ < kStreamRoom) {
        suspended_ = true;  // the fast loop left less room than the longest match
        return InflateStatus::ok;
      }
      // Careful path: one symbol with every check (near the end of the input or of the
      // output buffer, and for every error).
      std::uint32_t e = 0;
      InflateStatus st = decode(lit, kLitBits, InflateStatus::bad_symbol, e);
      if (st != InflateStatus::ok) {
        return st;
      }
      const std::uint32_t kind = e & kKindMask;
      if (kind == kLiteral) {
        if (n_out_ == cap_ && !room(1)) {
          if (mode_ == InflateMode::whole) {
            return InflateStatus::output_limit;
          }
          full_ = true;
          return InflateStatus::ok;
        }
        out_[n_out_++] = static_cast<std::uint8_t>(value_of(e));
        continue;
      }
      if (kind == kEnd) {
        return InflateStatus::ok;
      }
      if (kind != kBase) {
        return InflateStatus::bad_symbol;  // length symbol 286 or 287
      }
      if (!need(extra_bits(e))) {
        return InflateStatus::truncated_input;
      }
      std::size_t len = value_of(e) + bits(extra_bits(e));
      st = decode(dist, kDistBits, InflateStatus::bad_symbol, e);
      if (st != InflateStatus::ok) {
        return st;
      }
      if ((e & kKindMask) != kBase) {
        return InflateStatus::bad_symbol;  // distance symbol 30 or 31
      }
      if (!need(extra_bits(e))) {
        return InflateStatus::truncated_input;
      }
      const std::size_t d = value_of(e) + bits(extra_bits(e));
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
      std::uint8_t* dst = out_.data() + n_out_;
      const std::uint8_t* back = dst - d;
      for (std::size_t i = 0; i < len; ++i) {
        dst[i] = back[i];  // byte by byte: an overlapping copy repeats the last d bytes
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
  enum class Phase : std::uint8_t { block_start, stored, codes_fixed, codes_dynamic, done };
  Phase phase_ = Phase::block_start;
  bool last_ = false;             // the current block is the final one
  std::size_t stored_left_ = 0;   // bytes of the current stored block not yet copied
  // Streaming only:
  ByteSource* src_ = nullptr;
  std::vector<std::uint8_t>* in_buf_ = nullptr;
  bool src_eof_ = true;           // whole mode: all input is in in_
  bool suspended_ = false;        // pump() stopped for output room
  std::size_t delivered_ = 0;     // output bytes the consumer took
  LitTable lit_{};
  DistTable dist_{};
  LitTable fixed_lit_{};
  DistTable fixed_dist_{};
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

struct InflateStream::Impl {
  Impl(ByteSource& src, bool zlib_wrapper)
      : in_buf(kInBuffer), inf(src, in_buf, out), zlib(zlib_wrapper) {}
  std::vector<std::uint8_t> in_buf;
  std::vector<std::uint8_t> out;
  Inflater inf;
  bool zlib;
  bool started = false;
  bool failed = false;
  bool checked = false;  // the trailer was read (and, once all bytes are out, compared)
  InflateStatus status = InflateStatus::ok;
  std::uint32_t adler = 1U;
  std::uint32_t want_adler = 0U;
  std::uint64_t total = 0;

  void fail(InflateStatus st) {
    failed = true;
    status = st;
  }
  void start() {
    started = true;
    if (!zlib) {
      return;
    }
    std::array<std::uint8_t, 2> h{};
    if (!inf.read_aligned(h.data(), 2)) {
      fail(InflateStatus::truncated_input);
      return;
    }
    const unsigned cmf = h[0];
    const unsigned flg = h[1];
    if ((cmf & 0x0FU) != 8U || (cmf >> 4U) > 7U || ((cmf << 8U) | flg) % 31U != 0U) {
      fail(InflateStatus::bad_zlib_header);
    } else if ((flg & 0x20U) != 0U) {
      fail(InflateStatus::preset_dictionary);
    }
  }
  // Decode more output, about `want` bytes (after the consumer took all there was). False when
  // nothing more comes.
  bool produce(std::size_t want) {
    if (failed || inf.deflate_done()) {
      return false;
    }
    if (!started) {
      start();
      if (failed) {
        return false;
      }
    }
    if (inf.needs_slide()) {
      inf.slide();
    }
    const InflateStatus st = inf.pump(want);
    if (st != InflateStatus::ok) {
      fail(st);
      return false;
    }
    if (inf.deflate_done() && zlib) {
      std::array<std::uint8_t, 4> t{};
      if (!inf.read_aligned(t.data(), 4)) {
        fail(InflateStatus::truncated_input);
        return false;
      }
      want_adler = (static_cast<std::uint32_t>(t[0]) << 24U) |
                   (static_cast<std::uint32_t>(t[1]) << 16U) |
                   (static_cast<std::uint32_t>(t[2]) << 8U) | static_cast<std::uint32_t>(t[3]);
    }
    return true;
  }
};

InflateStream::InflateStream(ByteSource& src, bool zlib_wrapper)
    : impl_(std::make_unique<Impl>(src, zlib_wrapper)) {}
InflateStream::InflateStream(InflateStream&&) noexcept = default;
InflateStream& InflateStream::operator=(InflateStream&&) noexcept = default;
InflateStream::~InflateStream() = default;

std::size_t InflateStream::read(std::uint8_t* dst, std::size_t n) {
  Impl& m = *impl_;
  std::size_t got = 0;
  while (got < n && !m.failed) {
    std::size_t avail = 0;
    const std::uint8_t* p = m.inf.pending(avail);
    if (avail > 0U) {
      const std::size_t k = std::min(avail, n - got);
      std::memcpy(dst + got, p, k);
      if (m.zlib) {
        m.adler = adler32(p, k, m.adler);
      }
      m.inf.take(k);
      got += k;
      m.total += k;
      continue;
    }
    if (!m.produce(n - got)) {
      break;
    }
  }
  std::size_t left = 0;
  static_cast<void>(m.inf.pending(left));
  if (!m.failed && !m.checked && left == 0U && m.inf.deflate_done()) {
    m.checked = true;
    if (m.zlib && m.adler != m.want_adler) {
      m.fail(InflateStatus::adler_mismatch);
    }
  }
  return got;
}

InflateStatus InflateStream::status() const { return impl_->status; }
bool InflateStream::finished() const { return impl_->checked && !impl_->failed; }
std::uint64_t InflateStream::total_out() const { return impl_->total; }

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
  if (in_size < 2U) {
    out.clear();
    return InflateResult{InflateStatus::truncated_input, in_size};
  }
  const unsigned cmf = in[0];
  const unsigned flg = in[1];
  if ((cmf & 0x0FU) != 8U || (cmf >> 4U) > 7U || ((cmf << 8U) | flg) % 31U != 0U) {
    out.clear();
    return InflateResult{InflateStatus::bad_zlib_header, 0};
  }
  if ((flg & 0x20U) != 0U) {
    out.clear();
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

// LZ4 frame and block decoder, xxHash32. See imu/cli/lz4.hpp for the contract.
#include "imu/cli/lz4.hpp"

#include <algorithm>
#include <cstring>

namespace imu::cli {
namespace {

// xxHash32 primes (xxHash specification, XXH32).
constexpr std::uint32_t kPrime1 = 0x9E3779B1U;
constexpr std::uint32_t kPrime2 = 0x85EBCA77U;
constexpr std::uint32_t kPrime3 = 0xC2B2AE3DU;
constexpr std::uint32_t kPrime4 = 0x27D4EB2FU;
constexpr std::uint32_t kPrime5 = 0x165667B1U;

// LZ4 frame format 1.6.x, 2: the frame magic, and the skippable frames' 0x184D2A5X.
constexpr std::uint32_t kFrameMagic = 0x184D2204U;
constexpr std::uint32_t kSkippableMagic = 0x184D2A50U;
constexpr std::uint32_t kSkippableMask = 0xFFFFFFF0U;
// LZ4 block format: a match is at least 4 bytes; a 4-bit length of 15 continues in bytes.
constexpr std::size_t kMinMatch = 4U;
constexpr unsigned kRunMask = 15U;

constexpr std::uint32_t rotl(std::uint32_t x, unsigned r) {
  return (x << r) | (x >> (32U - r));
}

std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8U) |
         (static_cast<std::uint32_t>(p[2]) << 16U) | (static_cast<std::uint32_t>(p[3]) << 24U);
}

std::uint64_t le64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(le32(p)) | (static_cast<std::uint64_t>(le32(p + 4)) << 32U);
}

// A length of 15 in a token continues with bytes added to it until one below 255 (LZ4 block
// format). False if the input ends first, or the length would pass `limit`.
bool extend_length(const std::uint8_t* in, std::size_t in_size, std::size_t& i, std::size_t& len,
                   std::size_t limit) {
  for (;;) {
    if (i >= in_size) {
      return false;
    }
    const std::uint8_t b = in[i++];
    len += b;
    if (len > limit) {
      return false;
    }
    if (b != 255U) {
      return true;
    }
  }
}

// One LZ4 frame at in[0..in_size) (after its magic was read: `i` is 4), appended to out.
Lz4Status decode_frame(const std::uint8_t* in, std::size_t in_size, std::size_t& i,
                       std::size_t max_out, std::vector<std::uint8_t>& out) {
  // Frame descriptor: FLG, BD, [content size], [dictionary id], HC.
  if (in_size - i < 3U) {
    return Lz4Status::truncated_input;
  }
  const std::size_t desc = i;
  const std::uint8_t flg = in[i];
  const std::uint8_t bd = in[i + 1U];
  if ((flg >> 6U) != 1U || (flg & 0x02U) != 0U || (bd & 0x8FU) != 0U || ((bd >> 4U) & 7U) < 4U) {
    return Lz4Status::bad_descriptor;
  }
  const bool independent = (flg & 0x20U) != 0U;
  const bool block_sum = (flg & 0x10U) != 0U;
  const bool has_size = (flg & 0x08U) != 0U;
  const bool content_sum = (flg & 0x04U) != 0U;
  if ((flg & 0x01U) != 0U) {
    return Lz4Status::dictionary;
  }
  // Block maximum: 64 KiB, 256 KiB, 1 MiB, 4 MiB for BD 4..7.
  const std::size_t block_max = std::size_t{1} << (8U + 2U * ((bd >> 4U) & 7U));
  i += 2U;
  std::uint64_t content_size = 0;
  if (has_size) {
    if (in_size - i < 8U) {
      return Lz4Status::truncated_input;
    }
    content_size = le64(in + i);
    i += 8U;
  }
  if (in_size - i < 1U) {
    return Lz4Status::truncated_input;
  }
  // HC: the second byte of the descriptor's xxHash32 (seed 0), FLG to the byte before HC.
  if (static_cast<std::uint8_t>((xxh32(in + desc, i - desc) >> 8U) & 0xFFU) != in[i]) {
    return Lz4Status::bad_header_checksum;
  }
  ++i;
  const std::size_t start = out.size();
  if (has_size && content_size > max_out - start) {
    return Lz4Status::output_limit;
  }
  for (;;) {
    if (in_size - i < 4U) {
      return Lz4Status::truncated_input;
    }
    const std::uint32_t word = le32(in + i);
    i += 4U;
    if (word == 0U) {
      break;  // end mark
    }
    const bool stored = (word & 0x80000000U) != 0U;
    const std::size_t size = word & 0x7FFFFFFFU;
    if (size > block_max) {
      return Lz4Status::block_too_large;
    }
    if (in_size - i < size + (block_sum ? 4U : 0U)) {
      return Lz4Status::truncated_input;
    }
    if (block_sum && xxh32(in + i, size) != le32(in + i + size)) {
      return Lz4Status::block_checksum;
    }
    const std::size_t at = out.size();
    const std::size_t room = std::min(block_max, max_out - at);
    if (stored) {
      if (size > max_out - at) {
        return Lz4Status::output_limit;
      }
      out.insert(out.end(), in + i, in + i + size);
    } else {
      out.resize(at + room);
      std::size_t n = at;
      const Lz4Status st =
          lz4_decode_block(in + i, size, out.data(), at + room, independent ? at : start, n);
      if (st != Lz4Status::ok) {
        out.resize(at);
        // A block that fills the room: past the block maximum, or past max_out.
        return st == Lz4Status::bad_block && room < block_max ? Lz4Status::output_limit : st;
      }
      out.resize(n);
    }
    i += size + (block_sum ? 4U : 0U);
  }
  if (has_size && out.size() - start != content_size) {
    return Lz4Status::content_size_mismatch;
  }
  if (content_sum) {
    if (in_size - i < 4U) {
      return Lz4Status::truncated_input;
    }
    // Verified (not skipped): a corrupt chunk is refused rather than read as other numbers.
    if (xxh32(out.data() + start, out.size() - start) != le32(in + i)) {
      return Lz4Status::content_checksum;
    }
    i += 4U;
  }
  return Lz4Status::ok;
}

}  // namespace

const char* describe(Lz4Status status) {
  switch (status) {
    case Lz4Status::ok:
      return "ok";
    case Lz4Status::truncated_input:
      return "the LZ4 data ends inside a frame";
    case Lz4Status::bad_magic:
      return "not an LZ4 frame (magic 0x184D2204)";
    case Lz4Status::bad_descriptor:
      return "a malformed LZ4 frame descriptor";
    case Lz4Status::dictionary:
      return "an LZ4 frame with a preset dictionary (not supported)";
    case Lz4Status::bad_header_checksum:
      return "an LZ4 frame header checksum mismatch";
    case Lz4Status::block_too_large:
      return "an LZ4 block larger than its frame's block maximum";
    case Lz4Status::bad_block:
      return "a malformed LZ4 block (a sequence past its end)";
    case Lz4Status::bad_offset:
      return "an LZ4 match offset before the start of the data";
    case Lz4Status::output_limit:
      return "the LZ4 data decodes to more than its stated size";
    case Lz4Status::content_size_mismatch:
      return "the LZ4 content size differs from the frame's";
    case Lz4Status::block_checksum:
      return "an LZ4 block checksum mismatch";
    case Lz4Status::content_checksum:
      return "an LZ4 content checksum mismatch";
  }
  return "an LZ4 error";
}

Lz4Status lz4_decode_block(const std::uint8_t* in, std::size_t in_size, std::uint8_t* out,
                           std::size_t out_capacity, std::size_t window, std::size_t& out_size) {
  std::size_t i = 0;
  std::size_t o = out_size;
  if (window > o || o > out_capacity) {
    return Lz4Status::bad_offset;
  }
  while (i < in_size) {
    const unsigned token = in[i++];
    // Literals.
    std::size_t lit = token >> 4U;
    if (lit == kRunMask && !extend_length(in, in_size, i, lit, in_size)) {
      return Lz4Status::bad_block;
    }
    if (lit > in_size - i || lit > out_capacity - o) {
      return Lz4Status::bad_block;
    }
    std::memcpy(out + o, in + i, lit);
    i += lit;
    o += lit;
    if (i == in_size) {
      break;  // the last sequence: literals only
    }
    // Match: a 2-byte offset, then its length.
    if (in_size - i < 2U) {
      return Lz4Status::bad_block;
    }
    const std::size_t offset = static_cast<std::size_t>(in[i]) |
                               (static_cast<std::size_t>(in[i + 1U]) << 8U);
    i += 2U;
    if (offset == 0U || offset > o - window) {
      return Lz4Status::bad_offset;
    }
    std::size_t len = token & kRunMask;
    if (len == kRunMask && !extend_length(in, in_size, i, len, out_capacity)) {
      return Lz4Status::bad_block;
    }
    len += kMinMatch;
    if (len > out_capacity - o) {
      return Lz4Status::bad_block;
    }
    // Byte by byte: the match may overlap its own output (offset < len repeats a pattern).
    const std::uint8_t* from = out + (o - offset);
    if (offset >= len) {
      std::memcpy(out + o, from, len);
    } else {
      for (std::size_t k = 0; k < len; ++k) {
        out[o + k] = from[k];
      }
    }
    o += len;
  }
  out_size = o;
  return Lz4Status::ok;
}

Lz4Status lz4_decode_frames(const std::uint8_t* in, std::size_t in_size, std::size_t max_out,
                            std::vector<std::uint8_t>& out) {
  out.clear();
  std::size_t i = 0;
  if (in_size == 0U) {
    return Lz4Status::truncated_input;
  }
  while (i < in_size) {
    if (in_size - i < 4U) {
      return Lz4Status::truncated_input;
    }
    const std::uint32_t magic = le32(in + i);
    i += 4U;
    if ((magic & kSkippableMask) == kSkippableMagic) {
      if (in_size - i < 4U || le32(in + i) > in_size - i - 4U) {
        return Lz4Status::truncated_input;
      }
      i += 4U + le32(in + i);
      continue;
    }
    if (magic != kFrameMagic) {
      return Lz4Status::bad_magic;
    }
    const Lz4Status st = decode_frame(in, in_size, i, max_out, out);
    if (st != Lz4Status::ok) {
      return st;
    }
  }
  return Lz4Status::ok;
}

std::uint32_t xxh32(const std::uint8_t* data, std::size_t size, std::uint32_t seed) {
  const std::uint8_t* p = data;
  const std::uint8_t* const end = data + size;
  std::uint32_t h = 0;
  if (size >= 16U) {
    std::uint32_t v1 = seed + kPrime1 + kPrime2;
    std::uint32_t v2 = seed + kPrime2;
    std::uint32_t v3 = seed;
    std::uint32_t v4 = seed - kPrime1;
    const auto round = [](std::uint32_t acc, std::uint32_t lane) {
      return rotl(acc + lane * kPrime2, 13U) * kPrime1;
    };
    while (end - p >= 16) {
      v1 = round(v1, le32(p));
      v2 = round(v2, le32(p + 4));
      v3 = round(v3, le32(p + 8));
      v4 = round(v4, le32(p + 12));
      p += 16;
    }
    h = rotl(v1, 1U) + rotl(v2, 7U) + rotl(v3, 12U) + rotl(v4, 18U);
  } else {
    h = seed + kPrime5;
  }
  h += static_cast<std::uint32_t>(size);
  while (end - p >= 4) {
    h = rotl(h + le32(p) * kPrime3, 17U) * kPrime4;
    p += 4;
  }
  while (p < end) {
    h = rotl(h + static_cast<std::uint32_t>(*p) * kPrime5, 11U) * kPrime1;
    ++p;
  }
  h ^= h >> 15U;
  h *= kPrime2;
  h ^= h >> 13U;
  h *= kPrime3;
  h ^= h >> 16U;
  return h;
}

}  // namespace imu::cli

// RFC 1951 inflate (stored, fixed and dynamic Huffman blocks) with the RFC 1950 zlib wrapper,
// and two small zlib writers: stored blocks (level 0) and one fixed-Huffman block with LZ77. Standard library only, host code.
//
// Decoding is table-driven: one lookup in a 10-bit (literal/length) or 8-bit (distance) primary
// table, or a second one in a sub-table for longer codes, gives a symbol's code length and its
// literal byte or base length/distance with the count of extra bits. A fast loop runs while 8
// input bytes and 320 bytes of output room remain: a 64-bit bit buffer refilled by one 8-byte
// load per symbol (>= 56 bits: a whole length/distance pair), no per-byte bound checks, match
// copies in 8/16/32-byte chunks. Near the ends of the input and of the output buffer, and for
// every error, a careful path decodes one symbol at a time with every check.
// Validation follows zlib: over-subscribed code sets are rejected, incomplete sets are accepted
// only when they have at most one code, a symbol outside the set, a distance before the start of
// the output, length symbols 286/287 and distance symbols 30/31 are errors.
//
// Output is bounded (a memory budget): never more than `max_out` bytes are produced or allocated
// (a stream that would inflate to more is InflateStatus::output_limit in whole mode; the buffer
// grows geometrically up to min(max_out, what the stream actually produces), starting from
// `size_hint` when the caller knows the expected size).
//
// Cost: O(input + output); one table build per dynamic block (O(2^10 + 288)). Re-entrant: no
// global state.
#ifndef IMU_MAT_ZLIB_HPP
#define IMU_MAT_ZLIB_HPP

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace imu::mat {

enum class InflateStatus : std::uint8_t {
  ok,
  truncated_input,    ///< the stream ends before its final block (or before the Adler-32)
  bad_zlib_header,    ///< CM != 8, CINFO > 7 or the header check bits are wrong
  preset_dictionary,  ///< FDICT set: a preset dictionary is not supported
  bad_block_type,     ///< BTYPE == 3
  bad_stored_length,  ///< LEN != ~NLEN in a stored block
  bad_code_lengths,   ///< invalid or over-subscribed/incomplete Huffman code set
  bad_symbol,         ///< a code not in the set, or length symbol 286/287, distance 30/31
  bad_distance,       ///< a distance reaching before the start of the output
  output_limit,       ///< the stream inflates to more than max_out bytes
  adler_mismatch,     ///< Adler-32 of the output differs from the stream's trailer
};

/// Short, lower-case description of a status ("corrupt zlib stream: ..." prefixes are the
/// caller's business).
[[nodiscard]] const char* describe(InflateStatus status);

enum class InflateMode : std::uint8_t {
  whole,   ///< decode the whole stream; more than max_out bytes is output_limit
  prefix,  ///< stop with ok once max_out bytes are produced (no Adler-32 check then)
};

struct InflateResult {
  InflateStatus status;
  std::size_t in_consumed;  ///< input bytes used (up to and including the trailer when whole)
};

/// Inflate a zlib (RFC 1950) stream. `out` is replaced by the produced bytes (also on error:
/// what was decoded so far). Bytes after the Adler-32 trailer are ignored (in_consumed says
/// where the stream ended).
[[nodiscard]] InflateResult inflate_zlib(const std::uint8_t* in, std::size_t in_size,
                                         std::size_t max_out, InflateMode mode,
                                         std::vector<std::uint8_t>& out,
                                         std::size_t size_hint = 0);

/// Inflate a raw deflate (RFC 1951) stream, no wrapper, no check value.
[[nodiscard]] InflateResult inflate_raw(const std::uint8_t* in, std::size_t in_size,
                                        std::size_t max_out, InflateMode mode,
                                        std::vector<std::uint8_t>& out, std::size_t size_hint = 0);

/// Where InflateStream gets its compressed bytes (a file region, a memory buffer).
class ByteSource {
 public:
  ByteSource() = default;
  ByteSource(const ByteSource&) = delete;
  ByteSource& operator=(const ByteSource&) = delete;
  ByteSource(ByteSource&&) = delete;
  ByteSource& operator=(ByteSource&&) = delete;
  virtual ~ByteSource() = default;
  /// Up to `n` bytes into `dst`; 0 only at the end of the input (or on a read error, which the
  /// source records for its owner).
  [[nodiscard]] virtual std::size_t read(std::uint8_t* dst, std::size_t n) = 0;
};

/// A zlib (or raw deflate) stream inflated as it is read, in constant memory: the 32 KiB window
/// plus a 64 KiB chunk of output, a 64 KiB input buffer refilled from the ByteSource, and the
/// decoding tables (about 190 kB in all, whatever the stream's length). Same decoder, same
/// validation and same errors as inflate_zlib(); the Adler-32 is checked when the last byte has
/// been read (a consumer must look at status() after read() returned 0 before trusting the
/// data). Cost per byte as inflate_zlib() plus one copy into the caller's buffer.
class InflateStream {
 public:
  /// `src` must outlive the stream. `zlib_wrapper`: RFC 1950 header and Adler-32, else raw.
  InflateStream(ByteSource& src, bool zlib_wrapper);
  InflateStream(const InflateStream&) = delete;
  InflateStream& operator=(const InflateStream&) = delete;
  InflateStream(InflateStream&&) noexcept;
  InflateStream& operator=(InflateStream&&) noexcept;
  ~InflateStream();

  /// Up to `n` inflated bytes into `dst` (fewer only at the end of the stream or on an error).
  /// Returns the count; 0 once the stream is finished or failed (see status()).
  [[nodiscard]] std::size_t read(std::uint8_t* dst, std::size_t n);
  /// ok while running and after a complete, checked stream; else the first error.
  [[nodiscard]] InflateStatus status() const;
  /// The stream ended (final block, and the Adler-32 checked) and every byte was read.
  [[nodiscard]] bool finished() const;
  /// Inflated bytes handed out so far.
  [[nodiscard]] std::uint64_t total_out() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Adler-32 (RFC 1950) of `size` bytes, continuing from `adler` (1 for a new checksum).
[[nodiscard]] std::uint32_t adler32(const std::uint8_t* data, std::size_t size,
                                    std::uint32_t adler = 1U);

/// Wrap `size` bytes in a valid zlib stream made of stored blocks (no compression, 5 bytes of
/// overhead per 65535 bytes + 6). Any RFC 1950 decoder accepts it.
[[nodiscard]] std::vector<std::uint8_t> zlib_store(const std::uint8_t* data, std::size_t size);

/// Compress `size` bytes into a zlib stream of one fixed-Huffman block (RFC 1951 3.2.6) with
/// greedy LZ77 matching (hash chains, 32 KiB window, at most `max_chain` candidates per
/// position). About 8x smaller than stored blocks on quantised IMU doubles; not as small as
/// zlib's dynamic blocks. Cost: O(size * max_chain) time, 256 KiB of tables.
[[nodiscard]] std::vector<std::uint8_t> zlib_compress_fixed(const std::uint8_t* data,
                                                            std::size_t size,
                                                            unsigned max_chain = 32U);

/// Upper bound of the inflated size of `compressed_size` bytes of deflate data: a length/distance
/// pair takes at least 2 bits (1-bit length code, 1-bit distance code) and yields at most 258
/// bytes, so 1032 bytes per input byte, plus a margin.
[[nodiscard]] constexpr std::size_t max_inflated_size(std::size_t compressed_size) {
  return compressed_size > (static_cast<std::size_t>(-1) - 1024U) / 1032U
             ? static_cast<std::size_t>(-1)
             : compressed_size * 1032U + 1024U;
}

}  // namespace imu::mat

#endif  // IMU_MAT_ZLIB_HPP

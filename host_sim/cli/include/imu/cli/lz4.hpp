// LZ4 frame decoder (LZ4 frame format 1.6.x, LZ4 block format) and xxHash32, as ROS bags'
// "lz4" chunks (roslz4) and the lz4 command line tool write them. Standard library only, host
// code.
//
// A frame: magic 0x184D2204, a descriptor (FLG, BD, an optional 8-byte content size, HC), data
// blocks of a 4-byte size word (high bit: the block is stored uncompressed) each with an
// optional 4-byte checksum, the end mark 0, an optional content checksum. Skippable frames
// (magic 0x184D2A50..0x184D2A5F) are skipped. Everything is checked: the header checksum HC,
// the block size against the descriptor's maximum, the block checksums and the content
// checksum when present (xxHash32 over the block's bytes / the frame's content), the content
// size when present. A match may reach back into the earlier blocks of its frame when the
// blocks are linked (FLG B.Indep = 0), only into its own block when they are independent.
// A preset dictionary (FLG DictID) is refused.
//
// Every malformed input is a status, never an out-of-bounds read or write: each literal run,
// match and field is checked against the input left and the output room before it is copied.
// Output is bounded: never more than `max_out` bytes are produced or allocated.
//
// Cost: O(input + output), plus one xxHash32 pass over the output when the frame carries a
// content checksum. Re-entrant: no global state.
#ifndef IMU_CLI_LZ4_HPP
#define IMU_CLI_LZ4_HPP

#include <cstddef>
#include <cstdint>
#include <vector>

namespace imu::cli {

enum class Lz4Status : std::uint8_t {
  ok,
  truncated_input,       ///< the input ends inside a frame (header, block or checksum)
  bad_magic,             ///< neither an LZ4 frame nor a skippable frame
  bad_descriptor,        ///< FLG version not 01, a reserved bit set, or BD's block size < 4
  dictionary,            ///< FLG DictID: a preset dictionary is not supported
  bad_header_checksum,   ///< HC differs from the descriptor's xxHash32
  block_too_large,       ///< a block's size word above the descriptor's block maximum
  bad_block,             ///< a sequence runs past its block, or a block decodes to more than
                         ///< the block maximum
  bad_offset,            ///< a match offset of 0 or reaching before its window
  output_limit,          ///< the frames decode to more than max_out bytes
  content_size_mismatch, ///< the decoded size differs from the descriptor's content size
  block_checksum,        ///< a block checksum differs from the block's xxHash32
  content_checksum,      ///< the content checksum differs from the content's xxHash32
};

/// Short, lower-case description of a status.
[[nodiscard]] const char* describe(Lz4Status status);

/// Decode `in_size` bytes holding one or more LZ4 frames (and skippable frames) into `out`,
/// which is replaced by the content (also on error: what was decoded so far). ok only when the
/// whole input is consumed by complete, checked frames.
[[nodiscard]] Lz4Status lz4_decode_frames(const std::uint8_t* in, std::size_t in_size,
                                          std::size_t max_out, std::vector<std::uint8_t>& out);

/// Decode one LZ4 block (LZ4 block format: sequences of a token, literals and a match) of
/// `in_size` bytes, appended to `out` at out_size (out[0..out_capacity) is writable; the
/// decoded bytes go to out[out_size..out_size + n)). A match may reach back to out[window]
/// (window <= out_size). On ok, out_size is advanced past the block's bytes.
[[nodiscard]] Lz4Status lz4_decode_block(const std::uint8_t* in, std::size_t in_size,
                                         std::uint8_t* out, std::size_t out_capacity,
                                         std::size_t window, std::size_t& out_size);

/// xxHash32 (XXH32, as the LZ4 frame format uses it) of `size` bytes with `seed`.
[[nodiscard]] std::uint32_t xxh32(const std::uint8_t* data, std::size_t size,
                                  std::uint32_t seed = 0U);

}  // namespace imu::cli

#endif  // IMU_CLI_LZ4_HPP

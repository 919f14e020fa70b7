// The JSON scalars every imu-sim command writes (one JSON writer): numbers with 10
// significant digits (%.10g; NaN and Inf, which JSON lacks, as null) and strings with the
// escapes JSON requires. One vocabulary rides on them: counts are n_*, times *_s, rates *_hz;
// the noise terms are lower-case IEEE 952 symbols (n, q, b, k, r; a GM term's sb and tb_s),
// each JSON naming their units in a "units" object beside them.
#ifndef IMU_CLI_JSON_HPP
#define IMU_CLI_JSON_HPP

#include <cstddef>
#include <string>

namespace imu::cli {

/// A JSON number: %.10g, non-finite -> null.
[[nodiscard]] std::string json_num(double v);
/// A number for a message or a note: 6 significant digits, an exponent when it helps (1e+300,
/// 1e-13, 100): never 300 digits, never 0.000000 for a small value.
[[nodiscard]] std::string num_text(double v);
/// A JSON string literal (quotes, backslash and control characters escaped; a byte that is not
/// part of valid UTF-8 becomes U+FFFD). Also a valid YAML double-quoted scalar (YAML 1.2 reads
/// JSON strings), which is how the YAML writer quotes names and paths.
[[nodiscard]] std::string json_str(const std::string& s);
/// The length of the valid UTF-8 sequence starting at s[i] (1 for ASCII), 0 if the bytes there
/// are not valid UTF-8 (a stray continuation byte, a cut, overlong or surrogate sequence).
[[nodiscard]] std::size_t utf8_sequence(const std::string& s, std::size_t i);
/// The "units" object of a JSON whose channel is in `unit` (e.g. "m/s^2"): each noise term's
/// unit, e.g. {"n": "m/s^2/sqrt(Hz)", "k": "m/s^2*sqrt(Hz)", ...}; "sb", the GM drive's PSD, is
/// (unit)^2/s (its steady variance Sb Tb / 2 is in unit^2).
[[nodiscard]] std::string json_units(const std::string& unit);

/// The version of the shape of every command's JSON (its JSON Schema:
/// host_sim/cli/imu-sim.schema.json). Raised when a key is renamed, moved or removed.
inline constexpr int kJsonSchemaVersion = 1;
/// The members every command's JSON document starts with, one per line after `indent`, each
/// followed by a comma: "schema_version", "command" (adev, analyze, run), "source" (the input).
[[nodiscard]] std::string json_head(const std::string& command, const std::string& source,
                                    const std::string& indent);

}  // namespace imu::cli

#endif  // IMU_CLI_JSON_HPP

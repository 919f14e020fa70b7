// The command-line parser of every imu-sim subcommand (and imu-analyze), and the exit codes.
//
//   Exit status: kExitOk (0) success; kExitRuntime (1) a run-time failure (bad or unreadable
//   file, data that cannot be processed, bus error, failed write, out of memory); kExitUsage (2)
//   a command-line error (unknown option, missing or malformed value, a number out of its range,
//   an option that does not fit the data it applies to).
//
// Grammar: `--name VALUE`, `--name=VALUE`, `--flag`; `-h` / `--help` anywhere asks for the usage;
// any other argument starting with '-' (except "-" itself) is an unknown option, never a file
// name; the rest are positionals, at most max_positional of them. Numbers are checked before
// they become sizes or integers: finite, in [lo, hi], integers where asked.
// Host code (allocates). Errors are one line, without the command's name (the caller adds it).
#ifndef IMU_CLI_ARGS_HPP
#define IMU_CLI_ARGS_HPP

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace imu::cli {

/// The candidate closest to `word` by edit distance, if it is close enough to be a typo (at
/// most a third of its length, at least 1); "" if none. For "did you mean" in messages.
[[nodiscard]] std::string closest(const std::string& word, const std::vector<std::string>& candidates);

/// A message that a name is missing ("variable 'X' not found; variables: A, B", "no column 'X';
/// the columns: A, B", "no column 'X'; columns: A, B") with "; did you mean Y?" appended when one
/// of the listed names is closest() to X; any other message unchanged.
[[nodiscard]] std::string with_suggestion(const std::string& msg);

inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntime = 1;
inline constexpr int kExitUsage = 2;

/// One option of a subcommand.
struct OptSpec {
  const char* name;  ///< "--bus"
  bool has_value;
};

/// Parsed command line: options by name, positionals in order.
class Args {
 public:
  /// Parse argv[first..argc). False (with err) on an unknown option, a missing value, a value
  /// given to a flag, or more positionals than allowed. O(argc x specs).
  [[nodiscard]] bool parse(int argc, char** argv, int first, const std::vector<OptSpec>& specs,
                           std::size_t max_positional, std::string& err);
  /// -h or --help was given (parse() then ignores everything else and returns true).
  [[nodiscard]] bool help() const { return help_; }
  [[nodiscard]] bool has(const std::string& name) const { return opts_.count(name) != 0; }
  [[nodiscard]] std::string get(const std::string& name, const std::string& def = "") const;
  /// Numeric option: def if absent; false (with err) unless a finite number in [lo, hi].
  [[nodiscard]] bool number(const std::string& name, double def, double lo, double hi, double& out,
                            std::string& err) const;
  /// Any finite number (callers that check the range themselves).
  [[nodiscard]] bool number(const std::string& name, double def, double& out,
                            std::string& err) const;
  /// Integer option: def if absent; false (with err) unless an integer in [lo, hi] (hi <= 2^53).
  [[nodiscard]] bool integer(const std::string& name, std::uint64_t def, std::uint64_t lo,
                             std::uint64_t hi, std::uint64_t& out, std::string& err) const;
  [[nodiscard]] const std::vector<std::string>& positional() const { return pos_; }

 private:
  std::map<std::string, std::string> opts_;
  std::vector<std::string> pos_;
  bool help_ = false;
};

/// A channel named on the command line: NAME, or NAME:K for column K (1-based, as in Octave)
/// of a matrix NAME.
struct ChannelSpec {
  std::string name;         ///< the file's variable
  std::size_t column = 0;   ///< 0-based
  bool has_column = false;  ///< :K was given
};

/// The reader's error names a channel the file does not hold (a variable, struct field, text
/// column or matrix column), or a ROS bag topic to be chosen or not held (its message names
/// --topic): a command-line mistake, exit kExitUsage in every command.
[[nodiscard]] bool names_missing_channel(const std::string& err);

/// Parse NAME or NAME:K; false with a one-line err when K is not a number in [1, 1e6].
[[nodiscard]] bool parse_channel_spec(const std::string& text, ChannelSpec& out, std::string& err);

/// The file variables that may hold a channel's LSB, in the order every command tries them:
/// for NAME (NAME:K, or a struct field P.NAME) <group>_lsb (acc_lsb for acc_z, gyro_lsb for
/// gyro_x; the part before the first '_'), NAME_lsb, lsb; for a struct field first inside its
/// struct (P.acc_lsb, ...), then at the top level. The first one the file holds is the LSB (one
/// that is not a positive number is an error, not skipped).
[[nodiscard]] std::vector<std::string> lsb_candidates(const std::string& channel);

/// The LSB a file gives `channel` (every command the same): the first of lsb_candidates() that
/// the file holds, 0 if none. `held(name)`: the file has a top-level variable `name` (struct
/// fields are tried whatever it says); `read(name, value, err)`: its scalar value. False with
/// err: a held top-level candidate cannot be read, or the value is not a positive number.
[[nodiscard]] bool file_lsb(const std::string& channel, const std::string& file,
                            const std::function<bool(const std::string&)>& held,
                            const std::function<bool(const std::string&, double&, std::string&)>& read,
                            double& lsb, std::string& err);

/// The IMU channel names, in the order `--channel all` takes them.
inline constexpr const char* kImuChannelNames[] = {"acc_x", "acc_y", "acc_z",
                                                   "gyro_x", "gyro_y", "gyro_z"};

/// --channel SPEC naming one or several channels: `all` is the IMU channels (kImuChannelNames)
/// among `held` (what the file holds), in that order; else a comma list, each name once, in
/// order. False with a one-line err: an empty name in the list, or `all` on a file holding
/// none of them (the message lists what it holds).
[[nodiscard]] bool expand_channels(const std::string& spec, const std::vector<std::string>& held,
                                   std::vector<std::string>& out, std::string& err);

/// job(0) .. job(n - 1), each once, on up to hardware_concurrency() threads including this one
/// (one thread when the environment sets IMU_NO_THREADS: qemu-aarch64 user mode hangs on a
/// second thread, the cross tests set it; fewer when threads cannot be created). Jobs must not
/// throw (catch inside; an escaping exception terminates).
void parallel_for(std::size_t n, const std::function<void(std::size_t)>& job);

}  // namespace imu::cli

#endif  // IMU_CLI_ARGS_HPP

// The fully overlapping Allan deviation of a whole record (`imu-sim adev --estimator full`), for
// parity with allantools' oadev and Stable32, the modified Allan, overlapping Hadamard and time
// deviations of `--deviation` (NIST SP 1065, Riley 2008, eqns. 14, 20, 15), and the tau grids of
// `--taus` (allantools' keywords). Host only: the record's counts are kept (4 bytes per sample + the
// gap marks; float data without an LSB: its values, 8 bytes); the online estimator (fw OnlineAdev)
// is the constant-memory one.
#ifndef IMU_SIM_FULL_ADEV_HPP
#define IMU_SIM_FULL_ADEV_HPP

#include <cstdint>
#include <string>
#include <vector>

#include "data.hpp"
#include "report.hpp"

namespace imu::sim {

/// Collects a channel's counts (or, with `values`, its samples as they are: float data without
/// an LSB, no grid) and gaps as stream_counts() delivers them.
class FullAdevSink final : public CountSink {
 public:
  explicit FullAdevSink(bool values = false) : values_mode_(values) {}
  void push(const std::int32_t* counts, std::size_t n) override;
  void gap(std::size_t n) override;
  [[nodiscard]] bool takes_values() const override { return values_mode_; }
  void push_values(const double* values, std::size_t n) override;
  [[nodiscard]] const std::vector<std::int32_t>& counts() const { return counts_; }
  [[nodiscard]] const std::vector<double>& values() const { return values_; }
  [[nodiscard]] const std::vector<std::uint8_t>& gaps() const { return gaps_; }
  /// Samples held, gaps included.
  [[nodiscard]] std::size_t size() const { return gaps_.size(); }

 private:
  bool values_mode_;
  std::vector<std::int32_t> counts_;
  std::vector<double> values_;
  std::vector<std::uint8_t> gaps_;  // 1 where a sample is missing (its count or value is 0)
};

/// Averaging factors m of a tau grid for n samples, as allantools' tau_generator: "octave"
/// 1, 2, 4, ..; "decade" 1, 2, 4, 10, 20, 40, ..; "quarter" round(2^(k/4)) (quarter octaves,
/// duplicates removed); "all" every m. Only m <= (n - 1) / 2 (at least one term). False for an
/// unknown keyword.
[[nodiscard]] bool tau_grid(const std::string& kind, std::uint64_t n, std::vector<std::uint64_t>& m);

/// Number of second differences the full estimator sums over the grid (its cost).
[[nodiscard]] double full_adev_cost(std::uint64_t n, const std::vector<std::uint64_t>& m);

/// The deviations of `imu-sim adev --deviation`, all fully overlapping, from frequency data
/// (NIST SP 1065 section 5.2): adev eqn. 11 (allantools oadev), mdev eqn. 14 (allantools mdev),
/// hdev the overlapping Hadamard deviation eqn. 20 (allantools ohdev), tdev = tau mdev / sqrt(3)
/// eqn. 15 (allantools tdev; in the data's unit times seconds).
enum class Deviation : std::uint8_t { kAdev, kMdev, kHdev, kTdev };

/// "adev", "mdev", "hdev" or "tdev": the JSON key, CSV header and option value.
[[nodiscard]] const char* deviation_name(Deviation d);

/// A comma list of deviation names ("mdev,tdev"), in the order given, without repeats. False
/// with err for an unknown or empty name.
[[nodiscard]] bool parse_deviations(const std::string& list, std::vector<Deviation>& out,
                                    std::string& err);

/// The largest averaging factor whose estimate has at least two terms on n samples without gaps,
/// as allantools keeps (its remove_small_ns): adev (n - 1) / 2, mdev and tdev n / 3, hdev
/// (n - 1) / 3. 0 when none.
[[nodiscard]] std::uint64_t deviation_max_af(Deviation d, std::uint64_t n);

/// The deviation `d` at each m of the grid that is at most deviation_max_af(d, n). From the
/// integer phase x (cumulative counts; exact in int64), times lsb^2 (a sink of values: x the
/// cumulative sum of the mean-removed values, accumulated in long double, as allantools' phase;
/// lsb unused):
///   adev: AVAR = sum_i (x[i+2m] - 2 x[i+m] + x[i])^2 / (2 m^2 terms), terms = n + 1 - 2m
///         without gaps; EDF Greenhall-Riley for white FM (d = 2);
///   mdev: MVAR = sum_j S_j^2 / (2 m^4 terms) lsb^2, S_j = sum_{i=j}^{j+m-1} (x[i+2m] - 2 x[i+m]
///         + x[i]), the S_j by a sliding sum of third differences (exact in 128-bit integers),
///         terms = n + 2 - 3m without gaps;
///   hdev: HVAR = sum_j (x[j+3m] - 3 x[j+2m] + 3 x[j+m] - x[j])^2 / (6 m^2 terms) lsb^2 (exact
///         in int64), terms = n + 1 - 3m without gaps;
///   tdev: tau MDEV / sqrt(3).
/// A term whose samples include a gap is left out (mdev: 3m - 1 samples, hdev: 3m); rows with no
/// term are omitted. EDF: Greenhall-Riley for white FM, fully overlapping (stride factor S = m):
/// mdev and tdev the modified variance (F = 1, d = 2), hdev d = 3; 68.3 % interval. The row's
/// `adev` field holds the deviation. O(n) per m.
[[nodiscard]] std::vector<AdevRow> full_deviation(const FullAdevSink& data, Deviation d,
                                                  const std::vector<std::uint64_t>& m,
                                                  double ts_s, double lsb);

/// Keep the rows whose averaging factor is in the grid (the online estimator's taus that are
/// also the grid's).
[[nodiscard]] std::vector<AdevRow> rows_on_grid(const std::vector<AdevRow>& rows,
                                                const std::vector<std::uint64_t>& m);

/// CSV: tau_s,af,adev,ci_lo,ci_hi,edf,n_terms (one header line; `value` names the third
/// column: the deviation).
[[nodiscard]] std::string adev_csv(const std::vector<AdevRow>& rows, const char* value = "adev");

}  // namespace imu::sim

#endif  // IMU_SIM_FULL_ADEV_HPP

// The fully overlapping Allan deviation of a whole record (`imu-sim adev --estimator full`), for
// parity with allantools' oadev and Stable32, and the tau grids of `--taus` (allantools'
// keywords). Host only: the record's counts are kept (4 bytes per sample + the gap marks);
// the online estimator (fw OnlineAdev) is the constant-memory one.
#ifndef IMU_SIM_FULL_ADEV_HPP
#define IMU_SIM_FULL_ADEV_HPP

#include <cstdint>
#include <string>
#include <vector>

#include "data.hpp"
#include "report.hpp"

namespace imu::sim {

/// Collects a channel's counts and gaps as stream_counts() delivers them.
class FullAdevSink final : public CountSink {
 public:
  void push(const std::int32_t* counts, std::size_t n) override;
  void gap(std::size_t n) override;
  [[nodiscard]] const std::vector<std::int32_t>& counts() const { return counts_; }
  [[nodiscard]] const std::vector<std::uint8_t>& gaps() const { return gaps_; }

 private:
  std::vector<std::int32_t> counts_;
  std::vector<std::uint8_t> gaps_;  // 1 where a sample is missing (its count is 0)
};

/// Averaging factors m of a tau grid for n samples, as allantools' tau_generator: "octave"
/// 1, 2, 4, ..; "decade" 1, 2, 4, 10, 20, 40, ..; "quarter" round(2^(k/4)) (quarter octaves,
/// duplicates removed); "all" every m. Only m <= (n - 1) / 2 (at least one term). False for an
/// unknown keyword.
[[nodiscard]] bool tau_grid(const std::string& kind, std::uint64_t n, std::vector<std::uint64_t>& m);

/// Number of second differences the full estimator sums over the grid (its cost).
[[nodiscard]] double full_adev_cost(std::uint64_t n, const std::vector<std::uint64_t>& m);

/// Fully overlapping ADEV at each m: sum over every start i of (x[i+2m] - 2 x[i+m] + x[i])^2 /
/// (2 m^2 terms) with x the integer phase (cumulative counts; exact in int64), times lsb^2;
/// a term whose 2m samples include a gap is left out. EDF: Greenhall-Riley for white FM (the
/// golden files' assumption), 68.3 % interval. Rows with no term are omitted. O(n) per m.
[[nodiscard]] std::vector<AdevRow> full_adev(const FullAdevSink& data,
                                             const std::vector<std::uint64_t>& m, double ts_s,
                                             double lsb);

/// Keep the rows whose averaging factor is in the grid (the online estimator's taus that are
/// also the grid's).
[[nodiscard]] std::vector<AdevRow> rows_on_grid(const std::vector<AdevRow>& rows,
                                                const std::vector<std::uint64_t>& m);

/// CSV: tau_s,af,adev,ci_lo,ci_hi,edf,n_terms (one header line).
[[nodiscard]] std::string adev_csv(const std::vector<AdevRow>& rows);

}  // namespace imu::sim

#endif  // IMU_SIM_FULL_ADEV_HPP

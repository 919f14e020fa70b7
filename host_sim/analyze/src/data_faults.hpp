// Faults of the recording rather than of the sensor's noise (internal to the analysis): a frozen
// output (one value repeated far longer than the record's own ties allow) and a clipped output
// (the record's extreme value held by far more samples than the value next to it).
#ifndef IMU_ANALYZE_DATA_FAULTS_HPP
#define IMU_ANALYZE_DATA_FAULTS_HPP

#include <cstddef>
#include <vector>

namespace imu::analyze {

/// Runs of one repeated value, each of `length` samples from `first`.
struct FrozenRun {
  std::size_t first = 0;
  std::size_t length = 0;
};

/// The runs of y (non-finite samples break runs) longer than the record's ties allow: with p0
/// the fraction of successive finite pairs that are equal (the 95th percentile over blocks of
/// 1024 pairs, so that a lattice on which the level dwells in places does not count as frozen),
/// a run of L samples has probability about n p0^(L - 1) of appearing by chance; runs of four
/// times the L where that falls below alpha (ties on a coarse lattice come in runs), and of at
/// least 16, are returned, longest first. `min_length_out` (if given): the shortest run length
/// that would have been returned.
std::vector<FrozenRun> find_frozen_runs(const std::vector<double>& y, double alpha,
                                        std::size_t* min_length_out = nullptr);

/// The record's output clipped at one end: `count` samples equal to the extreme value `value`
/// (the minimum when `at_min`), against `next_count` at the nearest other value. A tail of a
/// noise distribution thins out towards its extreme; a clipped one piles up there. Found when
/// count >= 10, count >= 4 (next_count + 1), next_count >= 1 (a constant record clips nothing)
/// and count >= 1e-4 of the finite samples.
struct Clipping {
  bool found = false;
  bool at_min = false;
  double value = 0.0;
  std::size_t count = 0;
  std::size_t next_count = 0;
  std::size_t first = 0;  ///< first and last sample at the value
  std::size_t last = 0;
};

/// Both ends of y are checked; the end with more samples at its value is returned.
Clipping find_clipping(const std::vector<double>& y);

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_DATA_FAULTS_HPP

#include "data_faults.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace imu::analyze {
namespace {

// a and b are finite and equal (without operator== on doubles: -Wfloat-equal).
bool same_finite(double a, double b) {
  return std::isfinite(a) && std::isfinite(b) && !(a < b) && !(a > b);
}

}  // namespace

std::vector<FrozenRun> find_frozen_runs(const std::vector<double>& y, double alpha,
                                        std::size_t* min_length_out) {
  constexpr std::size_t kBlockPairs = 1024;
  constexpr std::size_t kMinRun = 16;
  std::vector<double> block_p0;
  std::size_t pairs = 0;
  std::size_t ties = 0;
  std::size_t total_pairs = 0;
  for (std::size_t i = 0; i + 1 < y.size(); ++i) {
    if (!std::isfinite(y[i]) || !std::isfinite(y[i + 1])) {
      continue;
    }
    ++pairs;
    ++total_pairs;
    ties += same_finite(y[i + 1], y[i]) ? 1U : 0U;
    if (pairs == kBlockPairs) {
      block_p0.push_back(static_cast<double>(ties) / static_cast<double>(pairs));
      pairs = 0;
      ties = 0;
    }
  }
  std::vector<FrozenRun> out;
  if (block_p0.size() < 8) {
    return out;
  }
  const auto k95 = block_p0.begin() + static_cast<std::ptrdiff_t>(block_p0.size() * 95 / 100);
  std::nth_element(block_p0.begin(), k95, block_p0.end());
  // At least one tie in a block's worth of pairs: a record without ties says little about them.
  const double p0 = std::max(*k95, 1.0 / static_cast<double>(kBlockPairs));
  if (p0 >= 0.99) {
    return out;  // a record that mostly repeats itself: no run stands out
  }
  // n p0^(L - 1) < alpha  <=>  L - 1 > ln(alpha / n) / ln(p0)
  const double ties_needed =
      std::log(alpha / static_cast<double>(std::max<std::size_t>(total_pairs, 1))) /
      std::log(p0);
  // Four times the length that chance allows under independent ties: on a coarse lattice the
  // level dwells on one value while a slow term holds it mid-step, so ties come in runs longer
  // than independent ones (runs of 74 where 71 was the independent limit, on a lattice of 3 x
  // the white std).
  const auto min_length = std::max(
      kMinRun, 4 * (static_cast<std::size_t>(std::floor(ties_needed)) + 2));
  if (min_length_out != nullptr) {
    *min_length_out = min_length;
  }
  std::size_t i = 0;
  while (i < y.size()) {
    std::size_t b = i + 1;
    while (b < y.size() && same_finite(y[b], y[i])) {
      ++b;
    }
    if (b - i >= min_length) {
      out.push_back(FrozenRun{i, b - i});
    }
    i = b;
  }
  std::sort(out.begin(), out.end(),
            [](const FrozenRun& a, const FrozenRun& b) { return a.length > b.length; });
  return out;
}

namespace {

// The samples at y's extreme value (min or max) and at the nearest other value.
Clipping clipping_at(const std::vector<double>& y, bool at_min) {
  Clipping c;
  c.at_min = at_min;
  const double inf = std::numeric_limits<double>::infinity();
  double ext = at_min ? inf : -inf;
  for (const double v : y) {
    if (std::isfinite(v)) {
      ext = at_min ? std::min(ext, v) : std::max(ext, v);
    }
  }
  double next = at_min ? inf : -inf;
  std::size_t finite = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double v = y[i];
    if (!std::isfinite(v)) {
      continue;
    }
    ++finite;
    if (same_finite(v, ext)) {
      c.first = c.count == 0 ? i : c.first;
      c.last = i;
      ++c.count;
    } else {
      next = at_min ? std::min(next, v) : std::max(next, v);
    }
  }
  for (const double v : y) {
    c.next_count += same_finite(v, next) ? 1U : 0U;
  }
  c.value = ext;
  c.found = c.next_count > 0 && c.count >= 10 && c.count >= 4 * (c.next_count + 1) &&
            static_cast<double>(c.count) >= 1e-4 * static_cast<double>(finite);
  return c;
}

}  // namespace

Clipping find_clipping(const std::vector<double>& y) {
  const Clipping lo = clipping_at(y, true);
  const Clipping hi = clipping_at(y, false);
  if (lo.found && (!hi.found || lo.count >= hi.count)) {
    return lo;
  }
  return hi.found ? hi : Clipping{};
}

}  // namespace imu::analyze

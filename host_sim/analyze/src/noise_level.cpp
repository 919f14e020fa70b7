#include "noise_level.hpp"

#include <algorithm>
#include <cmath>

namespace imu::analyze {

double median_of(std::vector<double> v) {
  if (v.empty()) {
    return 0.0;
  }
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

namespace {

// Per block of `len` samples, the mean of the squared first differences (pairs with a gap
// skipped), each clipped at `clip` (0: none). A block with fewer than half its pairs is NaN.
std::vector<double> block_levels(const std::vector<double>& y, const std::vector<std::uint8_t>& gap,
                                 std::size_t len, double clip) {
  const std::size_t blocks = (y.size() - 1) / len;
  std::vector<double> out(blocks, std::nan(""));
  for (std::size_t b = 0; b < blocks; ++b) {
    double sum = 0.0;
    std::size_t used = 0;
    for (std::size_t i = b * len; i < (b + 1) * len; ++i) {
      if (!gap.empty() && (gap[i] != 0 || gap[i + 1] != 0)) {
        continue;
      }
      const double d = y[i + 1] - y[i];
      sum += clip > 0.0 ? std::min(d * d, clip) : d * d;
      ++used;
    }
    if (2 * used >= len) {
      out[b] = sum / static_cast<double>(used);
    }
  }
  return out;
}

}  // namespace

NoiseLevelChange find_noise_level_change(const std::vector<double>& y,
                                         const std::vector<std::uint8_t>& gap, double alpha,
                                         double min_ratio) {
  NoiseLevelChange out;
  const std::size_t len = std::clamp<std::size_t>(y.size() / 1024, 64, 4096);
  if (y.size() < 64 * len || !(alpha > 0.0 && alpha < 1.0)) {
    return out;
  }
  std::vector<double> lv = block_levels(y, gap, len, 0.0);
  std::vector<double> finite;
  for (const double v : lv) {
    if (std::isfinite(v)) {
      finite.push_back(v);
    }
  }
  const double med = median_of(finite);
  if (!(med > 0.0)) {
    return out;
  }
  lv = block_levels(y, gap, len, 25.0 * med);
  // Log-levels of the blocks that have one (a gap's block is left out; its index kept).
  std::vector<double> l;
  std::vector<std::size_t> first_sample;
  for (std::size_t b = 0; b < lv.size(); ++b) {
    if (std::isfinite(lv[b])) {
      l.push_back(std::log(std::max(lv[b], 1e-3 * med)));
      first_sample.push_back(b * len);
    }
  }
  const std::size_t j = l.size();
  if (j < 32) {
    return out;
  }
  std::vector<double> diffs(j - 1);
  for (std::size_t k = 0; k + 1 < j; ++k) {
    diffs[k] = l[k + 1] - l[k];
  }
  const double dmed = median_of(diffs);
  for (auto& d : diffs) {
    d = std::fabs(d - dmed);
  }
  const double sigma = 1.4826 * median_of(diffs) / std::sqrt(2.0);
  if (!(sigma > 0.0)) {
    return out;
  }
  double mean = 0.0;
  for (const double v : l) {
    mean += v;
  }
  mean /= static_cast<double>(j);
  double s = 0.0;
  double best = 0.0;
  std::size_t best_k = 0;
  for (std::size_t k = 0; k + 1 < j; ++k) {
    s += l[k] - mean;
    if (std::fabs(s) > best) {
      best = std::fabs(s);
      best_k = k + 1;  // the second part starts at block k + 1
    }
  }
  if (best_k == 0) {
    return out;
  }
  out.blocks = j;
  out.block_len = len;
  out.statistic = best / (sigma * std::sqrt(static_cast<double>(j)));
  out.threshold = std::sqrt(0.5 * std::log(2.0 / alpha));
  double m1 = 0.0;
  double m2 = 0.0;
  for (std::size_t k = 0; k < j; ++k) {
    (k < best_k ? m1 : m2) += l[k];
  }
  m1 /= static_cast<double>(best_k);
  m2 /= static_cast<double>(j - best_k);
  out.std_ratio = std::exp(0.5 * (m2 - m1));
  out.at = first_sample[best_k];
  const double r = std::max(out.std_ratio, 1.0 / out.std_ratio);
  out.found = out.statistic > out.threshold && r >= min_ratio;
  return out;
}

}  // namespace imu::analyze

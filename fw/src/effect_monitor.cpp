// On-target effect detectors: outlier gate, two-window step detector, ADEV residual runs.
#include "imu/effect_monitor.hpp"

#include <cmath>

#include "imu/edf.hpp"

namespace imu {

double two_sided_normal_threshold(double p) {
  // P(|N| > z) = p  <=>  z = -quantile(p / 2).
  return p > 0.0 && p < 1.0 ? -normal_quantile(0.5 * p) : 0.0;
}

EffectStatus OutlierGate::configure(double threshold) {
  if (!(threshold > 0.0) || !std::isfinite(threshold)) {
    return EffectStatus::kBadConfig;
  }
  threshold_ = threshold;
  stats_ = OutlierGateStats{};
  return EffectStatus::kOk;
}

bool OutlierGate::push(double nu) {
  ++stats_.samples;
  if (!std::isfinite(nu)) {
    ++stats_.rejected_nonfinite;
    ++stats_.outliers;
    return true;
  }
  const double a = std::fabs(nu);
  stats_.max_abs = a > stats_.max_abs ? a : stats_.max_abs;
  if (a > threshold_) {
    ++stats_.outliers;
    return true;
  }
  return false;
}

template <std::size_t kMaxBlocks, std::size_t kMaxEvents>
EffectStatus StepDetector<kMaxBlocks, kMaxEvents>::configure(std::uint32_t block_len,
                                                             std::uint32_t window_blocks,
                                                             double avar_ref_counts2,
                                                             double threshold) {
  if (block_len < 1 || window_blocks < 1 ||
      2 * static_cast<std::size_t>(window_blocks) > kMaxBlocks || !(threshold > 0.0) ||
      !std::isfinite(threshold) || !(avar_ref_counts2 > 0.0) || !std::isfinite(avar_ref_counts2)) {
    return EffectStatus::kBadConfig;
  }
  block_len_ = block_len;
  window_ = window_blocks;
  sigma_d_ = std::sqrt(2.0 * avar_ref_counts2);
  threshold_ = threshold;
  block_sum_ = 0;
  in_block_ = 0;
  for (auto& r : ring_) {
    r = 0;
  }
  head_ = 0;
  filled_ = 0;
  sum_new_ = 0;
  sum_old_ = 0;
  z_ = 0.0;
  in_excursion_ = false;
  peak_ = StepEvent{};
  for (auto& e : events_) {
    e = StepEvent{};
  }
  stats_ = StepDetectorStats{};
  return EffectStatus::kOk;
}

template <std::size_t kMaxBlocks, std::size_t kMaxEvents>
EffectStatus StepDetector<kMaxBlocks, kMaxEvents>::set_reference_avar(double avar_ref_counts2) {
  if (!(avar_ref_counts2 > 0.0) || !std::isfinite(avar_ref_counts2)) {
    return EffectStatus::kBadConfig;
  }
  sigma_d_ = std::sqrt(2.0 * avar_ref_counts2);
  return EffectStatus::kOk;
}

template <std::size_t kMaxBlocks, std::size_t kMaxEvents>
void StepDetector<kMaxBlocks, kMaxEvents>::push(std::int32_t counts) {
  ++stats_.samples;
  block_sum_ += counts;
  if (++in_block_ < block_len_) {
    return;
  }
  // A block is complete: it enters the new window, the new window's oldest block moves to the
  // old window, and the old window's oldest block leaves.
  const std::size_t w = window_;
  const std::size_t cap = 2 * w;
  if (filled_ >= w) {
    const std::size_t mid = (head_ + cap - w) % cap;  // oldest block of the new window
    sum_new_ -= ring_[mid];
    sum_old_ += ring_[mid];
  }
  if (filled_ >= cap) {
    sum_old_ -= ring_[head_];  // oldest block of the old window (its slot is reused now)
  }
  ring_[head_] = block_sum_;
  sum_new_ += block_sum_;
  head_ = (head_ + 1) % cap;
  filled_ = filled_ < cap ? filled_ + 1 : cap;
  block_sum_ = 0;
  in_block_ = 0;
  ++stats_.blocks;
  if (filled_ < cap) {
    return;
  }
  const double d = static_cast<double>(sum_new_ - sum_old_) /
                   (static_cast<double>(w) * static_cast<double>(block_len_));
  z_ = d / sigma_d_;
  const double a = std::fabs(z_);
  stats_.max_abs_z = a > stats_.max_abs_z ? a : stats_.max_abs_z;
  if (a > threshold_) {
    if (!in_excursion_ || a > std::fabs(peak_.z)) {
      // Boundary between the two windows: start of block (blocks - W), 0-based.
      peak_.sample_index = (stats_.blocks - w) * block_len_;
      peak_.size_counts = d;
      peak_.z = z_;
    }
    in_excursion_ = true;
  } else if (in_excursion_) {
    close_excursion();
  }
}

template <std::size_t kMaxBlocks, std::size_t kMaxEvents>
void StepDetector<kMaxBlocks, kMaxEvents>::finish() {
  if (in_excursion_) {
    close_excursion();
  }
}

template <std::size_t kMaxBlocks, std::size_t kMaxEvents>
void StepDetector<kMaxBlocks, kMaxEvents>::close_excursion() {
  if (stats_.events < kMaxEvents) {
    events_[stats_.events] = peak_;
  } else {
    ++stats_.events_dropped;
  }
  ++stats_.events;
  in_excursion_ = false;
  peak_ = StepEvent{};
}

template <std::size_t kMaxRuns>
EffectStatus check_adev_residual(const AdevPoint* points, std::size_t n, const ModelParams& model,
                                 const AdevCheckOptions& options, AdevCheckResult<kMaxRuns>& out,
                                 double* z_out) {
  out = AdevCheckResult<kMaxRuns>{};
  if ((points == nullptr && n > 0) || !(options.threshold > 0.0) || options.min_run < 1) {
    return EffectStatus::kBadConfig;
  }
  AdevRun cur{};
  double sum_sq_rel = 0.0;
  const auto close_run = [&out, &options](const AdevRun& run) {
    const bool strong = options.z_single > 0.0 && run.max_abs_z > options.z_single;
    if (run.count == 0 || (run.count < options.min_run && !strong)) {
      return;
    }
    if (out.n_runs < kMaxRuns) {
      out.runs[out.n_runs++] = run;
      return;
    }
    // Keep the longest: replace the shortest stored run if this one is longer.
    std::size_t shortest = 0;
    for (std::size_t i = 1; i < kMaxRuns; ++i) {
      shortest = out.runs[i].count < out.runs[shortest].count ? i : shortest;
    }
    if (run.count > out.runs[shortest].count) {
      out.runs[shortest] = run;
    }
    ++out.runs_dropped;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const AdevPoint& p = points[i];
    double z = 0.0;
    const bool in_range = p.tau_s >= options.tau_min_s * (1.0 - 1e-9) &&
                          p.tau_s <= options.tau_max_s * (1.0 + 1e-9);
    const bool valid = p.adev > 0.0 && p.ci_lo > 0.0 && p.ci_hi > p.ci_lo && std::isfinite(p.ci_hi);
    const double m = model_avar(model, p.tau_s);
    if (in_range && valid && m > 0.0) {
      const double model_adev = std::sqrt(m);
      const double h = 0.5 * std::log(p.ci_hi / p.ci_lo);
      z = std::log(model_adev / p.adev) / h;
      const double rel = std::fabs(model_adev / p.adev - 1.0);
      sum_sq_rel += rel * rel;
      out.max_rel = rel > out.max_rel ? rel : out.max_rel;
      out.max_abs_z = std::fabs(z) > out.max_abs_z ? std::fabs(z) : out.max_abs_z;
      ++out.n_checked;
      const int sign = z > options.threshold ? 1 : (z < -options.threshold ? -1 : 0);
      if (sign != 0 && sign == cur.sign) {
        ++cur.count;
        cur.sum_z += z;
        cur.max_abs_z = std::fabs(z) > cur.max_abs_z ? std::fabs(z) : cur.max_abs_z;
      } else {
        close_run(cur);
        cur = AdevRun{};
        if (sign != 0) {
          cur.first = i;
          cur.count = 1;
          cur.sign = sign;
          cur.sum_z = z;
          cur.max_abs_z = std::fabs(z);
        }
      }
    }
    if (z_out != nullptr) {
      z_out[i] = z;
    }
  }
  close_run(cur);
  out.rms_rel = out.n_checked > 0 ? std::sqrt(sum_sq_rel / static_cast<double>(out.n_checked)) : 0.0;
  return EffectStatus::kOk;
}

// Explicit instantiations (so the fw prelude's poison sees the template bodies).
template class StepDetector<64, 4>;
template class StepDetector<16, 4>;
template class StepDetector<16, 64>;  // the analysis: every excursion of a record at a scale
template EffectStatus check_adev_residual<8>(const AdevPoint*, std::size_t, const ModelParams&,
                                             const AdevCheckOptions&, AdevCheckResult<8>&,
                                             double*);

}  // namespace imu

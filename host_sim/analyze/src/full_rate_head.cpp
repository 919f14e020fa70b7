// A long record's two analyses joined (issue 14): the whole record on block means, its head at
// full rate (analyze.hpp merge_full_rate_head).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "imu/analyze/analyze.hpp"

namespace imu::analyze {
namespace {

std::string g4(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// A line or band the head found above the means' Nyquist.
struct FastLine {
  double f_hz = 0.0;
  double tol_hz = 0.0;  // how close the record's alias of it may lie
};

// Where a component at f_hz lands in block means at rate fs_b_hz (folded into [0, fs_b / 2]).
double alias_of(double f_hz, double fs_b_hz) {
  double r = std::fmod(f_hz, fs_b_hz);
  return r > fs_b_hz / 2.0 ? fs_b_hz - r : r;
}

bool is_alias(double f_hz, const std::vector<FastLine>& fast, double fs_b_hz) {
  return std::any_of(fast.begin(), fast.end(), [&](const FastLine& l) {
    return std::fabs(f_hz - alias_of(l.f_hz, fs_b_hz)) <= l.tol_hz;
  });
}

bool no_worse(const ErrorStats& e, const ErrorStats& ref) {
  return e.adev_rms_rel <= ref.adev_rms_rel && e.adev_max_rel <= ref.adev_max_rel;
}

std::string errors_text(const ErrorStats& e) {
  return "RMS " + g4(e.adev_rms_rel) + " max " + g4(e.adev_max_rel);
}

}  // namespace

void merge_full_rate_head(Report& record, Report&& head, std::uint64_t block, const Options& o) {
  FullRateHead& h = record.head;
  h.samples = head.samples;
  h.fs_hz = head.fs_hz;
  h.block = block;
  h.model_before = head.model_before;
  h.model_after = head.model_after;
  h.error_before = head.error_before;
  h.error_after = head.error_after;
  h.effects = std::move(head.effects);
  h.unexplained = head.unexplained;

  const double fs = head.fs_hz;
  const double b = static_cast<double>(block);
  const double fs_b = fs / b;
  const double nyquist_b = fs_b / 2.0;
  const double tau_lo = b / fs;           // the record's first tau
  const double tau_split = 4.0 * tau_lo;  // GM peaks below: the head's; above: the record's
  const std::string where = "full rate on the first " + std::to_string(head.samples) +
                            " samples (" + g4(static_cast<double>(head.samples) / fs / 3600.0) +
                            " h)";

  const ModelParams& hm = head.model_after;
  ModelParams c = record.model_after;
  c.n = hm.n;
  c.q = hm.q;

  // The head's lines and bands above the means' Nyquist; the record's at their aliases go.
  std::vector<FastLine> fast;
  const auto add_fast = [&](double a, double f, double bw) {
    if (a > 0.0 && f > nyquist_b) {
      fast.push_back({f, std::max({0.02 * alias_of(f, fs_b), bw, 2.0 * fs / static_cast<double>(
                                                                       head.samples)})});
    }
  };
  add_fast(hm.sin_a, hm.sin_f0_hz, 0.0);
  add_fast(hm.sin2_a, hm.sin2_f0_hz, 0.0);
  add_fast(hm.osc_sigma, hm.osc_f0_hz, hm.osc_beta_per_s / 3.14159265358979323846);

  std::vector<std::pair<double, double>> sines;  // (A, f0)
  std::vector<std::string> dropped;
  for (const auto& s : {std::make_pair(c.sin_a, c.sin_f0_hz), std::make_pair(c.sin2_a,
                                                                             c.sin2_f0_hz)}) {
    if (s.first > 0.0) {
      if (is_alias(s.second, fast, fs_b)) {
        dropped.push_back("sinusoid at " + g4(s.second) + " Hz");
      } else {
        sines.push_back(s);
      }
    }
  }
  for (const auto& s : {std::make_pair(hm.sin_a, hm.sin_f0_hz), std::make_pair(hm.sin2_a,
                                                                              hm.sin2_f0_hz)}) {
    if (s.first > 0.0 && s.second > nyquist_b) {
      sines.push_back(s);
    }
  }
  bool fits = sines.size() <= 2;
  c.sin_a = c.sin_f0_hz = c.sin2_a = c.sin2_f0_hz = 0.0;
  if (fits && !sines.empty()) {
    c.sin_a = sines[0].first;
    c.sin_f0_hz = sines[0].second;
  }
  if (fits && sines.size() > 1) {
    c.sin2_a = sines[1].first;
    c.sin2_f0_hz = sines[1].second;
  }
  if (c.osc_sigma > 0.0 && is_alias(c.osc_f0_hz, fast, fs_b)) {
    dropped.push_back("oscillation at " + g4(c.osc_f0_hz) + " Hz");
    c.osc_sigma = c.osc_f0_hz = c.osc_beta_per_s = 0.0;
  }
  if (hm.osc_sigma > 0.0 && hm.osc_f0_hz > nyquist_b) {
    if (c.osc_sigma > 0.0) {
      fits = false;  // one oscillation slot
    } else {
      c.osc_sigma = hm.osc_sigma;
      c.osc_f0_hz = hm.osc_f0_hz;
      c.osc_beta_per_s = hm.osc_beta_per_s;
    }
  }
  std::vector<GmParam> gms;
  for (std::size_t i = 0; i < hm.n_gm; ++i) {
    if (kGmPeakTauFactor * hm.gm[i].tb_s < tau_split) {
      gms.push_back(hm.gm[i]);
    }
  }
  for (std::size_t i = 0; i < record.model_after.n_gm; ++i) {
    if (kGmPeakTauFactor * record.model_after.gm[i].tb_s >= tau_split) {
      gms.push_back(record.model_after.gm[i]);
    }
  }
  fits = fits && gms.size() <= kMaxGmTerms;
  c.n_gm = 0;
  for (std::size_t i = 0; fits && i < gms.size(); ++i) {
    c.gm[c.n_gm++] = gms[i];
  }

  const double t_max_rec = record.error_after.tau_max_s;
  const ErrorStats on_record = score_model(record.adev_clean, c, o, tau_lo, t_max_rec);
  h.error_record_model =
      score_model(head.adev_clean, c, o, head.error_after.tau_min_s, head.error_after.tau_max_s);
  if (!fits) {
    record.notes.push_back("full-rate head (" + where + "): its fast terms do not fit beside the "
                           "record's in the model's slots (2 GMs, 2 sinusoids, 1 oscillation): "
                           "the record's model is kept; the head's findings are under "
                           "full_rate_head");
    h.error_record_model = score_model(head.adev_clean, record.model_after, o,
                                       head.error_after.tau_min_s, head.error_after.tau_max_s);
    return;
  }
  if (!no_worse(on_record, record.error_before) || !no_worse(h.error_record_model,
                                                              head.error_before)) {
    record.notes.push_back(
        "full-rate head (" + where + "): the record's model with the head's fast terms would be "
        "worse than the seed's model (record taus: " + errors_text(on_record) + " vs " +
        errors_text(record.error_before) + "; head taus: " + errors_text(h.error_record_model) +
        " vs " + errors_text(head.error_before) + "): the record's model is kept");
    h.error_record_model = score_model(head.adev_clean, record.model_after, o,
                                       head.error_after.tau_min_s, head.error_after.tau_max_s);
    return;
  }
  h.merged = true;
  record.notes.push_back(
      "full-rate head (" + where + "): white noise, quantization, GMs peaking below " +
      g4(tau_split) + " s and lines above the means' Nyquist " + g4(nyquist_b) +
      " Hz come from it; the model's errors on the record's taus " + errors_text(on_record) +
      " (block-means model " + errors_text(record.error_after) + "), on the head's " +
      errors_text(h.error_record_model) + " (the head's own after-model " +
      errors_text(head.error_after) + "); its NIS and covariance figures are the block-means "
      "model's");
  for (const auto& d : dropped) {
    record.notes.push_back("dropped: " + d + " on the block means, the alias of a line the "
                           "full-rate head finds above " + g4(nyquist_b) + " Hz");
  }
  // Effects: the record's quantization and aliases go, the head's fast ones come in.
  std::vector<Effect> kept;
  for (auto& e : record.effects) {
    const bool alias = (e.type == "sinusoid" || e.type == "oscillation") &&
                       is_alias(e.freq_hz, fast, fs_b);
    if (e.type != "quantization" && !alias) {
      kept.push_back(std::move(e));
    }
  }
  for (const auto& e : h.effects) {
    if (e.type == "quantization" ||
        ((e.type == "sinusoid" || e.type == "oscillation") && e.freq_hz > nyquist_b)) {
      kept.push_back(e);
      record.notes.push_back(e.type + " at full rate (" + where + ")");
    }
  }
  record.effects = std::move(kept);
  for (const auto& u : head.unexplained) {
    if (u.tau_max_s < tau_lo) {
      record.unexplained.push_back(u);
    }
  }
  const ErrorStats filter = record.error_after;
  record.model_after = c;
  record.error_after = on_record;
  record.error_after.cov_ratio = filter.cov_ratio;
  record.error_after.nis_mean = filter.nis_mean;
  record.error_after.nis_flagged_fraction = filter.nis_flagged_fraction;
  record.error_after.whiteness_flagged_fraction = filter.whiteness_flagged_fraction;
  record.error_after.filter_states = filter.filter_states;
}

}  // namespace imu::analyze

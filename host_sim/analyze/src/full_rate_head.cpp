// A long record's two analyses joined: the whole record on block means, its head at
// full rate (analyze.hpp merge_full_rate_head).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "effects.hpp"

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

// Where the means stop resolving: their rate fs_b, Nyquist fs_b / 2, first tau, and the GM-peak
// tau that splits the head's GMs from the record's.
struct Split {
  double fs_b_hz = 0.0;
  double nyquist_hz = 0.0;
  double tau_lo_s = 0.0;
  double tau_split_s = 0.0;
};

// The candidate model: the record's, with the head's fast terms (analyze.hpp). `fits` is false
// when the terms do not fit the model's slots; `dropped` names the record's alias lines.
struct Join {
  ModelParams model{};
  std::vector<FastLine> fast;
  std::vector<std::string> dropped;
  bool fits = true;
};

struct Line {
  double a = 0.0;     // amplitude
  double f_hz = 0.0;
  double ts_s = 0.0;  // the sampling period it was measured at (ModelParams::sin_ts_s)
};

Join join_models(const ModelParams& rec, const ModelParams& hm, const Split& sp,
                 double head_tol_hz) {
  Join j;
  j.model = rec;
  ModelParams& c = j.model;
  c.n = hm.n;
  c.n_filter_s = hm.n_filter_s;  // the sensor's filter is seen at full rate only
  c.q = hm.q;
  const Line head_sines[] = {{hm.sin_a, hm.sin_f0_hz, hm.sin_ts_s},
                             {hm.sin2_a, hm.sin2_f0_hz, hm.sin2_ts_s}};
  const Line rec_sines[] = {{rec.sin_a, rec.sin_f0_hz, rec.sin_ts_s},
                            {rec.sin2_a, rec.sin2_f0_hz, rec.sin2_ts_s}};
  const auto add_fast = [&](double a, double f, double bw) {
    if (a > 0.0 && f > sp.nyquist_hz) {
      j.fast.push_back({f, std::max({0.02 * alias_of(f, sp.fs_b_hz), bw, head_tol_hz})});
    }
  };
  for (const Line& l : head_sines) {
    add_fast(l.a, l.f_hz, 0.0);
  }
  add_fast(hm.osc_sigma, hm.osc_f0_hz, hm.osc_beta_per_s / 3.14159265358979323846);

  std::vector<Line> sines;
  for (const Line& l : rec_sines) {
    if (l.a > 0.0 && is_alias(l.f_hz, j.fast, sp.fs_b_hz)) {
      j.dropped.push_back("sinusoid at " + g4(l.f_hz) + " Hz");
    } else if (l.a > 0.0) {
      sines.push_back(l);
    }
  }
  for (const Line& l : head_sines) {
    if (l.a > 0.0 && l.f_hz > sp.nyquist_hz) {
      sines.push_back(l);
    }
  }
  j.fits = sines.size() <= 2;
  sines.resize(2, Line{});  // two slots (fits says whether more were asked for)
  c.sin_a = sines[0].a;
  c.sin_f0_hz = sines[0].f_hz;
  c.sin_ts_s = sines[0].ts_s;
  c.sin2_a = sines[1].a;
  c.sin2_f0_hz = sines[1].f_hz;
  c.sin2_ts_s = sines[1].ts_s;

  if (c.osc_sigma > 0.0 && is_alias(c.osc_f0_hz, j.fast, sp.fs_b_hz)) {
    j.dropped.push_back("oscillation at " + g4(c.osc_f0_hz) + " Hz");
    c.osc_sigma = c.osc_f0_hz = c.osc_beta_per_s = c.osc_ts_s = 0.0;
  }
  if (hm.osc_sigma > 0.0 && hm.osc_f0_hz > sp.nyquist_hz) {
    j.fits = j.fits && !(c.osc_sigma > 0.0);  // one oscillation slot
    c.osc_sigma = hm.osc_sigma;
    c.osc_f0_hz = hm.osc_f0_hz;
    c.osc_beta_per_s = hm.osc_beta_per_s;
    c.osc_ts_s = hm.osc_ts_s;
  }

  std::vector<GmParam> gms;
  for (std::size_t i = 0; i < hm.n_gm; ++i) {
    if (kGmPeakTauFactor * hm.gm[i].tb_s < sp.tau_split_s) {
      gms.push_back(hm.gm[i]);
    }
  }
  for (std::size_t i = 0; i < rec.n_gm; ++i) {
    if (kGmPeakTauFactor * rec.gm[i].tb_s >= sp.tau_split_s) {
      gms.push_back(rec.gm[i]);
    }
  }
  j.fits = j.fits && gms.size() <= kMaxGmTerms;
  c.n_gm = std::min(gms.size(), kMaxGmTerms);
  std::copy_n(gms.begin(), c.n_gm, c.gm);
  return j;
}

// The joined model is taken: the record's quantization and alias effects go, the head's
// quantization and fast lines come in, with its unexplained runs below the record's first tau;
// the filter figures stay the block means' model's.
void take_join(Report& record, const Join& j, const ErrorStats& on_record, const Split& sp,
               const std::string& where) {
  for (const auto& d : j.dropped) {
    record.notes.push_back("dropped: " + d + " on the block means, the alias of a line the "
                           "full-rate head finds above " + g4(sp.nyquist_hz) + " Hz");
  }
  std::vector<Effect> kept;
  for (auto& e : record.effects) {
    const bool alias = (e.type == "sinusoid" || e.type == "oscillation") &&
                       is_alias(e.freq_hz, j.fast, sp.fs_b_hz);
    if (e.type != "quantization" && !alias) {
      kept.push_back(std::move(e));
    }
  }
  for (const auto& e : record.head.effects) {
    if (e.type == "quantization" ||
        ((e.type == "sinusoid" || e.type == "oscillation") && e.freq_hz > sp.nyquist_hz)) {
      kept.push_back(e);
      record.notes.push_back(e.type + " at full rate (" + where + ")");
    }
  }
  record.effects = std::move(kept);
  for (const auto& u : record.head.unexplained) {
    if (u.tau_max_s < sp.tau_lo_s) {
      record.unexplained.push_back(u);
    }
  }
  const ErrorStats filter = record.error_after;
  record.model_after = j.model;
  name_extra_gms(record.model_after, record.effects);
  record.error_after = on_record;
  record.error_after.cov_ratio = filter.cov_ratio;
  record.error_after.nis_mean = filter.nis_mean;
  record.error_after.nis_flagged_fraction = filter.nis_flagged_fraction;
  record.error_after.whiteness_flagged_fraction = filter.whiteness_flagged_fraction;
  record.error_after.filter_states = filter.filter_states;
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
  h.unexplained = std::move(head.unexplained);

  const double fs = head.fs_hz;
  Split sp;
  sp.fs_b_hz = fs / static_cast<double>(block);
  sp.nyquist_hz = sp.fs_b_hz / 2.0;
  sp.tau_lo_s = 1.0 / sp.fs_b_hz;
  sp.tau_split_s = 4.0 * sp.tau_lo_s;
  const std::string where = "full rate on the first " + std::to_string(head.samples) +
                            " samples (" + g4(static_cast<double>(head.samples) / fs / 3600.0) +
                            " h)";
  const Join j = join_models(record.model_after, head.model_after, sp,
                             2.0 * fs / static_cast<double>(head.samples));
  const ErrorStats on_record =
      score_model(record.adev_clean, j.model, o, sp.tau_lo_s, record.error_after.tau_max_s);
  const auto on_head = [&](const ModelParams& m) {
    return score_model(head.adev_clean, m, o, head.error_after.tau_min_s,
                       head.error_after.tau_max_s);
  };
  const ErrorStats joined_on_head = on_head(j.model);
  if (!j.fits) {
    record.notes.push_back("full-rate head (" + where + "): its fast terms do not fit beside the "
                           "record's in the model's slots (2 GMs, 2 sinusoids, 1 oscillation): "
                           "the record's model is kept; the head's findings are under "
                           "full_rate_head");
  } else if (!no_worse(on_record, record.error_before) ||
             !no_worse(joined_on_head, head.error_before)) {
    record.notes.push_back(
        "full-rate head (" + where + "): the record's model with the head's fast terms would be "
        "worse than the first-order model (record taus: " + errors_text(on_record) + " vs " +
        errors_text(record.error_before) + "; head taus: " + errors_text(joined_on_head) +
        " vs " + errors_text(head.error_before) + "): the record's model is kept");
  } else {
    h.merged = true;
    record.notes.push_back(
        "full-rate head (" + where + "): white noise, quantization, GMs peaking below " +
        g4(sp.tau_split_s) + " s and lines above the means' Nyquist " + g4(sp.nyquist_hz) +
        " Hz come from it; the model's errors on the record's taus " + errors_text(on_record) +
        " (block-means model " + errors_text(record.error_after) + "), on the head's " +
        errors_text(joined_on_head) + " (the head's own after-model " +
        errors_text(head.error_after) + "); its NIS and covariance figures are the block-means "
        "model's");
    take_join(record, j, on_record, sp, where);
  }
  h.error_record_model = h.merged ? joined_on_head : on_head(record.model_after);
}

}  // namespace imu::analyze

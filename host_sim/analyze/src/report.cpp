// JSON, text report and plots of the analysis.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <sstream>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "effects.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/cli/json.hpp"
#include "imu/cli/sensors.hpp"

namespace imu::analyze {
namespace {

std::string num(double v) { return imu::cli::json_num(v); }

std::string quoted(const std::string& s) { return imu::cli::json_str(s); }

std::string gm_list(const GmParam* g, std::size_t n) {
  std::ostringstream s;
  s << "[";
  for (std::size_t i = 0; i < n; ++i) {
    s << (i > 0 ? ", " : "") << "{\"sb\": " << num(g[i].sb) << ", \"tb_s\": " << num(g[i].tb_s)
      << "}";
  }
  s << "]";
  return s.str();
}

// Every term of the model with its parameters, and the state-space size it takes
// (error_model.hpp build_model: GMs 1 state each, the flicker bank 1 per member, RRW 1, ramp 2,
// each sinusoid 2, the oscillation 2).
std::string model_json(const ModelParams& p) {
  std::ostringstream s;
  ContinuousModel<kModelMaxStates> c;
  const bool built = build_model(p, c) == ModelStatus::kOk;
  GmParam bank[kMaxFlickerGm];
  const std::size_t nb =
      p.bi > 0.0 ? flicker_bank(p.bi, p.bi_tau_lo_s, p.bi_tau_hi_s, bank) : 0;
  s << "{\"n\": " << num(p.n) << ", \"n_filter_s\": " << num(p.n_filter_s)
    << ", \"q\": " << num(p.q) << ", \"gm\": " << gm_list(p.gm, p.n_gm)
    << ", \"k\": " << num(p.k) << ", \"r\": " << num(p.r) << ", \"sin_a\": " << num(p.sin_a)
    << ", \"sin_f0_hz\": " << num(p.sin_f0_hz) << ", \"sin2_a\": " << num(p.sin2_a)
    << ", \"sin2_f0_hz\": " << num(p.sin2_f0_hz) << ", \"sin_ts_s\": " << num(p.sin_ts_s)
    << ", \"sin2_ts_s\": " << num(p.sin2_ts_s) << ", \"bias_instability\": {\"b\": "
    << num(p.bi) << ", \"tau_lo_s\": " << num(p.bi_tau_lo_s) << ", \"tau_hi_s\": "
    << num(p.bi_tau_hi_s) << ", \"gm_bank\": " << gm_list(bank, nb)
    << "}, \"oscillation\": {\"sigma\": " << num(p.osc_sigma) << ", \"f0_hz\": "
    << num(p.osc_f0_hz) << ", \"beta_per_s\": " << num(p.osc_beta_per_s)
    << ", \"point_sampled_ts_s\": " << num(p.osc_ts_s) << "}, \"n_states\": "
    << (built ? std::to_string(c.n_states) : std::string("null")) << "}";
  return s.str();
}

std::string error_json(const ErrorStats& e) {
  std::ostringstream s;
  s << "{\"adev_rms_rel\": " << num(e.adev_rms_rel) << ", \"adev_max_rel\": "
    << num(e.adev_max_rel) << ", \"tau_min_s\": " << num(e.tau_min_s) << ", \"tau_max_s\": "
    << num(e.tau_max_s) << ", \"n_taus\": " << e.n_taus
    << ", \"example_range\": {\"adev_rms_rel\": "
    << num(e.example_rms_rel) << ", \"adev_max_rel\": " << num(e.example_max_rel)
    << ", \"tau_min_s\": " << num(e.tau_min_s) << ", \"tau_max_s\": " << num(e.example_tau_max_s)
    << "}, \"cost_sum_z2\": " << num(e.cost) << ", \"covariance_ratio\": " << num(e.cov_ratio)
    << ", \"nis_mean\": " << num(e.nis_mean) << ", \"nis_flagged_fraction\": "
    << num(e.nis_flagged_fraction) << ", \"whiteness_flagged_fraction\": "
    << num(e.whiteness_flagged_fraction) << ", \"filter_states\": " << e.filter_states << "}";
  return s.str();
}

// {"NAME": [lo, hi], ...} (an unbounded end: null).
std::string intervals_json(const std::vector<ParamInterval>& ci) {
  std::ostringstream s;
  s << "{";
  for (std::size_t i = 0; i < ci.size(); ++i) {
    s << (i > 0 ? ", " : "") << quoted(ci[i].name) << ": [" << num(ci[i].lo) << ", "
      << num(ci[i].hi) << "]";
  }
  s << "}";
  return s.str();
}

// " (95 %: NAME lo to hi, ...)" for the text; empty without intervals.
std::string intervals_text(const std::vector<ParamInterval>& ci) {
  std::string t;
  char buf[128];
  for (const ParamInterval& iv : ci) {
    std::snprintf(buf, sizeof buf, "%s%s %.3g to %.3g", t.empty() ? " (95 %: " : ", ",
                  iv.name.c_str(), iv.lo, iv.hi);
    t += buf;
  }
  return t.empty() ? t : t + ")";
}

std::string effect_json(const Effect& e) {
  std::ostringstream s;
  s << "{\"type\": " << quoted(e.type);
  if (const TermInfo* t = effect_term(e)) {
    for (std::size_t j = 0; j < t->n_params; ++j) {
      if (double Effect::*f = effect_field(t->params[j])) {
        s << ", " << quoted(t->params[j].key) << ": " << num(e.*f);
      }
    }
  } else if (e.type == "bias_step") {
    s << ", \"time_s\": " << num(e.time_s) << ", \"size\": " << num(e.size);
  } else if (e.type == "outliers") {
    s << ", \"count\": " << e.count << ", \"times_s\": [";
    for (std::size_t i = 0; i < e.times_s.size(); ++i) {
      s << (i > 0 ? ", " : "") << num(e.times_s[i]);
    }
    s << "]";
  }
  if (!e.ci95.empty()) {
    s << ", \"ci95\": " << intervals_json(e.ci95);
  }
  s << ", \"statistic\": " << num(e.statistic) << ", \"threshold\": " << num(e.threshold) << "}";
  return s.str();
}

// A list of effects, `sep` between them (a line break and indent in the report's main list).
std::string effects_json(const std::vector<Effect>& effects, const char* sep) {
  std::string s;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    s += (i > 0 ? "," : "") + std::string(sep) + effect_json(effects[i]);
  }
  return s;
}

std::string unexplained_json(const std::vector<UnexplainedRun>& runs) {
  std::ostringstream s;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const UnexplainedRun& u = runs[i];
    s << (i > 0 ? ", " : "") << "{\"tau_min_s\": " << num(u.tau_min_s) << ", \"tau_max_s\": "
      << num(u.tau_max_s) << ", \"max_abs_z\": " << num(u.max_abs_z);
    if (u.t_max_s > u.t_min_s) {
      s << ", \"t_min_s\": " << num(u.t_min_s) << ", \"t_max_s\": " << num(u.t_max_s)
        << ", \"what\": " << quoted(u.what);
    }
    s << "}";
  }
  return s.str();
}

// One effect with its parameters and evidence, as the text report prints it (no line break).
std::string effect_text(const Effect& e) {
  char buf[256];
  if (e.type == "quantization") {
    std::snprintf(buf, sizeof buf, "effect quantization: Q = %.4e", e.q);
  } else if (e.type == "rate_random_walk") {
    std::snprintf(buf, sizeof buf, "effect rate_random_walk: K = %.4e", e.k);
  } else if (e.type == "ramp") {
    std::snprintf(buf, sizeof buf, "effect ramp: R = %.4e", e.r);
  } else if (e.type == "sinusoid") {
    std::snprintf(buf, sizeof buf, "effect sinusoid: f = %.6g Hz (period %.4g s), A = %.4e",
                  e.freq_hz, 1.0 / e.freq_hz, e.amplitude);
  } else if (e.type == "oscillation") {
    std::snprintf(buf, sizeof buf,
                  "effect oscillation: f0 = %.5g Hz, half-power width %.3g Hz, sigma = %.4e",
                  e.freq_hz, e.bandwidth_hz, e.amplitude);
  } else if (e.type == "bias_step") {
    std::snprintf(buf, sizeof buf, "effect bias_step: at t = %.1f s, size %.4e", e.time_s,
                  e.size);
  } else if (e.type == "bias_instability") {
    std::snprintf(buf, sizeof buf, "effect bias_instability: B = %.4e (ADEV floor %.4e)", e.b,
                  kFlickerAdevFactor * e.b);
  } else if (e.type == "gauss_markov") {
    std::snprintf(buf, sizeof buf,
                  "effect gauss_markov: a second GM term, sigma = %.4e, Tb = %.4g s (ADEV peak "
                  "%.4e at %.4g s)",
                  e.amplitude, e.tb_s, kGmPeakAdevFactor * std::sqrt(2.0) * e.amplitude,
                  kGmPeakTauFactor * e.tb_s);
  } else {
    std::snprintf(buf, sizeof buf, "effect outliers: %llu samples",
                  static_cast<unsigned long long>(e.count));
  }
  std::string line = buf + intervals_text(e.ci95);
  std::snprintf(buf, sizeof buf, " (statistic %.3g > threshold %.3g)", e.statistic,
                e.threshold);
  return line + buf;
}

// The unit of a report's numbers: the one the reading set (declared or checked), else the
// one its name suggests (imu::cli::guess_sensor), "unit" when it suggests none.
std::string unit_of(const Report& r) {
  return r.unit.empty() ? imu::cli::si_unit(imu::cli::guess_sensor(r.channel)) : r.unit;
}

double model_adev(const ModelParams& p, double tau) { return std::sqrt(model_avar(p, tau)); }

}  // namespace

std::string to_json(const Report& r) {
  std::ostringstream s;
  const std::string unit = unit_of(r);
  s << "{\n  \"channel\": " << quoted(r.channel) << ",\n  \"sensor\": " << quoted(r.sensor)
    << ",\n  \"fs_hz\": " << num(r.fs_hz)
    << ",\n  \"n_samples\": " << r.samples << ",\n  \"lsb\": " << num(r.lsb)
    << ",\n  \"lsb_note\": " << quoted(r.lsb_note) << ",\n  \"unit\": " << quoted(unit)
    << ",\n  \"units\": " << imu::cli::json_units(unit) << ",\n  \"adev\": [";
  for (std::size_t i = 0; i < r.adev.size(); ++i) {
    const AdevPoint& p = r.adev[i];
    s << (i > 0 ? "," : "") << "\n    {\"tau_s\": " << num(p.tau_s) << ", \"adev\": "
      << num(p.adev) << ", \"edf\": " << num(p.edf) << ", \"ci_lo\": " << num(p.ci_lo)
      << ", \"ci_hi\": " << num(p.ci_hi) << ", \"n_terms\": " << p.n_terms << ", \"af\": "
      << p.af << "}";
  }
  s << "\n  ],\n  \"model_before\": " << model_json(r.model_before)
    << ",\n  \"error_before\": " << error_json(r.error_before) << ",\n  \"effects\": [";
  s << effects_json(r.effects, "\n    ");
  s << (r.effects.empty() ? "" : "\n  ") << "],\n  \"model_after\": " << model_json(r.model_after)
    << ",\n  \"model_after_ci95\": " << intervals_json(r.model_after_ci95)
    << ",\n  \"error_after\": " << error_json(r.error_after) << ",\n  \"notes\": [";
  for (std::size_t i = 0; i < r.notes.size(); ++i) {
    s << (i > 0 ? ", " : "") << quoted(r.notes[i]);
  }
  s << "],\n  \"unexplained\": [" << unexplained_json(r.unexplained) << "]";
  if (r.head.samples > 0) {
    const FullRateHead& h = r.head;
    s << ",\n  \"full_rate_head\": {\"n_samples\": " << h.samples << ", \"fs_hz\": "
      << num(h.fs_hz) << ", \"block\": " << h.block << ", \"merged\": "
      << (h.merged ? "true" : "false") << ",\n    \"model_before\": "
      << model_json(h.model_before) << ",\n    \"error_before\": " << error_json(h.error_before)
      << ",\n    \"effects\": [" << effects_json(h.effects, " ")
      << "],\n    \"model_after\": " << model_json(h.model_after)
      << ",\n    \"error_after\": " << error_json(h.error_after)
      << ",\n    \"error_record_model\": " << error_json(h.error_record_model)
      << ",\n    \"unexplained\": [" << unexplained_json(h.unexplained) << "]}";
  }
  s << ",\n  \"gaps\": {\"samples\": " << r.gap_samples << ", \"runs\": " << r.gap_runs
    << "},\n  \"timing_s\": {\"total\": " << num(r.seconds) << ", \"cpu\": " << num(r.cpu_seconds)
    << "}\n}\n";
  return s.str();
}

namespace {

struct NamedTerm {
  std::string type;
  double value;
};

// The terms of a model beyond white noise and its first GM, each with its main parameter.
std::vector<NamedTerm> terms_beyond_first_order(const ModelParams& m) {
  std::vector<NamedTerm> t;
  for (const TermInfo& row : kTermTable) {
    for (std::size_t i = base_instances(row.kind); i < row.max_instances; ++i) {
      const double v = term_param(m, row.kind, i, row.main_param);
      if (std::fabs(v) > 0.0) {
        t.push_back(NamedTerm{row.name, v});
      }
    }
  }
  return t;
}

}  // namespace

bool gm_stands_in_for_walk(const Report& r) {
  if (r.model_after.n_gm != 1 || r.model_after.k > 0.0) {
    return false;
  }
  for (const Effect& e : r.effects) {
    if (e.type == "rate_random_walk") {
      return false;
    }
  }
  for (const ParamInterval& iv : r.model_after_ci95) {
    if (iv.name == "gm_tb_s") {
      return std::isinf(iv.hi);
    }
  }
  return false;
}

bool report_consistent(const Report& r, std::string& why) {
  std::vector<NamedTerm> named;
  for (const auto& e : r.effects) {
    if (e.type != "bias_step" && e.type != "outliers") {
      named.push_back(NamedTerm{e.type, effect_size(e)});
    }
  }
  for (const auto& t : terms_beyond_first_order(r.model_after)) {
    bool found = false;
    for (auto it = named.begin(); it != named.end(); ++it) {
      if (it->type == t.type &&
          std::fabs(it->value - t.value) <= 1e-9 * std::max(std::fabs(t.value), 1e-300)) {
        named.erase(it);
        found = true;
        break;
      }
    }
    if (!found) {
      why = "model_after holds " + t.type + " = " + num(t.value) +
            " and no effect names it with that value";
      return false;
    }
  }
  if (!named.empty()) {
    why = "effect " + named.front().type + " = " + num(named.front().value) +
          " is not a term of model_after";
    return false;
  }
  // Each effect's line says "(statistic S > threshold T)": its evidence must pass its own test.
  for (const auto& e : r.effects) {
    if (!(e.statistic > e.threshold)) {
      why = "effect " + e.type + " states statistic " + num(e.statistic) + " > threshold " +
            num(e.threshold) + ", which does not hold";
      return false;
    }
  }
  // The text: one "effect " line per effect; "effects: none (...)" only without effects.
  const std::string text = to_text(r);
  std::size_t lines = 0;
  for (std::size_t at = 0; (at = text.find("\neffect ", at)) != std::string::npos; ++at) {
    ++lines;
  }
  if (lines != r.effects.size()) {
    why = "the text lists " + std::to_string(lines) + " effects, the report " +
          std::to_string(r.effects.size());
    return false;
  }
  if (r.effects.empty() != (text.find("\neffects: none (") != std::string::npos)) {
    why = "the text's \"effects: none\" line disagrees with the effect list";
    return false;
  }
  return true;
}

namespace {

// One model's line of the text report.
void model_text(std::ostringstream& s, const char* name, const ModelParams& p) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "%s: N = %.4e", name, p.n);
  s << buf;
  if (p.n_filter_s > 0.0) {
    std::snprintf(buf, sizeof buf, " (through an output filter of %.3g ms)", 1e3 * p.n_filter_s);
    s << buf;
  }
  if (p.q > 0.0) {
    std::snprintf(buf, sizeof buf, ", Q = %.4e", p.q);
    s << buf;
  }
  for (std::size_t i = 0; i < p.n_gm; ++i) {
    std::snprintf(buf, sizeof buf, ", GM Sb = %.4e Tb = %.1f s (peak ADEV %.3e)", p.gm[i].sb,
                  p.gm[i].tb_s, kGmPeakAdevFactor * std::sqrt(p.gm[i].sb * p.gm[i].tb_s));
    s << buf;
  }
  if (p.k > 0.0) {
    std::snprintf(buf, sizeof buf, ", K = %.4e", p.k);
    s << buf;
  }
  if (p.r > 0.0) {
    std::snprintf(buf, sizeof buf, ", R = %.4e", p.r);
    s << buf;
  }
  if (p.sin_a > 0.0) {
    std::snprintf(buf, sizeof buf, ", sinusoid A = %.4e f0 = %.5g Hz", p.sin_a, p.sin_f0_hz);
    s << buf;
  }
  if (p.sin2_a > 0.0) {
    std::snprintf(buf, sizeof buf, ", sinusoid A = %.4e f0 = %.5g Hz", p.sin2_a, p.sin2_f0_hz);
    s << buf;
  }
  if (p.osc_sigma > 0.0) {
    std::snprintf(buf, sizeof buf,
                  ", oscillation sigma = %.4e f0 = %.5g Hz beta = %.3g /s (ADEV of %s)",
                  p.osc_sigma, p.osc_f0_hz, p.osc_beta_per_s,
                  p.osc_ts_s > 0.0 ? "point samples" : "averages over each sample period");
    s << buf;
  }
  if (p.bi > 0.0) {
    std::snprintf(buf, sizeof buf, ", bias instability B = %.4e (flicker bank over [%.3g, %.4g] s)",
                  p.bi, p.bi_tau_lo_s, p.bi_tau_hi_s);
    s << buf;
  }
  s << "\n";
}

// One model's error line (its ADEV against the data's, and its bias filter's checks).
void error_text(std::ostringstream& s, const char* name, const ErrorStats& e) {
  char buf[512];
  if (e.filter_states == 0) {
    // White noise alone (a failed fit's fallback): no bias state, so no filter to check.
    std::snprintf(buf, sizeof buf,
                  "%s: |ADEV_model/ADEV_data - 1| RMS %.3f max %.3f over %zu taus [%.3g, %.4g] s;"
                  " no bias filter (the model has no state)\n",
                  name, e.adev_rms_rel, e.adev_max_rel, e.n_taus, e.tau_min_s, e.tau_max_s);
    s << buf;
    return;
  }
  std::snprintf(buf, sizeof buf,
                "%s: |ADEV_model/ADEV_data - 1| RMS %.3f max %.3f over %zu taus [%.3g, %.4g] s;"
                " RMS %.3f max %.3f over [%.3g, %.4g] s; covariance ratio %.3f; NIS mean %.3f "
                "(%zu-state filter; innovation blocks flagged: NIS %.0f %%, whiteness %.0f %%)\n",
                name, e.adev_rms_rel, e.adev_max_rel, e.n_taus, e.tau_min_s, e.tau_max_s,
                e.example_rms_rel, e.example_max_rel, e.tau_min_s, e.example_tau_max_s,
                e.cov_ratio, e.nis_mean, e.filter_states, 100.0 * e.nis_flagged_fraction,
                100.0 * e.whiteness_flagged_fraction);
  s << buf;
}

// The effects line when none is named. The terms the model after holds beyond white noise and
// one GM are each said: the effect list never reads as if the model after were the first-order
// one when it is not.
std::string no_effects_text(const ModelParams& m) {
  std::string held;
  for (const auto& t : terms_beyond_first_order(m)) {
    held += (held.empty() ? "" : ", ") + t.type;
  }
  // The sensor's output filter is a property of the white noise, not a term: said here.
  const std::string white =
      m.n_filter_s > 0.0 ? "white noise through the sensor's output filter" : "white noise";
  return held.empty()
             ? (m.n_gm == 0 ? "effects: none (" + white + " only; see notes)\n"
                            : "effects: none (" + white + " and one GM term; the model after "
                              "is that model refitted over [Ts, T/10])\n")
             : "effects: none named; the model after also holds " + held + " (see notes)\n";
}

void unexplained_text(std::ostringstream& s, const std::vector<UnexplainedRun>& runs) {
  char buf[512];
  if (runs.empty()) {
    s << "unexplained: nothing (the model after is inside the intervals, no significant run)\n";
  }
  for (const auto& u : runs) {
    if (u.t_max_s > u.t_min_s) {
      std::snprintf(buf, sizeof buf, "unexplained: t %.6g - %.6g s (tau %.3g - %.4g s): ",
                    u.t_min_s, u.t_max_s, u.tau_min_s, u.tau_max_s);
      s << buf << u.what << "\n";
      continue;
    }
    std::snprintf(buf, sizeof buf,
                  "unexplained: tau %.3g - %.4g s, max |z| %.1f (model %s the data)\n",
                  u.tau_min_s, u.tau_max_s, u.max_abs_z, u.sign > 0 ? "above" : "below");
    s << buf;
  }
}

void head_text(std::ostringstream& s, const FullRateHead& h) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "full-rate head: the first %llu samples at %g Hz (%.2f h), analysed on their "
                "own; %s\n",
                static_cast<unsigned long long>(h.samples), h.fs_hz,
                static_cast<double>(h.samples) / h.fs_hz / 3600.0,
                h.merged ? "its fast terms are in the model after (notes)"
                         : "the model after is the block means' (notes)");
  s << buf;
  error_text(s, "  head, error before", h.error_before);
  model_text(s, "  head, model after", h.model_after);
  error_text(s, "  head, error after", h.error_after);
  std::snprintf(buf, sizeof buf,
                "  head, the model after above: RMS %.3f max %.3f over its %zu taus\n",
                h.error_record_model.adev_rms_rel, h.error_record_model.adev_max_rel,
                h.error_record_model.n_taus);
  s << buf;
  for (const auto& e : h.effects) {
    s << "  head, " << effect_text(e) << "\n";
  }
}

}  // namespace

std::string to_text(const Report& r) {
  std::ostringstream s;
  char buf[512];
  std::snprintf(buf, sizeof buf, "channel %s: %llu samples at %g Hz (%.1f s), %s\n",
                r.channel.c_str(), static_cast<unsigned long long>(r.samples), r.fs_hz,
                static_cast<double>(r.samples) / r.fs_hz, r.lsb_note.c_str());
  s << buf;
  if (r.gap_samples > 0) {
    std::snprintf(buf, sizeof buf, "gaps: %llu missing samples in %llu runs\n",
                  static_cast<unsigned long long>(r.gap_samples),
                  static_cast<unsigned long long>(r.gap_runs));
    s << buf;
  }
  model_text(s,
             r.model_before.n_gm > 0 ? "model before (white + GM over [Ts, 100 s])"
                                     : "model before (white noise only: the white + GM fit "
                                       "failed, see notes)",
             r.model_before);
  error_text(s, "error before", r.error_before);
  if (r.effects.empty()) {
    s << no_effects_text(r.model_after);
  }
  for (const auto& e : r.effects) {
    s << effect_text(e) << "\n";
  }
  model_text(s, "model after (joint fit over [Ts, T/10])", r.model_after);
  if (!r.model_after_ci95.empty()) {
    s << "model after, its white noise and GM" << intervals_text(r.model_after_ci95) << "\n";
  }
  error_text(s, "error after", r.error_after);
  unexplained_text(s, r.unexplained);
  if (r.head.samples > 0) {
    head_text(s, r.head);
  }
  for (const auto& n : r.notes) {
    s << "note: " << n << "\n";
  }
  std::snprintf(buf, sizeof buf, "analysis time %.2f s wall, %.2f s CPU\n", r.seconds,
                r.cpu_seconds);
  s << buf;
  return s.str();
}

namespace {

// The components the plots draw under the total: one per instance of each row of the term
// registry (a row that holds two, e.g. the GMs, gets two, numbered).
struct TermColumn {
  TermKind kind;
  std::size_t instance;
  std::string name;   // CSV column (after_NAME, before_NAME)
  std::string title;  // plot key
};

const std::vector<TermColumn>& term_columns() {
  static const std::vector<TermColumn> columns = [] {
    std::vector<TermColumn> c;
    for (const TermInfo& t : kTermTable) {
      for (std::size_t i = 0; i < t.max_instances; ++i) {
        const std::string n = t.max_instances > 1 ? std::to_string(i + 1) : std::string();
        c.push_back(TermColumn{t.kind, i, std::string(t.name) + (n.empty() ? "" : "_" + n),
                               std::string(t.label) + (n.empty() ? "" : " " + n)});
      }
    }
    return c;
  }();
  return columns;
}

// The ADEV of each term column of a model at tau (0 where the term is absent).
std::vector<double> term_adevs(const ModelParams& p, double tau) {
  std::vector<double> out;
  for (const TermColumn& c : term_columns()) {
    out.push_back(std::sqrt(term_avar(p, c.kind, c.instance, tau)));
  }
  return out;
}

// A path made absolute (so the .gp script works from any directory).
std::string absolute(const std::string& path) {
  char* real = ::realpath(path.c_str(), nullptr);
  if (real == nullptr) {
    return path;
  }
  std::string out(real);
  std::free(real);  // NOLINT(cppcoreguidelines-no-malloc): realpath's buffer
  return out;
}

std::string gq(const std::string& s) { return imu::cli::gnuplot_str(s); }

}  // namespace

namespace {

// The ADEV table of the plots: the data raw and cleaned with their intervals, both models and
// each term of each.
std::string adev_csv_text(const Report& r) {
  std::ostringstream f;
  f << "tau_s,adev_raw,ci_lo_raw,ci_hi_raw,adev_clean,ci_lo_clean,ci_hi_clean,model_before,"
       "model_after";
  for (const TermColumn& t : term_columns()) {
    f << ",after_" << t.name;
  }
  for (const TermColumn& t : term_columns()) {
    f << ",before_" << t.name;
  }
  f << "\n";
  for (std::size_t i = 0; i < r.adev.size(); ++i) {
    const AdevPoint& p = r.adev[i];
    const AdevPoint& c = i < r.adev_clean.size() ? r.adev_clean[i] : p;
    f << num(p.tau_s) << ',' << num(p.adev) << ',' << num(p.ci_lo) << ',' << num(p.ci_hi) << ','
      << num(c.adev) << ',' << num(c.ci_lo) << ',' << num(c.ci_hi) << ','
      << num(model_adev(r.model_before, p.tau_s)) << ','
      << num(model_adev(r.model_after, p.tau_s));
    for (const double v : term_adevs(r.model_after, p.tau_s)) {
      f << ',' << num(v);
    }
    for (const double v : term_adevs(r.model_before, p.tau_s)) {
      f << ',' << num(v);
    }
    f << '\n';
  }
  return f.str();
}

// One script that draws both figures (before, after) in SVG and PNG from the table at csv;
// every path in it is absolute and titles are noenhanced (a channel name like acc_z is not a
// subscript).
std::string adev_script_text(const Report& r, const std::string& base, const std::string& csv,
                             const std::string& gp) {
  const double tau_fit_hi = r.error_after.tau_max_s;
  const double tau_fit_lo = r.error_after.tau_min_s;
  std::ostringstream g;
  g << "# ADEV of " << imu::cli::term_safe(r.channel)
    << ": data with its 68 % interval, the model and its terms.\n"
    << "# Run from any directory: gnuplot " << gq(gp) << "\n"
    << "set datafile separator ','\nset logscale xy\nset format y '%.0e'\nset grid\n"
    << "set key bottom left noenhanced\nset xlabel 'tau [s]'\n"
    << "set ylabel " << gq("Allan deviation [" + unit_of(r) + "]") << "\n"
    << "set style line 9 lc rgb '#888888' dt 2\n"
    << "set arrow 1 from " << num(tau_fit_lo) << ", graph 0 to " << num(tau_fit_lo)
    << ", graph 1 nohead ls 9\n"
    << "set arrow 2 from " << num(tau_fit_hi) << ", graph 0 to " << num(tau_fit_hi)
    << ", graph 1 nohead ls 9\n"
    << "set label 1 'fitted range' at " << num(tau_fit_lo) << ", graph 0.97 offset 1,0\n";
  // Only the terms the model holds are drawn (and keyed).
  const auto present = [&r](const ModelParams& m, std::size_t t) {
    const TermColumn& c = term_columns()[t];
    for (const AdevPoint& p : r.adev) {
      if (term_avar(m, c.kind, c.instance, p.tau_s) > 0.0) {
        return true;
      }
    }
    return false;
  };
  const auto figure = [&](const char* which, int data_col, int model_col, int first_term,
                          const ModelParams& m, const char* title) {
    for (const char* term : {"svg size 900,600", "pngcairo size 900,600"}) {
      const bool svg = std::string(term).rfind("svg", 0) == 0;
      g << "set terminal " << term << "\nset output "
        << gq(base + "_" + which + (svg ? ".svg" : ".png")) << "\n"
        << "set title " << gq(r.channel + ": " + title) << " noenhanced\n"
        << "plot " << gq(csv) << " skip 1 using 1:" << data_col << ":" << data_col + 1 << ":"
        << data_col + 2 << " with yerrorbars title 'data (68 % interval)', '' skip 1 using 1:"
        << model_col << " with lines lw 2 title 'model'";
      for (std::size_t t = 0; t < term_columns().size(); ++t) {
        if (!present(m, t)) {
          continue;
        }
        g << ", '' skip 1 using 1:($" << first_term + static_cast<int>(t) << " > 0 ? $"
          << first_term + static_cast<int>(t) << " : 1/0) with lines dt 2 title "
          << gq(term_columns()[t].title);
      }
      g << "\n";
    }
  };
  figure("before", 2, 8, 10 + static_cast<int>(term_columns().size()), r.model_before,
         "before (white + GM over [Ts, 100 s])");
  figure("after", 5, 9, 10, r.model_after,
         "after (joint fit with the effects found; data cleaned)");
  return g.str();
}

}  // namespace

bool write_plots(const Report& r, const std::string& dir, const std::string& stem,
                 std::string& message) {
  // One naming rule with adev's plots (adev_NAME, mdev_NAME): what, then the channel, then the
  // part: analyze_NAME_adev.csv, analyze_NAME_{before,after}.{svg,png}.
  const std::string base = absolute(dir) + "/analyze_" + imu::cli::safe_component(stem);
  const std::string csv = base + "_adev.csv";
  if (!imu::cli::write_file_atomic(csv, adev_csv_text(r), message)) {
    return false;
  }
  message = "wrote " + csv;
  if (!imu::cli::gnuplot_available()) {
    message += "; gnuplot not found: no SVG/PNG (install gnuplot-nox)";
    return true;
  }
  const std::string gp = base + "_adev.gp";
  if (!imu::cli::write_file_atomic(gp, adev_script_text(r, base, csv, gp), message)) {
    return false;
  }
  // The path passed check_output_dir: no control characters.
  if (!imu::cli::gnuplot_run(gp)) {
    message = "gnuplot failed on " + gp + " (the CSV and the script were written)";
    return false;
  }
  message += ", " + base + "_{before,after}.{svg,png} (" + gp + ")";
  return true;
}

namespace {

constexpr double kFlickerFloor = 0.664;  // sqrt(2 ln 2 / pi): ADEV floor of B (IEEE 952)

// The line of log-log slope `slope` through the point of r's ADEV where the data's slope is
// nearest it (within 0.25; else not found): its log10 intercept, and that point's tau.
struct SlopeLine {
  bool found = false;
  double intercept = 0.0;
  double tau_s = 0.0;
};

SlopeLine read_off(const Report& r, double slope) {
  double best = 0.25;
  SlopeLine line;
  for (std::size_t i = 0; i + 1 < r.adev.size(); ++i) {
    const AdevPoint& p = r.adev[i];
    const AdevPoint& q = r.adev[i + 1];
    if (!(p.adev > 0.0 && q.adev > 0.0 && q.tau_s > p.tau_s)) {
      continue;
    }
    const double d = (std::log10(q.adev) - std::log10(p.adev)) /
                     (std::log10(q.tau_s) - std::log10(p.tau_s));
    if (std::fabs(d - slope) < best) {
      best = std::fabs(d - slope);
      line = SlopeLine{true, std::log10(p.adev) - slope * std::log10(p.tau_s), p.tau_s};
    }
  }
  return line;
}

// Axis `a` of a sensor's plot: its ADEV rows in `csv`, its points and the IEEE 952 lines read
// off it (N at 1 s, K at 3 s, B's floor) in `plot`, each line's reading point in `marks`.
void sensor_axis(const Report& r, std::size_t a, const char* colour, const std::string& base,
                 std::ostringstream& csv, std::ostringstream& plot, std::ostringstream& marks) {
  for (const AdevPoint& p : r.adev) {
    csv << a << "," << num(p.tau_s) << "," << num(p.adev) << "," << num(p.ci_lo) << ","
        << num(p.ci_hi) << "," << imu::cli::json_str(r.channel) << "\n";
  }
  const SlopeLine ln = read_off(r, -0.5);
  const SlopeLine lk = read_off(r, 0.5);
  const SlopeLine lb = read_off(r, 0.0);
  const double n = std::pow(10.0, ln.intercept);                           // the line at 1 s
  const double k = std::pow(10.0, lk.intercept + 0.5 * std::log10(3.0));  // at 3 s
  const double b = std::pow(10.0, lb.intercept) / kFlickerFloor;
  const std::string c = std::string("'") + colour + "'";
  const std::string& name = r.channel;
  plot << (a > 0 ? ", " : "") << "'" << base << ".csv' skip 1 using 2:(column(1) == " << a
       << " ? $3 : 1/0):4:5 with yerrorbars pt 7 ps 0.4 lc rgb " << c << " title "
       << gq(name + " ADEV");
  const auto mark = [&marks, &c](double tau, double value) {
    marks << "set object circle at " << num(tau) << "," << num(value) << " size screen 0.006 fc "
          << "rgb " << c << " fs solid\n";
  };
  if (ln.found) {
    plot << ", " << num(n) << " / sqrt(x) with lines dt 2 lc rgb " << c << " title "
         << gq(name + " N = " + imu::cli::num_text(n));
    mark(1.0, n);
  }
  if (lk.found) {
    plot << ", " << num(k) << " * sqrt(x / 3.0) with lines dt 3 lc rgb " << c << " title "
         << gq(name + " K = " + imu::cli::num_text(k));
    mark(3.0, k);
  }
  if (lb.found) {
    plot << ", " << num(kFlickerFloor * b) << " with lines dt 4 lc rgb " << c << " title "
         << gq(name + " B = " + imu::cli::num_text(b));
    mark(lb.tau_s, kFlickerFloor * b);
  }
}

}  // namespace

bool write_sensor_plots(const std::vector<Report>& reports, const std::string& dir,
                        std::string& message) {
  message.clear();
  const char* colours[3] = {"#1f77b4", "#d62728", "#2ca02c"};
  const std::string abs = absolute(dir);
  for (const char* sensor : {"accelerometer", "gyroscope"}) {
    std::vector<const Report*> axes;
    for (const Report& r : reports) {
      if (r.sensor == sensor && !r.adev.empty() && axes.size() < 3) {
        axes.push_back(&r);
      }
    }
    if (axes.empty()) {
      continue;
    }
    const std::string base = std::string("analyze_") + sensor;
    std::ostringstream csv;
    csv << "axis,tau_s,adev,ci_lo,ci_hi,channel\n";
    std::ostringstream gp;
    gp << "# " << sensor << ": the ADEV of each axis and the IEEE 952 lines read off it.\n"
       << "set datafile separator ','\nset logscale xy\nset format x '10^{%L}'\n"
       << "set format y '10^{%L}'\nset grid xtics ytics mxtics mytics lc rgb '#dddddd'\n"
       << "set key bottom left box opaque noenhanced font ',9'\nset xlabel 'tau [s]'\n"
       << "set ylabel " << gq("Allan deviation [" + unit_of(*axes[0]) + "]") << "\n"
       << "set title " << gq(std::string(sensor) +
                             ": ADEV per axis, IEEE Std 952 lines read off the slopes -1/2, "
                             "+1/2, 0 (N at 1 s, K at 3 s)")
       << " noenhanced\nset samples 200\n";
    std::ostringstream plot;
    plot << "plot ";
    std::ostringstream marks;
    for (std::size_t a = 0; a < axes.size(); ++a) {
      sensor_axis(*axes[a], a, colours[a], base, csv, plot, marks);
    }
    gp << marks.str() << plot.str() << "\n";
    std::string path = abs;
    path += "/";
    path += base;
    std::string err;
    if (!imu::cli::write_file_atomic(path + ".csv", csv.str(), err) ||
        !imu::cli::write_file_atomic(path + ".gp", gp.str(), err)) {
      message = err;
      return false;
    }
    const bool have = imu::cli::gnuplot_available();
    if (have && !imu::cli::gnuplot_render(abs, base, 700)) {
      message = "gnuplot failed on ";
      message += path;
      message += ".gp (see the .gnuplot.log beside it)";
      return false;
    }
    message += message.empty() ? "" : "; ";
    message += path;
    message += have ? ".{csv,gp,svg,png}" : ".{csv,gp} (no gnuplot)";
  }
  return true;
}

}  // namespace imu::analyze

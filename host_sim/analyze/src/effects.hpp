// Effects that name a model's terms, over the term registry (internal to the analysis: analyze.cpp,
// full_rate_head.cpp, report.cpp).
#ifndef IMU_ANALYZE_EFFECTS_HPP
#define IMU_ANALYZE_EFFECTS_HPP

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/model_fit.hpp"
#include "imu/terms.hpp"

namespace imu::analyze {

/// The bit that stands for the sinusoids in the analysis's term sets (FitTerm bits otherwise:
/// the ADEV fit has no sinusoid basis, the sinusoids are fitted in the time domain).
inline constexpr std::uint32_t kSineBit = 1U << 31;

/// Instances of a kind that belong to the first-order model every report starts from (white
/// noise and its first GM): they are never effects.
inline std::size_t base_instances(TermKind k) { return term_info(k).first_order; }

/// The analysis's bit for a kind: its fit basis (the second GM's for the GM, whose first is in
/// the base model), kSineBit for the sinusoids.
inline std::uint32_t analysis_bit(const TermInfo& t) {
  if (t.kind == TermKind::kSinusoid) {
    return kSineBit;
  }
  return t.kind == TermKind::kGaussMarkov ? kFitGm2 : t.fit_bit;
}

/// The registry row of an effect's type; nullptr for what cleans the record instead of
/// modelling it (bias_step, outliers).
inline const TermInfo* effect_term(const Effect& e) { return term_by_name(e.type.c_str()); }

/// The Effect field that reports a term's parameter (by the parameter's JSON key); nullptr for
/// the parameters an effect does not report (the flicker bank's range, white noise's).
inline double Effect::*effect_field(const TermParamInfo& p) {
  struct Field {
    const char* key;
    double Effect::*field;
  };
  static constexpr Field kFields[] = {
      {"q", &Effect::q},           {"k", &Effect::k},
      {"r", &Effect::r},           {"b", &Effect::b},
      {"freq_hz", &Effect::freq_hz}, {"amplitude", &Effect::amplitude},
      {"sigma", &Effect::amplitude}, {"bandwidth_hz", &Effect::bandwidth_hz},
      {"tb_s", &Effect::tb_s}};
  for (const Field& f : kFields) {
    if (p.key != nullptr && std::string_view(p.key) == f.key) {
      return f.field;
    }
  }
  return nullptr;
}

/// The main parameter of an effect that names a term (Q, K, R, B, A, sigma); 0 for others.
inline double effect_size(const Effect& e) {
  const TermInfo* t = effect_term(e);
  double Effect::*f = t != nullptr ? effect_field(t->params[t->main_param]) : nullptr;
  return f != nullptr ? e.*f : 0.0;
}

/// AVAR at tau of the term an effect of type `type` names in p (its instances beyond the base
/// model); -1 if `type` is not a term of the ADEV fit (the sinusoid, bias_step, outliers).
inline double effect_term_avar(const std::string& type, const ModelParams& p, double tau) {
  const TermInfo* t = term_by_name(type.c_str());
  if (t == nullptr || t->fit_bit == 0U || t->kind == TermKind::kWhite) {
    return -1.0;
  }
  double v = 0.0;
  for (std::size_t i = base_instances(t->kind); i < t->max_instances; ++i) {
    v += term_avar(p, t->kind, i, tau);
  }
  return v;
}

/// Makes the gauss_markov effects exactly the GMs of p beyond the first (sigma = sqrt(Sb Tb / 2),
/// Tb), keeping the evidence of the one the search accepted; a GM that came in with bias
/// instability (the pair is one candidate) carries that effect's evidence.
inline void name_extra_gms(const ModelParams& p, std::vector<Effect>& effects) {
  double statistic = 0.0;
  double threshold = 0.0;
  bool have = false;
  std::vector<Effect> kept;
  for (auto& e : effects) {
    if (e.type == "gauss_markov") {
      statistic = have ? statistic : e.statistic;
      threshold = have ? threshold : e.threshold;
      have = true;
    } else {
      kept.push_back(std::move(e));
    }
  }
  if (!have) {
    for (const auto& e : kept) {
      if (e.type == "bias_instability") {
        statistic = e.statistic;
        threshold = e.threshold;
      }
    }
  }
  for (std::size_t i = 1; i < p.n_gm; ++i) {
    Effect e;
    e.type = "gauss_markov";
    e.amplitude = std::sqrt(p.gm[i].sb * p.gm[i].tb_s / 2.0);
    e.tb_s = p.gm[i].tb_s;
    e.statistic = statistic;
    e.threshold = threshold;
    kept.push_back(e);
  }
  effects = std::move(kept);
}

}  // namespace imu::analyze

#endif  // IMU_ANALYZE_EFFECTS_HPP

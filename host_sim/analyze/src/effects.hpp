// Effects that name a model's terms (internal to the analysis: analyze.cpp, full_rate_head.cpp).
#ifndef IMU_ANALYZE_EFFECTS_HPP
#define IMU_ANALYZE_EFFECTS_HPP

#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "imu/analyze/analyze.hpp"

namespace imu::analyze {

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

// The node's model tuned by the record's Whittle likelihood (imu/analyze/node_tuning.hpp), on
// records simulated from a known model as the node sees it (its averaging sampler): a model
// given with wrong fast parameters comes back to the truth, an oscillation the model lacks is
// added (room made for it in a model that fills the node), none is added to a record without
// one, and a record without a long enough finite stretch is left alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "imu/analyze/node_tuning.hpp"
#include "imu/error_model.hpp"
#include "imu/node/node.hpp"
#include "imu/noise_sim.hpp"

namespace {

constexpr double kFsHz = 100.0;

// White N through a 2 ms output filter, a fast GM (sigma 4e-3, Tb 0.2 s), a slow one (sigma
// 1e-3, Tb 100 s), and with_osc: a narrowband oscillation (sigma 8e-3, 8 Hz, beta 2 /s).
imu::hal::ModelRecord truth(bool with_osc) {
  imu::hal::ModelRecord r{};
  r.version = imu::hal::kModelVersion2;
  r.n = 3e-3F;
  r.n_filter_s = 2e-3F;
  r.gm_sb[0] = static_cast<float>(2.0 * 4e-3 * 4e-3 / 0.2);  // Sb = 2 sigma^2 / Tb
  r.gm_tb_s[0] = 0.2F;
  r.gm_sb[1] = static_cast<float>(2.0 * 1e-3 * 1e-3 / 100.0);
  r.gm_tb_s[1] = 100.0F;
  if (with_osc) {
    r.osc_sigma = 8e-3F;
    r.osc_f0_hz = 8.0F;
    r.osc_beta_per_s = 2.0F;
  }
  return r;
}

// n samples of rec's process as the node's averaging sampler sees it.
std::vector<double> simulate(const imu::hal::ModelRecord& rec, std::size_t n,
                             std::uint64_t seed) {
  imu::ModelParams p{};
  EXPECT_TRUE(imu::node::model_record_valid(rec, p));
  imu::ContinuousModel<8> cm{};
  imu::DiscreteModel<8> dm{};
  imu::ModelSimulator<8> sim;
  EXPECT_EQ(imu::build_model(p, cm), imu::ModelStatus::kOk);
  EXPECT_EQ(imu::discretize_averaged(cm, 1.0 / kFsHz, dm), imu::ModelStatus::kOk);
  EXPECT_EQ(sim.configure(dm, seed), imu::ModelStatus::kOk);
  std::vector<double> x(n);
  for (double& v : x) {
    v = sim.next();
  }
  return x;
}

double rel(float got, float want) {
  return std::fabs(static_cast<double>(got) / static_cast<double>(want) - 1.0);
}

TEST(NodeTuning, WrongFastParametersComeBackToTheTruth) {
  const imu::hal::ModelRecord t = truth(true);
  const std::vector<double> x = simulate(t, std::size_t{1} << 20U, 7301);
  imu::hal::ModelRecord r = t;
  r.n *= 1.3F;
  r.n_filter_s *= 0.5F;
  r.gm_tb_s[0] *= 2.0F;
  r.osc_sigma *= 0.7F;
  r.osc_f0_hz = 8.6F;
  r.osc_beta_per_s = 4.0F;
  const imu::analyze::NodeTuning tn = imu::analyze::tune_node_record(x.data(), x.size(), kFsHz, r);
  std::printf("%s\n", tn.note.c_str());
  EXPECT_TRUE(tn.tuned);
  EXPECT_FALSE(tn.oscillation_added);
  EXPECT_GT(tn.two_ln_lr, 100.0);
  EXPECT_LT(rel(r.n, t.n), 0.05);
  EXPECT_LT(rel(r.osc_f0_hz, t.osc_f0_hz), 0.01);
  EXPECT_LT(rel(r.osc_sigma, t.osc_sigma), 0.1);
  EXPECT_LT(rel(r.osc_beta_per_s, t.osc_beta_per_s), 0.3);
  EXPECT_LT(rel(r.gm_tb_s[0], t.gm_tb_s[0]), 0.3);
  // The slow GM lies below the band: held.
  EXPECT_EQ(r.gm_tb_s[1], t.gm_tb_s[1]);
  EXPECT_EQ(r.gm_sb[1], t.gm_sb[1]);
}

TEST(NodeTuning, AnOscillationTheModelLacksIsAdded) {
  const imu::hal::ModelRecord t = truth(true);
  const std::vector<double> x = simulate(t, std::size_t{1} << 20U, 7302);
  imu::hal::ModelRecord r = truth(false);
  const imu::analyze::NodeTuning tn = imu::analyze::tune_node_record(x.data(), x.size(), kFsHz, r);
  std::printf("%s\n", tn.note.c_str());
  EXPECT_TRUE(tn.oscillation_added);
  EXPECT_GT(tn.oscillation_two_ln_lr, tn.oscillation_level);
  EXPECT_LT(rel(r.osc_f0_hz, t.osc_f0_hz), 0.01);
  EXPECT_LT(rel(r.osc_sigma, t.osc_sigma), 0.1);
}

// A model that fills the node's 8 states (the two GMs, the output filter and a 5-member
// bias-instability bank) makes room for the oscillation the record holds: the bank's short end
// moves up (its members there lie where the white noise dominates) and the result still runs.
TEST(NodeTuning, AModelThatFillsTheNodeMakesRoomForTheOscillation) {
  const imu::hal::ModelRecord t = truth(true);
  const std::vector<double> x = simulate(t, std::size_t{1} << 20U, 7303);
  imu::hal::ModelRecord r = truth(false);
  r.bi = 1e-5F;  // ADEV floor 6.6e-6, under the white noise's 3e-3 / sqrt(tau) up to 2e5 s
  r.bi_tau_lo_s = 2.56F;
  r.bi_tau_hi_s = 1000.0F;
  imu::ModelParams p{};
  ASSERT_TRUE(imu::node::model_record_valid(r, p));
  imu::hal::ModelRecord with_osc = r;
  with_osc.osc_sigma = 8e-3F;
  with_osc.osc_f0_hz = 8.0F;
  with_osc.osc_beta_per_s = 2.0F;
  ASSERT_FALSE(imu::node::model_record_valid(with_osc, p)) << "the test needs a full node";
  const imu::analyze::NodeTuning tn = imu::analyze::tune_node_record(x.data(), x.size(), kFsHz, r);
  std::printf("%s\n", tn.note.c_str());
  EXPECT_TRUE(tn.oscillation_added);
  EXPECT_NE(tn.note.find("in place of the bias-instability bank below"), std::string::npos);
  EXPECT_TRUE(imu::node::model_record_valid(r, p));
  EXPECT_LT(rel(r.osc_f0_hz, t.osc_f0_hz), 0.01);
  EXPECT_GT(r.bi_tau_lo_s, 2.56F);
  EXPECT_EQ(r.bi_tau_hi_s, 1000.0F);
}

// A clean record (no oscillation) on several seeds: none is added, and the given (true) model
// moves little. The oscillation's level is a Bonferroni 1 % over the bins searched.
TEST(NodeTuning, NoOscillationIsAddedToARecordWithoutOne) {
  const imu::hal::ModelRecord t = truth(false);
  int added = 0;
  for (std::uint64_t seed = 7311; seed < 7317; ++seed) {
    const std::vector<double> x = simulate(t, std::size_t{1} << 19U, seed);
    imu::hal::ModelRecord r = t;
    const imu::analyze::NodeTuning tn =
        imu::analyze::tune_node_record(x.data(), x.size(), kFsHz, r);
    std::printf("seed %llu: %s\n", static_cast<unsigned long long>(seed), tn.note.c_str());
    added += tn.oscillation_added ? 1 : 0;
    EXPECT_LT(rel(r.n, t.n), 0.05) << seed;
    EXPECT_LT(tn.oscillation_two_ln_lr, tn.oscillation_level) << seed;
  }
  EXPECT_EQ(added, 0);
}

// Fewer than 2^12 finite samples in a row, a constant record or an exact line: left as it is,
// said. A gap: the longest finite run.
TEST(NodeTuning, ShortOrGappedRecords) {
  const imu::hal::ModelRecord t = truth(true);
  std::vector<double> x = simulate(t, 20000, 7321);
  for (std::size_t i = 4000; i < x.size(); i += 4000) {
    x[i] = std::numeric_limits<double>::quiet_NaN();
  }
  imu::hal::ModelRecord r = t;
  imu::analyze::NodeTuning tn = imu::analyze::tune_node_record(x.data(), x.size(), kFsHz, r);
  EXPECT_FALSE(tn.tuned);
  EXPECT_EQ(tn.samples, 0U);
  EXPECT_NE(tn.note.find("not tuned"), std::string::npos) << tn.note;
  EXPECT_EQ(r.n, t.n);
  x[8000] = 0.0;  // two runs joined: 7999 finite samples in a row
  tn = imu::analyze::tune_node_record(x.data(), x.size(), kFsHz, r);
  EXPECT_EQ(tn.samples, 4096U) << tn.note;
  // A constant channel (a sensor axis that reads one value): nothing to tune on.
  const std::vector<double> flat(8192, 9.81);
  imu::hal::ModelRecord flat_r = t;
  tn = imu::analyze::tune_node_record(flat.data(), flat.size(), kFsHz, flat_r);
  EXPECT_FALSE(tn.tuned);
  EXPECT_NE(tn.note.find("does not vary"), std::string::npos) << tn.note;
  EXPECT_EQ(flat_r.n, t.n);
  // An exact line: nothing but rounding once the line is removed.
  std::vector<double> line(8192);
  for (std::size_t i = 0; i < line.size(); ++i) {
    line[i] = 9.81 + 1e-3 * static_cast<double>(i);
  }
  imu::hal::ModelRecord line_r = t;
  tn = imu::analyze::tune_node_record(line.data(), line.size(), kFsHz, line_r);
  EXPECT_FALSE(tn.tuned);
  EXPECT_NE(tn.note.find("rounding"), std::string::npos) << tn.note;
  EXPECT_EQ(line_r.n, t.n);
  // A model the node would not run is not tuned.
  imu::hal::ModelRecord bad = t;
  bad.n = -1e-3F;
  tn = imu::analyze::tune_node_record(x.data(), x.size(), kFsHz, bad);
  EXPECT_FALSE(tn.tuned);
  EXPECT_EQ(bad.n, -1e-3F);
}

}  // namespace

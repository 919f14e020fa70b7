// The model reader of `imu-sim run --model` and `synth --model` (host_sim/app/src/model_json.hpp)
// on analysis JSON written out here: what goes into the version 2 ModelRecord, what is left out
// and said, and what is refused with a message.
#include "model_json.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "imu/error_model.hpp"
#include "imu/node/node.hpp"

namespace {

std::uint32_t bits(float v) {
  std::uint32_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// A one-channel analysis JSON of acc_z at 100 Hz whose model_after has the given members after
// N (`extra`, with a leading comma) and the given GMs, RRW and bias instability.
std::string analysis(const std::string& extra, const std::string& gm = "[{\"sb\": 2.68e-8, \"tb_s\": 158.7}]",
                     const std::string& k = "0",
                     const std::string& bi = "{\"b\": 0, \"tau_lo_s\": 0, \"tau_hi_s\": 0}") {
  return "{\"channel\": \"acc_z\", \"fs_hz\": 100, \"model_after\": {\"n\": 3.3e-3" + extra +
         ", \"q\": 0, \"gm\": " + gm + ", \"k\": " + k +
         ", \"r\": 0, \"sin_a\": 0, \"sin_f0_hz\": 0, \"sin2_a\": 0, \"sin2_f0_hz\": 0, "
         "\"bias_instability\": " + bi + "}}";
}

const std::string kOsc = ", \"oscillation\": {\"sigma\": 0.02, \"f0_hz\": 6, \"beta_per_s\": 1.57}";

struct Read {
  bool ok = false;
  imu::hal::ModelRecord rec{};
  std::string dropped;
  std::string err;
};

Read read(const std::string& json) {
  Read r;
  r.ok = imu::sim::model_from_analysis_json(json, "acc_z", 2, r.rec, r.dropped, r.err);
  return r;
}

bool node_runs(const imu::hal::ModelRecord& m) {
  imu::ModelParams p{};
  return imu::node::model_record_valid(m, p);
}

}  // namespace

// n_filter_s and the oscillation go into a version 2 record as they are (float of the JSON's
// number), nothing is said about them, and the node's own check accepts the record.
TEST(ModelJson, ReadsTheOutputFilterAndTheOscillation) {
  const Read r = read(analysis(", \"n_filter_s\": 2e-3" + kOsc));
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_EQ(r.rec.version, imu::hal::kModelVersion2);
  EXPECT_EQ(r.rec.channel, 2U);
  EXPECT_EQ(bits(r.rec.n), bits(3.3e-3F)) << "N is the white noise's density, filter or not";
  EXPECT_EQ(bits(r.rec.n_filter_s), bits(2e-3F));
  EXPECT_EQ(bits(r.rec.osc_sigma), bits(0.02F));
  EXPECT_EQ(bits(r.rec.osc_f0_hz), bits(6.0F));
  EXPECT_EQ(bits(r.rec.osc_beta_per_s), bits(1.57F));
  EXPECT_EQ(r.dropped, "");
  EXPECT_TRUE(node_runs(r.rec));
}

// An analysis without n_filter_s (written before it existed) or without an oscillation (or
// with sigma 0): those fields are 0.
TEST(ModelJson, AbsentFilterAndOscillationAreZero) {
  for (const std::string& extra :
       {std::string(), std::string(", \"oscillation\": {\"sigma\": 0, \"f0_hz\": 0, \"beta_per_s\": 0}"),
        std::string(", \"n_filter_s\": 0")}) {
    const Read r = read(analysis(extra));
    ASSERT_TRUE(r.ok) << r.err;
    EXPECT_EQ(r.rec.version, imu::hal::kModelVersion2);
    EXPECT_EQ(bits(r.rec.n_filter_s) | bits(r.rec.osc_sigma) | bits(r.rec.osc_f0_hz) |
                  bits(r.rec.osc_beta_per_s),
              0U)
        << extra;
    EXPECT_EQ(r.dropped, "");
  }
}

// A malformed filter or oscillation is a one-line error.
TEST(ModelJson, MalformedFilterOrOscillationIsRefused) {
  for (const std::string& extra :
       {std::string(", \"n_filter_s\": \"fast\""), std::string(", \"n_filter_s\": 1e300"),
        std::string(", \"oscillation\": {\"sigma\": 0.02, \"beta_per_s\": 1.57}"),
        std::string(", \"oscillation\": {\"sigma\": 0.02, \"f0_hz\": 6, \"beta_per_s\": null}")}) {
    const Read r = read(analysis(extra));
    EXPECT_FALSE(r.ok) << extra;
    EXPECT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.find('\n'), std::string::npos);
  }
}

// An oscillation fitted as point samples (the ADEV of m-sample means) is sent with the sigma
// the node's averaging sampler needs for the same ADEV: sigma x / sin(x), x = pi f0 Ts (said).
// Checked against the AVAR formulas themselves: the node's continuous-average AVAR with the sent
// sigma against the analysis's sample-mean AVAR, a narrow band at fs / 5.
TEST(ModelJson, APointSampledOscillationIsSentAsTheAveragingSamplerSeesIt) {
  const Read r = read(analysis(", \"oscillation\": {\"sigma\": 0.005, \"f0_hz\": 20, "
                               "\"beta_per_s\": 0.5, \"point_sampled_ts_s\": 0.01}"));
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_TRUE(node_runs(r.rec));
  const auto sent = static_cast<double>(r.rec.osc_sigma);
  for (const int m : {1, 2, 3, 7, 12}) {
    const double node = imu::avar_oscillation(sent, 20.0, 0.5, m * 0.01);
    const double data = imu::avar_oscillation_sampled(0.005, 20.0, 0.5, 0.01, m * 0.01);
    EXPECT_NEAR(node, data, 0.02 * data) << "m " << m;
  }
  EXPECT_NE(r.dropped.find("in point samples) sent as"), std::string::npos) << r.dropped;
  // Averages over each sample period (0) or no key: sent as it is.
  const Read a = read(analysis(", \"oscillation\": {\"sigma\": 0.005, \"f0_hz\": 20, "
                               "\"beta_per_s\": 0.5, \"point_sampled_ts_s\": 0}"));
  ASSERT_TRUE(a.ok) << a.err;
  EXPECT_EQ(bits(a.rec.osc_sigma), bits(0.005F));
  EXPECT_EQ(a.dropped, "");
  const Read bad = read(analysis(", \"oscillation\": {\"sigma\": 0.005, \"f0_hz\": 20, "
                                 "\"beta_per_s\": 0.5, \"point_sampled_ts_s\": \"x\"}"));
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.err.find("point_sampled_ts_s"), std::string::npos) << bad.err;
}

// A model the node would refuse only for its version 2 terms: 2 GM + RRW + a flicker bank
// over 1..1e3 s (5 members) + the oscillation (2) + the output filter (1) = 11 states against
// 8. First the bank's short end moves up (10..1e3 s, 4 members: 10), then the filter would go
// (9), so it stays and the oscillation's variance goes to the white noise (N'^2 = N^2 +
// sigma^2 / fs at the recording's rate): 8, with the filter and the narrowed bank; each said.
TEST(ModelJson, TermsTheNodeCannotHoldAreLeftOutAndSaid) {
  const std::string gm2 = "[{\"sb\": 2.68e-8, \"tb_s\": 158.7}, {\"sb\": 1e-6, \"tb_s\": 0.2}]";
  const std::string bank = "{\"b\": 1e-3, \"tau_lo_s\": 1, \"tau_hi_s\": 1000}";
  Read r = read(analysis(", \"n_filter_s\": 2e-3" + kOsc, gm2, "1.4e-4", bank));
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_TRUE(node_runs(r.rec));
  EXPECT_EQ(bits(r.rec.n_filter_s), bits(2e-3F));
  EXPECT_EQ(bits(r.rec.osc_sigma), 0U);
  EXPECT_EQ(bits(r.rec.bi_tau_lo_s), bits(10.0F));
  EXPECT_NEAR(static_cast<double>(r.rec.n), std::sqrt(3.3e-3 * 3.3e-3 + 0.02 * 0.02 / 100.0),
              1e-9);  // float rounding of 7e-3: 4e-10
  EXPECT_NE(r.dropped.find("realised by the node from 10 s, not 1 s"), std::string::npos)
      << r.dropped;
  EXPECT_NE(r.dropped.find("its variance is added to the white noise"), std::string::npos);
  EXPECT_EQ(r.dropped.find("output filter"), std::string::npos) << r.dropped;
  // The same in a long record's report (its fs_hz is the block means'; the node samples at the
  // full-rate head's 100 Hz).
  std::string long_json = analysis(kOsc, gm2, "1.4e-4", bank);
  long_json.replace(long_json.find("\"fs_hz\": 100"), 12, "\"fs_hz\": 25");
  long_json.insert(long_json.size() - 1,
                   ", \"full_rate_head\": {\"n_samples\": 4194304, \"fs_hz\": 100, \"block\": 4}");
  r = read(long_json);
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_NEAR(static_cast<double>(r.rec.n), std::sqrt(3.3e-3 * 3.3e-3 + 0.02 * 0.02 / 100.0),
              1e-9);
  EXPECT_EQ(r.dropped.find("output filter"), std::string::npos) << r.dropped;
  // 1 GM + RRW + bank (5) + oscillation + filter = 10: with the bank narrowed (9) the filter
  // goes (8): the oscillation stays as states.
  r = read(analysis(", \"n_filter_s\": 2e-3" + kOsc, "[{\"sb\": 2.68e-8, \"tb_s\": 158.7}]",
                    "1.4e-4", bank));
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_TRUE(node_runs(r.rec));
  EXPECT_EQ(bits(r.rec.n_filter_s), 0U);
  EXPECT_EQ(bits(r.rec.osc_sigma), bits(0.02F));
  EXPECT_EQ(bits(r.rec.bi_tau_lo_s), bits(10.0F));
  EXPECT_NE(r.dropped.find("output filter of model_after (0.002 s) not sent"), std::string::npos)
      << r.dropped;
  // 1 GM + RRW + a bank over 1..30 s (4 members) + oscillation = 8, + filter = 9: only the
  // filter goes.
  const std::string small_bank = "{\"b\": 1e-3, \"tau_lo_s\": 1, \"tau_hi_s\": 30}";
  imu::GmParam members[imu::kMaxFlickerGm] = {};
  const std::size_t nb = imu::flicker_bank(1e-3, 1.0, 30.0, members);
  ASSERT_EQ(nb + 2 + 2, imu::node::kNodeProcessStates) << "the bank's size this case assumes";
  r = read(analysis(", \"n_filter_s\": 2e-3" + kOsc, "[{\"sb\": 2.68e-8, \"tb_s\": 158.7}]",
                    "1.4e-4", small_bank));
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_TRUE(node_runs(r.rec));
  EXPECT_EQ(bits(r.rec.n_filter_s), 0U);
  EXPECT_EQ(bits(r.rec.osc_sigma), bits(0.02F));
  EXPECT_EQ(bits(r.rec.n), bits(3.3e-3F));
  EXPECT_EQ(r.dropped.find("oscillation"), std::string::npos) << r.dropped;
}

// A model the node refuses for another reason (here a negative N) is sent as it is, filter and
// oscillation included: the node refuses and counts it, and nothing is said about them.
TEST(ModelJson, AModelRefusedForAnotherReasonIsSentAsItIs) {
  std::string json = analysis(", \"n_filter_s\": 2e-3" + kOsc);
  json.replace(json.find("\"n\": 3.3e-3"), 11, "\"n\": -1");
  const Read r = read(json);
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_FALSE(node_runs(r.rec));
  EXPECT_EQ(bits(r.rec.n_filter_s), bits(2e-3F));
  EXPECT_EQ(bits(r.rec.osc_sigma), bits(0.02F));
  EXPECT_EQ(r.dropped, "");
}

// A bank the node refuses at every width (its short end 0, or its long end out of float range)
// is sent as it is after a bounded search for a width it runs: the node refuses and counts it.
TEST(ModelJson, ABankTheNodeRefusesAtEveryWidthIsSentAsItIs) {
  for (const char* bi : {"{\"b\": 9e-4, \"tau_lo_s\": 0, \"tau_hi_s\": 1000}",
                         "{\"b\": 9e-4, \"tau_lo_s\": 1e-30, \"tau_hi_s\": 3e38}"}) {
    const Read r = read(analysis(", \"n_filter_s\": 2e-3" + kOsc, "[{\"sb\": 2e-6, \"tb_s\": 300}]",
                                 "1.4e-4", bi));
    ASSERT_TRUE(r.ok) << r.err;
    EXPECT_FALSE(node_runs(r.rec)) << bi;
    EXPECT_EQ(r.dropped, "") << bi;
  }
}

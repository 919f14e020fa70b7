// Long test (label long): the 1,000,000-sample ADIS16405 acc_z channel through imu-sim run at
// --rate max over the loopback bus (in-process node): no frame lost, under 30 s, and the same
// ADEV as imu-sim adev. And both units, all six channels, with the node's default models and
// with the models of a whole-IMU analysis pushed. Skipped when the shared data is absent.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sim_test_util.hpp"

namespace {

double now_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

TEST(SimAdis, RunAtMaxRateOverLoopback) {
  const std::string mat = std::string(IMU_SHARED_DIR) + "/data/adis16405_imu1.mat";
  struct stat st {};
  if (stat(mat.c_str(), &st) != 0) {
    GTEST_SKIP() << "shared data absent: " << mat;
  }
  simtest::TempDir dir;
  const double t0 = now_s();
  auto r = simtest::run({"run", mat, "--channel", "acc_z", "--bus", "loopback",
                         "--rate", "max", "--out", dir.file("run"), "--no-plots", "--quiet"});
  const double t_run = now_s() - t0;
  ASSERT_EQ(r.status, 0) << r.err;
  std::printf("imu-sim run on adis16405_imu1 acc_z (1e6 samples): %.2f s\n", t_run);
  EXPECT_LT(t_run, 30.0) << "the 1,000,000-sample channel in under 30 s";
  const std::string json = simtest::read_text(dir.file("run") + "/report.json");
  const char* node = "node_stats";
  EXPECT_EQ(simtest::json_number_in(json, node, "samples"), 1e6);
  EXPECT_EQ(simtest::json_number_in(json, node, "missing"), 0.0);
  EXPECT_EQ(simtest::json_number_in(json, node, "lost"), 0.0);
  // The recorded acc_z holds steps and a drift the node's first-order filter lacks: its CUSUM
  // fires (the other channels' too, on the node's default models), and the report says so in
  // words next to the raw flags.
  const double flags = simtest::json_number_in(json, "residual_monitors",
                                               "flags");
  const std::string report = simtest::read_text(dir.file("run") + "/report.txt");
  EXPECT_GT(flags, 0.5);
  const std::size_t note = report.find("note: residual monitors: the innovation CUSUM detected level shifts on ");
  ASSERT_NE(note, std::string::npos)
      << report.substr(report.size() > 2000 ? report.size() - 2000 : 0);
  const std::string line = report.substr(note, report.find('\n', note) - note);
  EXPECT_NE(line.find("acc_z"), std::string::npos) << line;

  const double t1 = now_s();
  r = simtest::run({"adev", mat, "--channel", "acc_z", "--estimator", "online", "--json",
                    dir.file("adev.json")});
  std::printf("imu-sim adev on adis16405_imu1 acc_z: %.2f s\n", now_s() - t1);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto a = simtest::json_adev(simtest::read_text(dir.file("adev.json")));
  const auto b = simtest::json_adev(json);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 60U);
  for (std::size_t i = 0; i < a.size(); ++i) {
    // float32 telemetry (6e-8) and a different summation order (~1e-13): see test_cli.cpp.
    EXPECT_NEAR(b[i].tau_s, a[i].tau_s, 1e-12 * a[i].tau_s);
    EXPECT_NEAR(b[i].adev, a[i].adev, 3e-7 * a[i].adev) << "tau " << a[i].tau_s;
  }
}

// One row of the run JSON's node.channels.
struct NodeRow {
  std::string channel;
  std::string origin;
  double n_states = 0.0;
  double nis_mean = 0.0;
  bool whiteness_passed = false;
  bool cusum_alarm = false;
  double detections = 0.0;  // level shifts the node's CUSUM detected
  std::string steps_t_s;    // their times, as the JSON lists them
};

// The end of the JSON value (object or list) opening at `open`: the index after its closing
// bracket (strings in this JSON hold no brackets that matter: names and notes are skipped).
std::size_t value_end(const std::string& j, std::size_t open) {
  int depth = 0;
  bool in_str = false;
  for (std::size_t i = open; i < j.size(); ++i) {
    const char ch = j[i];
    if (in_str) {
      in_str = !(ch == '"' && j[i - 1] != '\\');
    } else if (ch == '"') {
      in_str = true;
    } else if (ch == '{' || ch == '[') {
      ++depth;
    } else if ((ch == '}' || ch == ']') && --depth == 0) {
      return i + 1;
    }
  }
  return std::string::npos;
}

// The times of the bias steps `analyze --channel all` named for one channel.
std::vector<double> named_steps(const std::string& analysis, const std::string& channel) {
  std::vector<double> t;
  const std::size_t chans = analysis.find("\"channels\": {");
  const std::size_t obj = analysis.find("\"" + channel + "\": {", chans);
  const std::size_t eff = analysis.find("\"effects\": [", obj);
  if (chans == std::string::npos || obj == std::string::npos || eff == std::string::npos) {
    return t;
  }
  const std::size_t end = value_end(analysis, analysis.find('[', eff));
  for (std::size_t i = analysis.find("\"bias_step\"", eff); i < end;
       i = analysis.find("\"bias_step\"", i + 1)) {
    const std::size_t k = analysis.find("\"time_s\": ", i);
    if (k < end) {
      t.push_back(std::strtod(analysis.c_str() + k + 10, nullptr));
    }
  }
  return t;
}

// How many of the node's detected shifts (a JSON list's text) lie within tol_s of a named step.
int shifts_near(const std::string& list, const std::vector<double>& steps, double tol_s) {
  int n = 0;
  const char* p = list.c_str();
  char* end = nullptr;
  for (double v = std::strtod(p, &end); end != p; v = std::strtod(p, &end)) {
    for (const double s : steps) {
      if (std::fabs(v - s) <= tol_s) {
        ++n;
        break;
      }
    }
    p = end;
    while (*p == ',' || *p == ' ') {
      ++p;
    }
  }
  return n;
}

std::vector<NodeRow> node_rows(const std::string& json) {
  std::vector<NodeRow> rows;
  const std::size_t at = json.find("\"channels\": [", json.find("\"node\": {"));
  if (at == std::string::npos) {
    return rows;
  }
  const std::size_t end = json.find("], \"faults\"", at);  // each object holds a list too
  for (std::size_t i = json.find('{', at); i < end; i = json.find('{', i + 1)) {
    const std::string obj = json.substr(i, json.find('}', i) - i + 1);
    auto str = [&obj](const char* key) {
      const std::size_t k = obj.find(std::string("\"") + key + "\": \"");
      if (k == std::string::npos) {
        return std::string();
      }
      const std::size_t b = obj.find(": \"", k) + 3;
      return obj.substr(b, obj.find('"', b) - b);
    };
    auto num = [&obj](const char* key) {
      const std::size_t k = obj.find(std::string("\"") + key + "\": ");
      return k == std::string::npos ? -1.0 : std::strtod(obj.c_str() + obj.find(": ", k) + 2, nullptr);
    };
    auto flag = [&obj](const char* key) {
      return obj.find(std::string("\"") + key + "\": true") != std::string::npos;
    };
    NodeRow r;
    r.channel = str("channel");
    r.origin = str("origin");
    r.n_states = num("n_states");
    r.nis_mean = num("nis_mean");
    r.whiteness_passed = flag("whiteness_passed");
    r.cusum_alarm = flag("cusum_alarm");
    r.detections = num("cusum_detections");
    const std::size_t st = obj.find("\"cusum_steps_t_s\": [");
    if (st != std::string::npos) {
      const std::size_t b = obj.find('[', st) + 1;
      r.steps_t_s = obj.substr(b, obj.find(']', b) - b);
    }
    rows.push_back(r);
  }
  return rows;
}

// Both shared units, all six channels: the node's default (first-order) models, then the
// models of `analyze --channel all` pushed (tuned to the node's filter on the record). Every
// channel must run what was pushed, its NIS mean must come near 1, its innovations must pass
// the whiteness test on at least 5 of 6 channels per unit, and the CUSUM must detect fewer
// level shifts than with the defaults. The table is the README's.
TEST(SimAdis, PushedWholeImuModelsRunOnEveryChannelOfBothUnits) {
  for (const char* unit : {"adis16405_imu1", "adis16405_imu2"}) {
    const std::string mat = std::string(IMU_SHARED_DIR) + "/data/" + unit + ".mat";
    struct stat st {};
    if (stat(mat.c_str(), &st) != 0) {
      GTEST_SKIP() << "shared data absent: " << mat;
    }
    simtest::TempDir dir;
    auto r = simtest::run({"analyze", mat, "--channel", "all", "--json", dir.file("all.json")});
    ASSERT_EQ(r.status, 0) << r.err;
    std::vector<NodeRow> rows[2];
    for (int pushed = 0; pushed < 2; ++pushed) {
      std::vector<std::string> args = {"run", mat, "--channel", "acc_x", "--no-plots", "--quiet",
                                       "--sim-windows", "10", "--out", dir.file("run")};
      if (pushed == 1) {
        args.insert(args.end(), {"--model", dir.file("all.json")});
      }
      r = simtest::run(args);
      ASSERT_EQ(r.status, 0) << r.err;
      const std::string json = simtest::read_text(dir.file("run") + "/report.json");
      rows[pushed] = node_rows(json);
      ASSERT_EQ(rows[pushed].size(), 6U) << json.substr(json.find("\"node\": {"));
      // The selected channel's own figures, not the worst channel's.
      EXPECT_NEAR(simtest::json_number_in(json, "node", "nis_mean"), rows[pushed][0].nis_mean,
                  1e-6 * rows[pushed][0].nis_mean);
    }
    int alarms[2] = {0, 0};
    int white = 0;
    double shifts[2] = {0.0, 0.0};
    int near_named = 0;
    constexpr double kNearStepS = 20.0;
    const std::string analysis = simtest::read_text(dir.file("all.json"));
    std::printf("%s  %-7s | default: states NIS    white shifts | pushed: states NIS    white "
                "shifts (at t s)\n", unit, "channel");
    for (std::size_t c = 0; c < 6; ++c) {
      const NodeRow& d = rows[0][c];
      const NodeRow& p = rows[1][c];
      const std::vector<double> steps = named_steps(analysis, p.channel);
      std::string named;
      for (const double t : steps) {
        named += (named.empty() ? "" : " ") + std::to_string(static_cast<int>(std::lround(t)));
      }
      const int near = shifts_near(p.steps_t_s, steps, kNearStepS);
      near_named += near;
      std::printf("%s  %-7s |          %6.0f %6.3f %-5s %6.0f |         %6.0f %6.3f %-5s %6.0f (%s)"
                  " | named steps: %s; %d shifts within %.0f s of one\n",
                  unit, d.channel.c_str(), d.n_states, d.nis_mean, d.whiteness_passed ? "ok" : "FAIL",
                  d.detections, p.n_states, p.nis_mean, p.whiteness_passed ? "ok" : "FAIL",
                  p.detections, p.steps_t_s.c_str(), named.c_str(), near, kNearStepS);
      EXPECT_EQ(d.origin, "default") << d.channel;
      EXPECT_EQ(d.n_states, 1.0) << d.channel;
      EXPECT_EQ(p.origin, "pushed") << p.channel;
      EXPECT_GE(p.n_states, 1.0) << p.channel;
      EXPECT_GE(p.nis_mean, 0.8) << unit << " " << p.channel;
      EXPECT_LE(p.nis_mean, 1.25) << unit << " " << p.channel;
      EXPECT_EQ(d.cusum_alarm, d.detections > 0.0) << d.channel;
      EXPECT_EQ(p.cusum_alarm, p.detections > 0.0) << p.channel;
      EXPECT_LE(p.detections, d.detections) << unit << " " << p.channel;
      white += p.whiteness_passed ? 1 : 0;
      alarms[0] += d.cusum_alarm ? 1 : 0;
      alarms[1] += p.cusum_alarm ? 1 : 0;
      shifts[0] += d.detections;
      shifts[1] += p.detections;
    }
    std::printf("%s: CUSUM level shifts on %d of 6 channels with the default models (%.0f in all), "
                "%d with the pushed ones (%.0f, %d within %.0f s of a step the analysis named); "
                "whiteness passed on %d of 6 with the pushed ones\n",
                unit, alarms[0], shifts[0], alarms[1], shifts[1], near_named, kNearStepS, white);
    EXPECT_LT(alarms[1], alarms[0]) << unit;
    EXPECT_GE(white, 5) << unit << ": whiteness passed on " << white << " of 6 channels";
    // The pushed models explain the drift the first-order one reads as a train of shifts: what
    // is left is a few steps per channel.
    EXPECT_LT(shifts[1], 0.2 * shifts[0]) << unit;
  }
}

}  // namespace

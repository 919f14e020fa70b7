// Tests of the imu-sim / imu-fw command lines (host_sim/app), run in-process: parse errors,
// bad files, the model subcommand against the example's printed numbers, and synth -> run over
// the loopback bus through the firmware node, compared with imu-sim adev on the same file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "imu/mat/mat_writer.hpp"
#include "imu/noise_sim.hpp"
#include "sim_test_util.hpp"

// Under qemu-aarch64 user mode (cross build) on the build machines a process cannot start a
// thread (a two-line std::thread program hangs in pthread_create: qemu 7.2, measured) nor exec
// another aarch64 binary (no binfmt_misc): the end-to-end runs, which need the in-process node
// thread or a spawned imu-fw, are skipped there; they run natively and in the VM test.
namespace {

using simtest::count_lines;
using simtest::run;

TEST(SimCli, NoArgumentsPrintsUsageAndExits2) {
  const auto r = run({});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("usage: imu-sim"), std::string::npos);
}

TEST(SimCli, HelpExits0) {
  const auto r = run({"--help"});
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("run FILE"), std::string::npos);
}

TEST(SimCli, UnknownCommand) {
  const auto r = run({"frobnicate"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.rfind("imu-sim: unknown command 'frobnicate'", 0), 0U) << r.err;
}

TEST(SimCli, ParseErrorsAreOneLineAndExit2) {
  const std::vector<std::vector<std::string>> cases = {
      {"run", "x.mat", "--bogus"},        // unknown option
      {"run", "--mat"},                             // missing value
      {"run"},                                      // FILE required
      {"run", "x.mat", "--rate", "fast"},  // bad enum
      {"run", "x.mat", "--node", "x"},
      {"run", "x.mat", "--N", "1e-3"},     // model needs N, B and Tp together
      {"run", "x.mat", "--channel", "data:x"},  // any variable, but NAME:K needs a number
      {"run", "x.mat", "--timeout", "abc"},
      {"run", "x.mat", "--no-plots=1"},    // flag with a value
      {"adev"},                                     // FILE required
      {"adev", "a.mat", "b.mat"},                   // one FILE only
      {"model", "--N", "abc"},
      {"model", "--N", "-1"},
      {"synth", "--duration", "0"},
      {"synth", "--channel", "mag_x"},
  };
  for (const auto& c : cases) {
    const auto r = run(c);
    std::string joined;
    for (const auto& s : c) {
      joined += s + " ";
    }
    EXPECT_EQ(r.status, 2) << joined << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1U) << joined << ": " << r.err;
    EXPECT_EQ(r.err.rfind("imu-sim ", 0), 0U) << joined << ": " << r.err;
  }
}

TEST(SimCli, FwParseErrors) {
  const std::vector<std::vector<std::string>> cases = {
      {},                                          // --bus required
      {"--bus", "loopback", "--bogus"},
      {"--bus", "loopback", "--layout", "x"},
      {"--bus", "loopback", "--static-line", "s"},  // needs --gpio-chip
      {"--bus", "loopback", "--N", "0"},            // model rejected
  };
  for (const auto& c : cases) {
    const auto r = run(c, true);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("imu-fw: "), std::string::npos) << r.err;
  }
}

TEST(SimCli, ModelPrintsTheExamplesNumbers) {
  const auto r = run({"model", "--N", "3.3e-3", "--B", "9e-4", "--Tp", "300", "--fs", "100"});
  ASSERT_EQ(r.status, 0) << r.err;
  // Typed from Farrell's ASD-to-state-space example (its printed output), not produced by the
  // code.
  const char* expected[] = {
      "db(t)/dt = -6.3000e-03 * b(t) + w(t)",
      "PSD S_n = 1.0890e-05",
      "PSD S_w = 2.6783e-08",
      "P_b_ss_c = 2.1256e-06",
      "b[k+1] = 0.9999 * b[k] + w[k]",
      "Q_n = 1.0890e-03 (std 3.3000e-02)",
      "Q_w = 2.6781e-10 (std 1.6365e-05)",
      "P_b_ss_d = 2.1256e-06",
  };
  for (const char* e : expected) {
    EXPECT_NE(r.out.find(e), std::string::npos) << "missing '" << e << "' in\n" << r.out;
  }
}

TEST(SimCli, BadFilesExit1WithOneLine) {
  simtest::TempDir dir;
  const std::string junk = dir.file("junk.mat");
  {
    std::FILE* f = std::fopen(junk.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("this is not a MAT-file, just text long enough to be read as a header......", f);
    std::fclose(f);
  }
  const std::string synth = dir.file("s.mat");
  ASSERT_EQ(run({"synth", "--out", synth, "--duration", "10"}).status, 0);
  const std::string missing = dir.file("does-not-exist.mat");
  const std::vector<std::vector<std::string>> cases = {
      {"adev", missing},
      {"adev", junk},
      {"adev", synth, "--channel", "gyro_x"},  // variable absent
      {"run", missing, "--out", dir.file("o1")},
      {"run", junk, "--out", dir.file("o2")},
      {"run", synth, "--channel", "gyro_y", "--out", dir.file("o3")},
  };
  for (const auto& c : cases) {
    const auto r = run(c);
    EXPECT_EQ(r.status, 1) << c[1] << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1U) << r.err;
  }
  EXPECT_NE(run({"adev", missing}).err.find("does-not-exist.mat"), std::string::npos);
  EXPECT_NE(run({"adev", synth, "--channel", "gyro_x"}).err.find("gyro_x"), std::string::npos);
}

TEST(SimCli, MissingBusExit1WithOneLine) {
  simtest::TempDir dir;
  const std::string mat = dir.file("s.mat");
  ASSERT_EQ(run({"synth", "--out", mat, "--duration", "10"}).status, 0);
  auto r = run({"run", mat, "--bus", "nosuchcan9", "--out", dir.file("o")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(count_lines(r.err), 1U) << r.err;
  EXPECT_NE(r.err.find("nosuchcan9"), std::string::npos) << r.err;
  r = run({"--bus", "nosuchcan9"}, true);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("imu-fw: cannot open bus: bus 'nosuchcan9'"), std::string::npos) << r.err;
}

/// synth (30,000 samples) -> run in-process over the loopback bus -> compare with adev.
TEST(SimCli, RunOverLoopbackLosesNothingAndMatchesAdev) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  const std::string mat = dir.file("synth.mat");
  auto r = run({"synth", "--out", mat, "--duration", "300", "--seed", "5"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("SYNTHETIC"), std::string::npos);
  const std::string out = dir.file("run");
  r = run({"run", mat, "--bus", "loopback", "--rate", "max", "--out", out, "--no-plots",
           "--quiet", "--sim-windows", "50", "--T-avg", "1", "--T-int", "2", "--N", "3.3e-3",
           "--B", "9e-4", "--Tp", "300", "--K", "1.4e-4"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("Continuous-time model is"), std::string::npos);
  EXPECT_NE(r.out.find("== Covariance check"), std::string::npos);
  EXPECT_NE(r.out.find("== Frame statistics"), std::string::npos);
  const std::string json = simtest::read_text(out + "/report.json");
  ASSERT_FALSE(json.empty());
  const char* node = "node_stats";
  EXPECT_EQ(simtest::json_number_in(json, node, "samples"), 30000.0);
  EXPECT_EQ(simtest::json_number_in(json, node, "missing"), 0.0);
  EXPECT_EQ(simtest::json_number_in(json, node, "lost"), 0.0);
  EXPECT_EQ(simtest::json_number_in(json, node, "crc_errors"), 0.0);
  // A channel whose monitors found something (a CUSUM alarm, whiteness failing beyond its own
  // false-alarm rate) comes with a note saying what it means, and only then.
  const std::size_t chans = json.find("\"channels\": [", json.find("\"node\": {"));
  ASSERT_NE(chans, std::string::npos);
  const std::string rows = json.substr(chans, json.find(']', chans) - chans);
  const bool found = rows.find("\"cusum_alarm\": true") != std::string::npos ||
                     rows.find("\"whiteness_passed\": false") != std::string::npos;
  const std::string report = simtest::read_text(out + "/report.txt");
  EXPECT_EQ(report.find("note: residual monitors: ") != std::string::npos, found) << rows;
  for (const char* f : {"report.txt", "fig1_adev_data.csv", "fig1_adev_model.csv",
                        "fig1_adev_sim.csv", "fig2_std.csv", "fig2_traj_sim.csv",
                        "fig2_traj_data.csv", "fig1_adev.gp", "fig2_covariance.gp"}) {
    EXPECT_FALSE(simtest::read_text(out + "/" + f).empty()) << f;
  }

  const std::string adev_json = dir.file("adev.json");
  r = run({"adev", mat, "--channel", "acc_z", "--estimator", "online", "--json", adev_json});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("online ADEV"), std::string::npos);
  const auto a = simtest::json_adev(simtest::read_text(adev_json));
  const auto b = simtest::json_adev(json);
  ASSERT_GT(a.size(), 40U);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    // tau is rebuilt exactly from the averaging factor; ADEV and its interval travel as float32
    // (relative rounding 6e-8) and the node adds one sample at a time where adev uses blocks
    // (sums in another order, ~1e-13): 3e-7 relative covers both with margin. EDF is
    // recomputed by imu-sim from n_terms with the same formula: 1e-12.
    EXPECT_NEAR(b[i].tau_s, a[i].tau_s, 1e-12 * a[i].tau_s) << i;
    EXPECT_NEAR(b[i].adev, a[i].adev, 3e-7 * a[i].adev) << "tau " << a[i].tau_s;
    EXPECT_NEAR(b[i].ci_lo, a[i].ci_lo, 3e-7 * a[i].ci_lo) << "tau " << a[i].tau_s;
    EXPECT_NEAR(b[i].ci_hi, a[i].ci_hi, 3e-7 * a[i].ci_hi) << "tau " << a[i].tau_s;
    EXPECT_NEAR(b[i].edf, a[i].edf, 1e-9 * a[i].edf) << "tau " << a[i].tau_s;
  }
}

/// imu-fw as its own process (spawned by imu-sim) over a named loopback bus.
TEST(SimCli, RunWithSpawnedFirmwareProcess) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  const std::string mat = dir.file("synth.mat");
  ASSERT_EQ(run({"synth", "--out", mat, "--duration", "100"}).status, 0);
  const std::string out = dir.file("run");
  const auto r = run({"run", mat, "--node", "spawn", "--fw", IMU_FW_PATH, "--out", out,
                      "--no-plots", "--quiet", "--sim-windows", "20", "--T-avg", "1", "--T-int",
                      "2"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string log = simtest::read_text(out + "/imu-fw.log");
  EXPECT_NE(log.find("stream ended (link-down): 10000 samples, 0 missing"), std::string::npos)
      << log;
  EXPECT_NE(log.find("final ADEV of acc_z"), std::string::npos) << log;
  const std::string json = simtest::read_text(out + "/report.json");
  EXPECT_EQ(simtest::json_number_in(json, "node_stats", "missing"), 0.0);
}

/// The plots: gnuplot renders SVG (and PNG) from the CSV files, or the report says it is missing.
TEST(SimCli, PlotsAreRenderedOrReportedMissing) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  const std::string mat = dir.file("synth.mat");
  ASSERT_EQ(run({"synth", "--out", mat, "--duration", "100"}).status, 0);
  const std::string out = dir.file("run");
  const auto r = run({"run", mat, "--out", out, "--quiet", "--sim-windows", "20",
                      "--T-avg", "1", "--T-int", "2"});
  ASSERT_EQ(r.status, 0) << r.err;
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_NE(simtest::read_text(out + "/fig1_adev.svg").find("<svg"), std::string::npos);
    EXPECT_NE(simtest::read_text(out + "/fig2_covariance.svg").find("<svg"), std::string::npos);
    EXPECT_NE(r.out.find("plots: fig1_adev.svg"), std::string::npos) << r.out;
    // The scripts run from any directory: here from /, into another file.
    for (const char* gp : {"fig1_adev", "fig2_covariance"}) {
      const std::string svg = dir.file(std::string(gp) + "_elsewhere.svg");
      std::string cmd = "cd / && gnuplot -e \"set terminal svg; set output '";
      cmd += svg;
      cmd += "'\" '";
      cmd += out;
      cmd += "/";
      cmd += gp;
      cmd += ".gp' 2>/dev/null";
      EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
      EXPECT_NE(simtest::read_text(svg).find("<svg"), std::string::npos) << gp;
    }
  } else {
    EXPECT_NE(r.out.find("gnuplot NOT FOUND"), std::string::npos) << r.out;
  }
}

}  // namespace

/// the criterion on the demo's synthetic data (synth defaults: the first-order model + RRW,
/// 1e6 samples): the first-order model on the node raises the CUSUM alarm, and the model
/// `imu-sim analyze` finds, pushed with `run --model`, is the one the node reports it runs,
/// gives no CUSUM alarm and an NIS mean in [0.8, 1.25] (the target band). The CUSUM threshold
/// is sized for an in-control ARL of 1e8 updates (imu/residual_monitor.hpp), so a correct model
/// has a ~1 % chance of a false alarm over this record; the first-order model is not one.
namespace {
void run_first_order_and_pushed(simtest::TempDir& dir, std::string& first_json,
                                std::string& push_json) {
  const std::string mat = dir.file("synth.mat");
  auto r = run({"synth", "--out", mat});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string analysis = dir.file("a.json");
  r = run({"analyze", mat, "--channel", "acc_z", "--json", analysis});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> common = {"--bus", "loopback", "--rate", "max", "--no-plots",
                                           "--quiet", "--sim-windows", "10", "--N", "3.3e-3",
                                           "--B", "9e-4", "--Tp", "300"};
  std::vector<std::string> first_args = {"run", mat, "--out", dir.file("first")};
  first_args.insert(first_args.end(), common.begin(), common.end());
  r = run(first_args);
  ASSERT_EQ(r.status, 0) << r.err;
  first_json = simtest::read_text(dir.file("first") + "/report.json");
  std::vector<std::string> push_args = {"run", mat, "--out", dir.file("push"), "--model",
                                        analysis};
  push_args.insert(push_args.end(), common.begin(), common.end());
  r = run(push_args);
  ASSERT_EQ(r.status, 0) << r.err;
  push_json = simtest::read_text(dir.file("push") + "/report.json");
}
}  // namespace

TEST(SimCli, FirstOrderModelAlarmsAndPushedAnalysisModelIsQuietOnTheDemoData) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  std::string first_json;
  std::string push_json;
  run_first_order_and_pushed(dir, first_json, push_json);
  EXPECT_NE(first_json.find("\"origin\": \"default\""), std::string::npos) << first_json;
  // The selected channel's own monitors: the node object up to its per-channel rows.
  const auto selected = [](const std::string& j) {
    const std::string node = j.substr(j.find("\"node\": {"));
    return node.substr(0, node.find("\"channels\": ["));
  };
  EXPECT_NE(selected(first_json).find("\"cusum_alarm\": true"), std::string::npos)
      << "the first-order model raises the CUSUM alarm on the demo data";
  EXPECT_NE(push_json.find("\"origin\": \"pushed\""), std::string::npos) << push_json;
  EXPECT_NE(push_json.find("\"model_pushed\": true"), std::string::npos);
  EXPECT_NE(selected(push_json).find("\"cusum_alarm\": false"), std::string::npos)
      << "the pushed analysis model gives no CUSUM alarm";
  const double nis = simtest::json_number_in(push_json, "node", "nis_mean");
  std::printf("first-order: cusum_alarm %s; pushed: cusum_alarm %s, nis_mean %.4f\n",
              first_json.find("\"cusum_alarm\": true") != std::string::npos ? "true" : "false",
              push_json.find("\"cusum_alarm\": true") != std::string::npos ? "true" : "false",
              nis);
  EXPECT_GE(nis, 0.8);
  EXPECT_LE(nis, 1.25);
  EXPECT_EQ(simtest::json_number_in(push_json, "node", "model_rejected"), 0.0);
  // The demo's data hold a rate random walk beside the GM (synth's default K): the analysis keeps
  // the walk its record's likelihood requires, so the node runs GM + walk.
  const std::string node = push_json.substr(push_json.find("\"node\": {"));
  const double states = simtest::json_number_in(node, "model", "n_states");  // the node's echo
  std::printf("pushed model: %.0f states\n", states);
  EXPECT_GE(states, 2.0) << node.substr(0, 1500);
}

/// `run --model --model-as-is` sends the white noise's output filter and the narrowband
/// oscillation as filter states (a version 2 model record) and the node runs them: its echo in
/// the run JSON carries them (float of the JSON's numbers), N unchanged, GM + filter +
/// oscillation = 4 states.
TEST(SimCli, RunModelSendsTheOutputFilterAndTheOscillation) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  const std::string mat = dir.file("synth.mat");
  auto r = run({"synth", "--out", mat, "--duration", "200"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string f = dir.file("osc.json");
  std::ofstream(f) << "{\"channel\": \"acc_z\", \"fs_hz\": 100, \"model_after\": {\"n\": 3.3e-3, "
                      "\"n_filter_s\": 2e-3, \"q\": 0, \"gm\": [{\"sb\": 5.7e-9, \"tb_s\": 158.7}], "
                      "\"k\": 0, \"r\": 0, \"sin_a\": 0, \"sin_f0_hz\": 0, \"sin2_a\": 0, "
                      "\"sin2_f0_hz\": 0, \"bias_instability\": {\"b\": 0, \"tau_lo_s\": 0, "
                      "\"tau_hi_s\": 0}, \"oscillation\": {\"sigma\": 0.02, \"f0_hz\": 6, "
                      "\"beta_per_s\": 1.57}}}";
  r = run({"run", mat, "--model", f, "--model-as-is", "--no-plots", "--quiet", "--sim-windows",
           "10", "--out", dir.file("o")});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string report = simtest::read_text(dir.file("o") + "/report.txt");
  EXPECT_EQ(report.find("tuned to the node's filter"), std::string::npos) << report;
  EXPECT_EQ(report.find("oscillation of model_after"), std::string::npos) << report;
  EXPECT_EQ(report.find("output filter of model_after"), std::string::npos) << report;
  const std::string json = simtest::read_text(dir.file("o") + "/report.json");
  const std::string node = json.substr(json.find("\"node\": {"));
  // The echo's floats, printed with 10 digits (enough to give the float back): the float of
  // each number of the file.
  const auto echoed = [&node](const char* group, const char* key) {
    return static_cast<float>(simtest::json_number_in(node, group, key));
  };
  EXPECT_EQ(echoed("model", "n"), 3.3e-3F);
  EXPECT_EQ(echoed("model", "n_filter_s"), 2e-3F);
  EXPECT_EQ(echoed("oscillation", "sigma"), 0.02F);
  EXPECT_EQ(echoed("oscillation", "f0_hz"), 6.0F);
  EXPECT_EQ(echoed("oscillation", "beta_per_s"), 1.57F);
  EXPECT_EQ(simtest::json_number_in(node, "model", "n_states"), 4.0);
  EXPECT_EQ(simtest::json_number_in(node, "node", "model_rejected"), 0.0);
  // Fig. 1 draws every kind of term the node runs, each from its own column of the model CSV:
  // the oscillation's ADEV is there (its bump near 1 / (2 f0)), the walk's (K = 0) is not.
  std::istringstream csv(simtest::read_text(dir.file("o") + "/fig1_adev_model.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  std::vector<std::string> header;
  for (std::istringstream h(line); std::getline(h, line, ',');) {
    header.push_back(line);
  }
  const auto column = [&header](const char* name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t osc = column("oscillation");
  const std::size_t walk = column("rate_random_walk");
  ASSERT_LT(osc, header.size());
  ASSERT_LT(walk, header.size());
  double osc_max = 0.0;
  double walk_max = 0.0;
  while (std::getline(csv, line)) {
    std::vector<double> v;
    for (std::istringstream row(line); std::getline(row, line, ',');) {
      v.push_back(std::stod(line));
    }
    ASSERT_EQ(v.size(), header.size());
    osc_max = std::max(osc_max, v[osc]);
    walk_max = std::max(walk_max, v[walk]);
  }
  EXPECT_GT(osc_max, 0.0);
  EXPECT_EQ(walk_max, 0.0);
  const std::string gp = simtest::read_text(dir.file("o") + "/fig1_adev.gp");
  const std::string osc_line = "using 1:($" + std::to_string(osc + 1) + ">0?$" +
                               std::to_string(osc + 1) + ":1/0)";
  EXPECT_NE(gp.find(osc_line), std::string::npos) << gp;
  EXPECT_NE(gp.find("title 'model: narrowband oscillation'"), std::string::npos) << gp;
  EXPECT_EQ(gp.find("title 'model: rate random walk'"), std::string::npos) << gp;
  // The text is about the same model: the node's, its oscillation with its parameters.
  EXPECT_NE(report.find("(the model pushed to the node, as it echoes it"), std::string::npos)
      << report;
  EXPECT_NE(report.find("Beyond the first-order model: narrowband oscillation f0 = 6.0000e+00 Hz, "
                        "sigma = 2.0000e-02 m/s^2"),
            std::string::npos)
      << report;
}

/// A model with more states than the node's filter holds once the oscillation is added (2 GM +
/// RRW + a 5-member flicker bank = 8): `run --model` gives the oscillation's variance to the
/// white noise (N'^2 = N^2 + sigma^2 / fs at the recording's rate), says so, and the node runs N'.
TEST(SimCli, RunModelFoldsAnOscillationTheNodeCannotHold) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  const std::string mat = dir.file("synth.mat");
  auto r = run({"synth", "--out", mat, "--duration", "200"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string model =
      "\"model_after\": {\"n\": 3.3e-3, "
      "\"q\": 0, \"gm\": [{\"sb\": 5.7e-9, \"tb_s\": 158.7}, {\"sb\": 1e-6, \"tb_s\": 0.2}], "
      "\"k\": 1e-5, \"r\": 0, \"sin_a\": 0, \"sin_f0_hz\": 0, \"sin2_a\": 0, \"sin2_f0_hz\": 0, "
      "\"bias_instability\": {\"b\": 1e-4, \"tau_lo_s\": 1, \"tau_hi_s\": 1000}, "
      "\"oscillation\": {\"sigma\": 0.02, \"f0_hz\": 6, \"beta_per_s\": 1.57}}";
  // A 100 Hz record's report, and a long record's (analysed on means of 4 at 25 Hz, its head at
  // the recording's 100 Hz): the node samples at 100 Hz in both (not the long one at the
  // means' rate, which would fold in 4 x the variance).
  for (const std::string& head : {std::string(), std::string(", \"full_rate_head\": "
                                                              "{\"n_samples\": 4194304, "
                                                              "\"fs_hz\": 100, \"block\": 4}")}) {
    const std::string f = dir.file("osc.json");
    std::ofstream(f) << "{\"channel\": \"acc_z\", \"fs_hz\": " << (head.empty() ? "100" : "25")
                     << ", " << model << head << "}";
    r = run({"run", mat, "--model", f, "--model-as-is", "--no-plots", "--quiet",
             "--sim-windows", "10", "--out", dir.file("o")});
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string report = simtest::read_text(dir.file("o") + "/report.txt");
    EXPECT_NE(report.find("its variance is added to the white noise"), std::string::npos)
        << report;
    const std::string json = simtest::read_text(dir.file("o") + "/report.json");
    // What the node echoes it runs (float in the record): sqrt(3.3e-3^2 + 0.02^2 / 100).
    const std::string node = json.substr(json.find("\"node\": {"));
    const double n_node = simtest::json_number_in(node, "model", "n");
    EXPECT_NEAR(n_node, std::sqrt(3.3e-3 * 3.3e-3 + 0.02 * 0.02 / 100.0), 1e-6) << head;
    EXPECT_EQ(simtest::json_number_in(node, "oscillation", "sigma"), 0.0);
    EXPECT_EQ(simtest::json_number_in(node, "model", "n_states"), 8.0);
  }
}

/// A malformed or missing model file is a one-line error, exit 1.
TEST(SimCli, RunModelFileErrors) {
  simtest::TempDir dir;
  const std::string mat = dir.file("synth.mat");
  auto r = run({"synth", "--out", mat, "--duration", "100"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string bad = dir.file("bad.json");
  {
    std::ofstream(bad) << "{\"channel\": \"acc_z\", \"model_before\": {}}";
  }
  for (const std::string& f : {bad, dir.file("absent.json")}) {
    r = run({"run", mat, "--model", f, "--no-plots", "--quiet", "--out", dir.file("o")});
    EXPECT_EQ(r.status, 1) << f;
    EXPECT_EQ(simtest::count_lines(r.err), 1U) << r.err;
  }
}

// `--version`, and a near miss named: an option one typo away, a command with two letters
// swapped; nothing suggested for a word far from every name.
TEST(SimCli, VersionAndDidYouMean) {
  auto r = run({"--version"});
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("imu-sim ", 0), 0U) << r.out;
  r = run({"--version"}, true);
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("imu-fw ", 0), 0U) << r.out;
  r = run({"adev", "x.mat", "--chanel", "acc_z"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("did you mean --channel?"), std::string::npos) << r.err;
  r = run({"adve", "x.mat"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("did you mean adev?"), std::string::npos) << r.err;
  r = run({"adev", "x.mat", "--frobnicate", "1"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.find("did you mean"), std::string::npos) << r.err;
}

// `synth --model A.json` simulates the model an analysis found: a record made by synth (the
// example's first-order model plus a rate random walk), analysed; the analysis's JSON
// simulated again by synth --model. The new record's exact ADEV follows the analysis's model
// (computed here from the JSON's numbers with the formulas of MODELS.md, not by the code under
// test) within 10 % at taus from Ts to 100 s, and its own analysis finds the same white noise
// within 5 %.
TEST(SimCli, SynthFromAnAnalysisFollowsItsModel) {
  SKIP_IF_EMULATED();  // two analyses of 2e6 samples: minutes under qemu-user
  simtest::TempDir dir;
  const std::string rec = dir.file("rec.mat");
  ASSERT_EQ(run({"synth", "--out", rec, "--duration", "20000", "--seed", "4711", "--K",
                 "1e-4"}).status, 0);
  const std::string a1 = dir.file("a1.json");
  ASSERT_EQ(run({"analyze", rec, "--channel", "acc_z", "--json", a1}).status, 0);
  const std::string sim = dir.file("sim.mat");
  const auto r = run({"synth", "--model", a1, "--out", sim, "--duration", "20000", "--seed",
                      "90210"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j1 = simtest::read_text(a1);
  const std::size_t after = j1.find("\"model_after\": ");
  ASSERT_NE(after, std::string::npos);
  const auto num = [&j1, after](const std::string& key, std::size_t from = 0) {
    const std::size_t p = j1.find("\"" + key + "\": ", std::max(after, from));
    return p == std::string::npos ? std::nan("") : std::strtod(j1.c_str() + p + key.size() + 4,
                                                               nullptr);
  };
  const double n = num("n");
  const double k = num("k");
  std::vector<std::pair<double, double>> gm;  // (sb, tb_s)
  const std::size_t gm_at = j1.find("\"gm\": [", after);
  const std::size_t gm_end = j1.find(']', gm_at);
  for (std::size_t p = j1.find("\"sb\": ", gm_at); p < gm_end; p = j1.find("\"sb\": ", p + 1)) {
    gm.emplace_back(std::strtod(j1.c_str() + p + 6, nullptr), num("tb_s", p));
  }
  ASSERT_TRUE(n > 0.0 && !gm.empty()) << j1.substr(after, 400);
  const auto model_adev = [&](double tau) {
    double avar = n * n / tau + k * k * tau / 3.0;  // MODELS.md: white, rate random walk
    for (const auto& [sb, tb] : gm) {                // first-order Gauss-Markov
      avar += sb * tb * tb / tau *
              (1.0 - tb / (2.0 * tau) * (3.0 - 4.0 * std::exp(-tau / tb) + std::exp(-2.0 * tau / tb)));
    }
    return std::sqrt(avar);
  };
  const std::string aj = dir.file("adev.json");
  ASSERT_EQ(run({"adev", sim, "--channel", "acc_z", "--json", aj}).status, 0);
  const auto rows = simtest::json_adev(simtest::read_text(aj));
  std::size_t checked = 0;
  for (const auto& row : rows) {
    if (row.tau_s <= 100.0) {
      EXPECT_NEAR(row.adev / model_adev(row.tau_s), 1.0, 0.10) << "tau " << row.tau_s;
      ++checked;
    }
  }
  EXPECT_GE(checked, 12U);
  const std::string a2 = dir.file("a2.json");
  ASSERT_EQ(run({"analyze", sim, "--channel", "acc_z", "--json", a2}).status, 0);
  const std::string j2 = simtest::read_text(a2);
  const double n2 = std::strtod(j2.c_str() + j2.find("\"n\": ", j2.find("\"model_after\": ")) + 5,
                                nullptr);
  EXPECT_NEAR(n2 / n, 1.0, 0.05);
  // The model given twice is a usage error.
  EXPECT_EQ(run({"synth", "--model", a1, "--N", "1e-3", "--out", sim}).status, 2);
}

// A channel name one typo away from one the file holds gets "did you mean" (adev, analyze, run
// alike, MAT and text); a name near none gets the list alone.
TEST(SimCli, AMistypedChannelGetsDidYouMean) {
  simtest::TempDir dir;
  const std::string mat = dir.file("s.mat");
  ASSERT_EQ(run({"synth", "--out", mat, "--duration", "10"}).status, 0);
  const std::string csv = dir.file("s.csv");
  {
    std::ofstream f(csv);
    f << "t,gyro_z\n";
    for (int i = 0; i < 100; ++i) {
      f << i * 0.01 << "," << (i % 7) * 1e-3 << "\n";
    }
  }
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"adev", mat, "--channel", "acc_zz"},
           {"analyze", mat, "--channel", "acc_zz"},
           {"adev", csv, "--channel", "gyro_zz"},
           {"run", csv, "--channel", "gyro_zz", "--out", dir.file("o")}}) {
    const auto r = run(args);
    EXPECT_EQ(r.status, 2) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find(args[1] == mat ? "did you mean acc_z?" : "did you mean gyro_z?"),
              std::string::npos)
        << args[0] << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1U) << r.err;
  }
  const auto r = run({"adev", mat, "--channel", "zzzzzz"});
  EXPECT_EQ(r.err.find("did you mean"), std::string::npos) << r.err;
}

namespace {

// A 1 h accelerometer record (100 Hz): white noise N 3.3e-3, a GM of Tb 158.7 s, a sinusoid of
// 0.01 m/s^2 at 0.37 Hz and a ramp of 2e-6 m/s^2/s, offset by gravity; seed 97301.
void write_signal_record(const std::string& path) {
  constexpr double kFs = 100.0;
  constexpr std::size_t kN = 360000;
  imu::GaussianRng rng(97301);
  const double phi = std::exp(-1.0 / (kFs * 158.7));
  const double q = 3e-4 * std::sqrt(1.0 - phi * phi);
  double gm = 0.0;
  std::vector<double> z(kN);
  for (std::size_t k = 0; k < kN; ++k) {
    const double t = static_cast<double>(k) / kFs;
    gm = phi * gm + q * rng.normal();
    z[k] = 9.81 + gm + 3.3e-3 * std::sqrt(kFs) * rng.normal() +
           0.01 * std::sin(2.0 * 3.14159265358979 * 0.37 * t + 1.0) + 2e-6 * t;
  }
  imu::mat::MatWriter w;
  ASSERT_TRUE(w.add_column("acc_z", z).ok());
  ASSERT_TRUE(w.add_scalar("fs", kFs).ok());
  ASSERT_TRUE(w.save(path).ok());
}

// The selected channel's row of the run JSON's node.channels.
std::string channel_row(const std::string& json) {
  const std::size_t c = json.find("\"channels\": [", json.find("\"node\": {"));
  return c == std::string::npos ? std::string() : json.substr(c, json.find('}', c) - c);
}

}  // namespace

/// The deterministic terms the analysis selects run on the node: with model_after's sinusoid
/// (and ramp, where named) pushed in their ModelSignalsRecord, the node's innovations are white,
/// NIS about 1 and the CUSUM quiet; the same model with them zeroed in the JSON leaves the
/// sinusoid in the innovations, which the monitors see (whiteness or CUSUM).
TEST(SimCli, RunModelSendsTheSinusoidAndRampAndTheNodeRunsThem) {
  SKIP_IF_EMULATED();
  simtest::TempDir dir;
  const std::string mat = dir.file("sig.mat");
  write_signal_record(mat);
  const std::string a = dir.file("a.json");
  auto r = run({"analyze", mat, "--channel", "acc_z", "--json", a});
  ASSERT_EQ(r.status, 0) << r.err;
  std::string analysis = simtest::read_text(a);
  ASSERT_NE(analysis.find("\"type\": \"sinusoid\""), std::string::npos) << r.out;
  // As the analysis gives them (--model-as-is): the node tuning would otherwise add an
  // oscillation where a sinusoid is missing, which is not what this compares.
  r = run({"run", mat, "--channel", "acc_z", "--model", a, "--model-as-is", "--no-plots",
           "--quiet", "--sim-windows", "10", "--out", dir.file("with")});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string with = simtest::read_text(dir.file("with") + "/report.json");
  const std::string node = with.substr(with.find("\"node\": {"));
  EXPECT_NE(node.find("\"sinusoids\": [{\"a\": "), std::string::npos) << node.substr(0, 1200);
  const std::string row = channel_row(with);
  const double nis = simtest::json_number_in(row, "channels", "nis_mean");
  std::printf("with the deterministic terms: %s\n", row.c_str());
  EXPECT_NE(row.find("\"whiteness_passed\": true"), std::string::npos) << row;
  EXPECT_NE(row.find("\"cusum_alarm\": false"), std::string::npos) << row;
  EXPECT_GE(nis, 0.8);
  EXPECT_LE(nis, 1.25);
  // The control: the same analysis without them.
  for (const std::string key : {"\"sin_a\": ", "\"r\": "}) {
    const std::size_t k = analysis.find(key, analysis.find("\"model_after\""));
    ASSERT_NE(k, std::string::npos);
    analysis.replace(k + key.size(), analysis.find(',', k) - k - key.size(), "0");
  }
  const std::string b = dir.file("b.json");
  std::ofstream(b) << analysis;
  r = run({"run", mat, "--channel", "acc_z", "--model", b, "--model-as-is", "--no-plots",
           "--quiet", "--sim-windows", "10", "--out", dir.file("without")});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string without_row =
      channel_row(simtest::read_text(dir.file("without") + "/report.json"));
  std::printf("without them: %s\n", without_row.c_str());
  EXPECT_TRUE(without_row.find("\"whiteness_passed\": false") != std::string::npos ||
              without_row.find("\"cusum_alarm\": true") != std::string::npos)
      << without_row;
}

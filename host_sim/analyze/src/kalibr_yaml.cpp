// Kalibr imu.yaml from the analysed channels (see analyze.hpp kalibr_yaml).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/cli/file_out.hpp"
#include "imu/cli/json.hpp"
#include "imu/model_fit.hpp"
#include "imu/terms.hpp"

namespace imu::analyze {
namespace {

struct KalibrAxis {
  std::string channel;
  double n = 0.0;       // noise density [unit/sqrt(Hz)]
  double k = 0.0;       // random walk [unit/s/sqrt(Hz)]
  bool k_bound = false;  // k is the upper bound (no walk in the model's ADEV)
  bool k_named = false;  // k is the named rate_random_walk effect's
};

// The Kalibr family (white + random walk) fitted to the after-model's ADEV over the analysed
// taus with relative weights (the same fit as the analysis, on the model's curve instead of
// the data's): the projection of the full model onto the two numbers Kalibr takes. A model
// without any rise at long tau gives K = 0 there; Kalibr needs K > 0, so K is then the largest
// walk the model allows at T/10 (its AVAR there equals the model's) and marked as a bound.
KalibrAxis project(const Report& r) {
  KalibrAxis a;
  a.channel = r.channel;
  std::vector<AdevPoint> pts;
  double tau_max = 0.0;
  for (const AdevPoint& p : r.adev_clean) {
    if (p.tau_s <= r.error_after.tau_max_s * (1.0 + 1e-9) && p.tau_s > 0.0) {
      AdevPoint q = p;
      q.avar = model_avar(r.model_after, p.tau_s);
      q.edf = 100.0;  // equal relative weight per tau
      if (q.avar > 0.0 && std::isfinite(q.avar)) {
        pts.push_back(q);
        tau_max = std::max(tau_max, p.tau_s);
      }
    }
  }
  if (pts.size() < 3) {
    a.n = r.model_after.n;
    return a;
  }
  FitOptions fo;
  fo.terms = kFitWhite | kFitRrw;
  fo.tau_min_s = pts.front().tau_s;
  fo.tau_max_s = tau_max;
  const FitResult f = fit(pts.data(), pts.size(), fo);
  a.n = f.status == FitStatus::kOk && f.params.n > 0.0 ? f.params.n : r.model_after.n;
  a.k = f.status == FitStatus::kOk ? f.params.k : 0.0;
  // A walk the analysis named is Kalibr's term itself: its K (the record's likelihood estimate
  // when a slow GM beside it was not needed) is taken over the projection.
  for (const Effect& e : r.effects) {
    if (e.type == term_info(TermKind::kRateRandomWalk).name && e.k > 0.0) {
      a.k = e.k;
      a.k_named = true;
    }
  }
  if (!(a.k > 0.0)) {
    a.k = std::sqrt(3.0 * model_avar(r.model_after, tau_max) / tau_max);
    a.k_bound = true;
  }
  return a;
}

// Always with a mantissa dot: YAML 1.1 loaders (PyYAML, which Kalibr uses) read "1e-05" as a
// string and only "1.0000e-05" as a float.
std::string g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4e", v);
  return buf;
}

std::string list(const std::vector<KalibrAxis>& axes, bool walk) {
  std::string s = "[";
  for (std::size_t i = 0; i < axes.size(); ++i) {
    s += (i > 0 ? ", " : "") + g(walk ? axes[i].k : axes[i].n);
  }
  return s + "]";
}

// The largest axis's N (or K with walk).
double worst(const std::vector<KalibrAxis>& v, bool walk) {
  double m = 0.0;
  for (const auto& a : v) {
    m = std::max(m, walk ? a.k : a.n);
  }
  return m;
}

// The axes' channel names, each a quoted YAML scalar.
std::string names(const std::vector<KalibrAxis>& v) {
  std::string s;
  for (const auto& a : v) {
    s += (s.empty() ? "" : ", ") + imu::cli::json_str(a.channel);
  }
  return s;
}

// Where each axis's K comes from (see the file's closing comment).
std::string sources(const std::vector<KalibrAxis>& v) {
  std::string s;
  for (const auto& a : v) {
    const char* from = a.k_bound ? "bound" : (a.k_named ? "named" : "fit");
    s += std::string(s.empty() ? "" : ", ") + from;
  }
  return "[" + s + "]";
}

// One comment line per channel with its full model after.
std::string terms(const std::vector<const Report*>& v) {
  std::string s;
  for (const Report* r : v) {
    const ModelParams& p = r->model_after;
    s += "#   " + imu::cli::term_safe(r->channel) + ": N " + g(p.n);
    for (std::size_t i = 0; i < p.n_gm; ++i) {
      s += ", GM (Sb " + g(p.gm[i].sb) + ", Tb " + g(p.gm[i].tb_s) + " s)";
    }
    s += p.k > 0.0 ? ", K " + g(p.k) : "";
    s += p.bi > 0.0 ? ", bias instability B " + g(p.bi) : "";
    s += p.q > 0.0 ? ", quantization Q " + g(p.q) : "";
    s += p.osc_sigma > 0.0 ? ", oscillation sigma " + g(p.osc_sigma) + " at " +
                                 g(p.osc_f0_hz) + " Hz" : "";
    s += p.sin_a > 0.0 ? ", sinusoid A " + g(p.sin_a) + " at " + g(p.sin_f0_hz) + " Hz" : "";
    s += "\n";
  }
  return s;
}

// The channels' bias instability B.
std::string bis(const std::vector<const Report*>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    s += (i > 0 ? ", " : "") + g(v[i]->model_after.bi);
  }
  return s + "]";
}

}  // namespace

bool kalibr_yaml(const std::vector<Report>& reports, const std::string& source, std::string& yaml,
                 std::string& err) {
  std::vector<KalibrAxis> acc;
  std::vector<KalibrAxis> gyro;
  std::vector<const Report*> acc_r;
  std::vector<const Report*> gyro_r;
  double fs = 0.0;
  for (const Report& r : reports) {
    fs = r.head.samples > 0 ? r.head.fs_hz : r.fs_hz;  // a long record: the IMU's rate, not
                                                       // its block means'
    if (r.sensor == "accelerometer") {
      acc.push_back(project(r));
      acc_r.push_back(&r);
    } else if (r.sensor == "gyroscope") {
      gyro.push_back(project(r));
      gyro_r.push_back(&r);
    }
  }
  if (acc.empty() || gyro.empty()) {
    err = "--yaml needs at least one accelerometer and one gyroscope channel (Kalibr takes "
          "both sensors): declare them with --acc COLS --gyro COLS";
    return false;
  }
  // Kalibr's keys: the sensor's prefix and the registry's key of the term.
  const std::string nd = term_info(TermKind::kWhite).yaml;
  const std::string rw = term_info(TermKind::kRateRandomWalk).yaml;
  const std::string acc_key = "accelerometer_";
  const std::string gyro_key = "gyroscope_";
  yaml = "# IMU noise parameters for Kalibr (github.com/ethz-asl/kalibr/wiki/IMU-Noise-Model),\n"
         "# written by imu-sim analyze from " + imu::cli::term_safe(source) + ".\n"
         "# noise_density: white noise N, continuous time (AVAR N^2/tau); random_walk: bias\n"
         "# random walk K (AVAR K^2 tau/3). N: the white + walk model fitted to the analysed\n"
         "# model's ADEV over [Ts, T/10] (equal relative weight per tau), Kalibr's two-term family\n"
         "# closest to everything the analysis found; K: the named rate_random_walk's K \"(walk:\n"
         "# named)\", else that fit's. One number per sensor: the largest axis (conservative).\n"
         "# Per-axis values and the full models follow as extra keys and comments.\n"
         + acc_key + nd + ": " + g(worst(acc, false)) + "  # m/s^2/sqrt(Hz)\n"
         + acc_key + rw + ": " + g(worst(acc, true)) + "  # m/s^3/sqrt(Hz)\n"
         + gyro_key + nd + ": " + g(worst(gyro, false)) + "  # rad/s/sqrt(Hz)\n"
         + gyro_key + rw + ": " + g(worst(gyro, true)) + "  # rad/s^2/sqrt(Hz)\n"
         "update_rate: " + g(fs) + "  # Hz\n"
         "rostopic: /imu0\n"
         "# Extra keys (Kalibr ignores them), per axis in the order of *_axes:\n"
         "accelerometer_axes: [" + names(acc) + "]\n"
         + acc_key + nd + "_per_axis: " + list(acc, false) + "\n"
         + acc_key + rw + "_per_axis: " + list(acc, true) + "\n"
         + acc_key + rw + "_source_per_axis: " + sources(acc) + "\n"
         "accelerometer_bias_instability_per_axis: " + bis(acc_r) + "  # IEEE 952 B, m/s^2\n"
         "gyroscope_axes: [" + names(gyro) + "]\n"
         + gyro_key + nd + "_per_axis: " + list(gyro, false) + "\n"
         + gyro_key + rw + "_per_axis: " + list(gyro, true) + "\n"
         + gyro_key + rw + "_source_per_axis: " + sources(gyro) + "\n"
         "gyroscope_bias_instability_per_axis: " + bis(gyro_r) + "  # IEEE 952 B, rad/s\n"
         "# The full models (model_after: GM drive PSD Sb and time Tb, etc.):\n" +
         terms(acc_r) + terms(gyro_r) +
         "# random_walk_source: named = the rate_random_walk the analysis named; fit = the white +\n"
         "# walk projection; bound = no walk in that axis's model, K is the largest walk its ADEV\n"
         "# at T/10 allows (Kalibr needs K > 0).\n";
  return true;
}

}  // namespace imu::analyze

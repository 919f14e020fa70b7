// See model_json.hpp. A minimal, depth-aware scanner: enough JSON for the analysis file
// (objects, arrays, strings without escapes that matter here, numbers); no new dependency.
#include "model_json.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "imu/analyze/node_tuning.hpp"
#include "imu/node/node.hpp"

namespace imu::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A number for a message: 6 significant digits.
std::string num_text(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Index one past the value starting at i (object, array, string or scalar); npos if unclosed.
std::size_t skip_value(const std::string& s, std::size_t i) {
  if (i >= s.size()) {
    return std::string::npos;
  }
  if (s[i] == '"') {
    for (std::size_t k = i + 1; k < s.size(); ++k) {
      if (s[k] == '\\') {
        ++k;
      } else if (s[k] == '"') {
        return k + 1;
      }
    }
    return std::string::npos;
  }
  if (s[i] == '{' || s[i] == '[') {
    int depth = 0;
    for (std::size_t k = i; k < s.size(); ++k) {
      const char c = s[k];
      if (c == '"') {
        k = skip_value(s, k);
        if (k == std::string::npos) {
          return k;
        }
        --k;
      } else if (c == '{' || c == '[') {
        ++depth;
      } else if (c == '}' || c == ']') {
        if (--depth == 0) {
          return k + 1;
        }
      }
    }
    return std::string::npos;
  }
  std::size_t k = i;
  while (k < s.size() && s[k] != ',' && s[k] != '}' && s[k] != ']') {
    ++k;
  }
  return k;
}

std::size_t skip_ws(const std::string& s, std::size_t i) {
  while (i < s.size() && (s[i] == ' ' || s[i] == '\n' || s[i] == '\r' || s[i] == '\t')) {
    ++i;
  }
  return i;
}

// Position of the value of `key` among the members of the object starting at obj ('{'), npos
// if absent or malformed.
std::size_t member(const std::string& s, std::size_t obj, const std::string& key) {
  if (obj >= s.size() || s[obj] != '{') {
    return std::string::npos;
  }
  std::size_t i = skip_ws(s, obj + 1);
  while (i < s.size() && s[i] == '"') {
    const std::size_t key_end = skip_value(s, i);
    if (key_end == std::string::npos) {
      return key_end;
    }
    const std::string k = s.substr(i + 1, key_end - i - 2);
    i = skip_ws(s, key_end);
    if (i >= s.size() || s[i] != ':') {
      return std::string::npos;
    }
    i = skip_ws(s, i + 1);
    if (k == key) {
      return i;
    }
    i = skip_value(s, i);
    if (i == std::string::npos) {
      return i;
    }
    i = skip_ws(s, i);
    if (i < s.size() && s[i] == ',') {
      i = skip_ws(s, i + 1);
    }
  }
  return std::string::npos;
}

bool number_at(const std::string& s, std::size_t i, double& v) {
  if (i >= s.size()) {
    return false;
  }
  const char* b = s.c_str() + i;
  char* e = nullptr;
  v = std::strtod(b, &e);
  return e != b && std::isfinite(v);
}

bool get_number(const std::string& s, std::size_t obj, const std::string& key, double& v,
                std::string& err) {
  if (!number_at(s, member(s, obj, key), v)) {
    err = "model_after." + key + " missing or not a finite number";
    return false;
  }
  if (std::fabs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
    err = "model_after." + key + " is beyond the node's single precision";
    return false;
  }
  return true;
}

// The member `key` of the object at obj is the string `value` (no escapes compared).
bool string_member_is(const std::string& s, std::size_t obj, const std::string& key,
                      const std::string& value) {
  const std::size_t v = member(s, obj, key);
  const std::size_t v_end = skip_value(s, v);
  return v != std::string::npos && v_end != std::string::npos && s[v] == '"' && v_end - v >= 2 &&
         s.compare(v + 1, v_end - v - 2, value) == 0;
}

// A record the node would refuse only for its version 2 terms (more states than its filter
// holds, or a term out of its ranges) loses what the node can do without, and the rest is sent
// as the node runs it. At each stage the bias-instability bank's short end may first move up a
// decade (one state) at a time while the bank spans two decades: the node then realises B from
// there up; below it the bank's ADEV falls off where the white noise dominates the data's
// (flicker_tau_lo's rule). The stages: the record as it is; the output filter left out (the
// white noise unfiltered changes a sample's variance by about 1.5 n_filter_s / Ts); the
// oscillation's variance moved to the white noise per sample (N'^2 = N^2 + sigma^2 / fs:
// innovations of the right variance, NIS ~ 1, though not of its colour, which the whiteness
// monitor still sees). A record refused for another reason is sent as it is: the node refuses
// and counts it. n: model_after's N; root: the channel's object (its fs_hz, or its full-rate
// head's). Notes go to `dropped`.
bool fit_to_node(const std::string& json, std::size_t root, double n, std::size_t reserved,
                 hal::ModelRecord& rec, std::string& dropped, std::string& err) {
  const auto runs = [reserved](const hal::ModelRecord& m) {
    ModelParams p{};
    return node::model_record_valid(m, p, reserved);
  };
  const auto note = [&dropped](const std::string& t) {
    dropped += (dropped.empty() ? "" : "; ") + t;
  };
  // A bank the node refuses at every width (a zero or non-finite end, a B out of range) ends
  // the narrowing where the float's range does: at most 83 decades. Two decades stay.
  const auto narrowed = [reserved](hal::ModelRecord m) {
    (void)analyze::narrow_flicker_bank(m, 100.0F, reserved);
    return m;
  };
  const auto runs_narrowed = [&](const hal::ModelRecord& m) { return runs(narrowed(m)); };
  // m as it is or with its bank narrowed (said); false if neither runs.
  const auto fits = [&](hal::ModelRecord& m) {
    if (runs(m)) {
      return true;
    }
    const hal::ModelRecord nm = narrowed(m);
    if (!runs(nm)) {
      return false;
    }
    note("bias instability of model_after realised by the node from " +
         num_text(static_cast<double>(nm.bi_tau_lo_s)) + " s, not " +
         num_text(static_cast<double>(m.bi_tau_lo_s)) + " s: its bank's members below would " +
         "exceed the node's " + std::to_string(node::kNodeProcessStates) + " states");
    m = nm;
    return true;
  };
  hal::ModelRecord unfiltered = rec;
  unfiltered.n_filter_s = 0.0F;
  hal::ModelRecord no_osc = rec;
  no_osc.osc_sigma = 0.0F;
  no_osc.osc_f0_hz = 0.0F;
  no_osc.osc_beta_per_s = 0.0F;
  hal::ModelRecord base = no_osc;
  base.n_filter_s = 0.0F;
  if (runs(rec) || !runs_narrowed(base) || fits(rec)) {
    return true;
  }
  const std::string why = " (the model with it is not one the node runs: more than " +
                          std::to_string(node::kNodeProcessStates) +
                          " states, or out of its ranges)";
  if (rec.n_filter_s > 0.0F && (runs_narrowed(unfiltered) || !runs_narrowed(no_osc))) {
    note("output filter of model_after (" + num_text(static_cast<double>(rec.n_filter_s)) +
         " s) not sent" + why + ": the white noise goes unfiltered");
    rec = unfiltered;
    if (fits(rec)) {
      return true;
    }
  }
  // Only the oscillation is left to go. A long record's report is at its block means' rate; the
  // node samples at the recording's, which its full-rate head carries.
  const std::size_t head = member(json, root, "full_rate_head");
  const std::size_t rate = member(json, head != std::string::npos ? head : root, "fs_hz");
  double fs_hz = 0.0;
  if (!number_at(json, rate, fs_hz) || !(fs_hz > 0.0)) {
    err = "model_after has an oscillation the node cannot run as states, and the JSON no valid "
          "fs_hz to add its variance to the white noise";
    return false;
  }
  const auto sigma = static_cast<double>(rec.osc_sigma);
  const double n_eff = std::sqrt(n * n + sigma * sigma / fs_hz);
  rec.n = static_cast<float>(n_eff);
  rec.osc_sigma = 0.0F;
  rec.osc_f0_hz = 0.0F;
  rec.osc_beta_per_s = 0.0F;
  note("oscillation of model_after (sigma " + num_text(sigma) + ") not sent as states" + why +
       ": its variance is added to the white noise (N " + std::to_string(n) + " -> " +
       std::to_string(n_eff) + ")");
  (void)fits(rec);  // runs: base does, with its bank narrowed
  return true;
}

}  // namespace

bool analysis_holds_channel(const std::string& json, const std::string& channel_name) {
  const std::size_t root = skip_ws(json, 0);
  const std::size_t chans = member(json, root, "channels");
  if (chans != std::string::npos && json[chans] == '{') {
    return member(json, chans, channel_name) != std::string::npos;
  }
  return string_member_is(json, root, "channel", channel_name);
}

namespace {

// The object of `channel_name` in an analysis JSON: the root, or the member of its "channels"
// object in a whole-IMU analysis (`analyze --channel all`: {"file", "channels": {NAME: {...}}}).
// npos with err when it is not there.
std::size_t channel_object(const std::string& json, const std::string& channel_name,
                           std::string& err) {
  std::size_t root = skip_ws(json, 0);
  if (root >= json.size() || json[root] != '{' || skip_value(json, root) == std::string::npos) {
    err = "not a JSON object";
    return std::string::npos;
  }
  const std::size_t chans = member(json, root, "channels");
  if (chans != std::string::npos && json[chans] == '{') {
    root = member(json, chans, channel_name);
    if (root == std::string::npos || json[root] != '{') {
      err = "its \"channels\" hold no " + channel_name;
      return std::string::npos;
    }
  }
  if (!string_member_is(json, root, "channel", channel_name)) {
    err = "its \"channel\" is not " + channel_name + " (the analysis of another channel?)";
    return std::string::npos;
  }
  return root;
}

// model_after.gm: at most the record's two GM terms.
bool read_gm_terms(const std::string& json, std::size_t m, hal::ModelRecord& rec,
                   std::string& err) {
  const std::size_t gm = member(json, m, "gm");
  if (gm == std::string::npos || json[gm] != '[') {
    err = "model_after.gm missing or not a list";
    return false;
  }
  std::size_t i = skip_ws(json, gm + 1);
  std::size_t n_gm = 0;
  while (i < json.size() && json[i] == '{') {
    if (n_gm == 2) {
      err = "model_after.gm has more than the 2 GM terms the node's model record holds";
      return false;
    }
    double sb = 0.0;
    double tb = 0.0;
    if (!get_number(json, i, "sb", sb, err) || !get_number(json, i, "tb_s", tb, err)) {
      err.insert(0, "model_after.gm[]: ");
      return false;
    }
    rec.gm_sb[n_gm] = static_cast<float>(sb);
    rec.gm_tb_s[n_gm] = static_cast<float>(tb);
    ++n_gm;
    i = skip_ws(json, skip_value(json, i));
    if (i < json.size() && json[i] == ',') {
      i = skip_ws(json, i + 1);
    }
  }
  return true;
}

bool read_bias_instability(const std::string& json, std::size_t m, hal::ModelRecord& rec,
                           std::string& err) {
  const std::size_t bi = member(json, m, "bias_instability");
  double b = 0.0;
  double lo = 0.0;
  double hi = 0.0;
  if (bi == std::string::npos || !get_number(json, bi, "b", b, err) ||
      !get_number(json, bi, "tau_lo_s", lo, err) || !get_number(json, bi, "tau_hi_s", hi, err)) {
    err = "model_after.bias_instability {B, tau_lo_s, tau_hi_s} missing or malformed";
    return false;
  }
  rec.bi = static_cast<float>(b);
  rec.bi_tau_lo_s = static_cast<float>(lo);
  rec.bi_tau_hi_s = static_cast<float>(hi);
  return true;
}

// The narrowband oscillation (2 filter states): sigma absent or 0 means none.
bool read_oscillation(const std::string& json, std::size_t m, hal::ModelRecord& rec,
                      std::string& dropped, std::string& err) {
  const std::size_t osc = member(json, m, "oscillation");
  double osc_sigma = 0.0;
  if (osc == std::string::npos || !get_number(json, osc, "sigma", osc_sigma, err) ||
      !(osc_sigma > 0.0)) {
    return true;
  }
  double f0 = 0.0;
  double beta = 0.0;
  if (!get_number(json, osc, "f0_hz", f0, err) ||
      !get_number(json, osc, "beta_per_s", beta, err)) {
    err = "model_after.oscillation {sigma, f0_hz, beta_per_s} malformed";
    return false;
  }
  // Fitted as point samples (the ADEV of m-sample means): the node sees the process through
  // its averaging sampler, whose sample means' AVAR is the continuous average's; a band at f0
  // seen so needs sigma x / sin(x), x = pi f0 Ts, to give the data's ADEV (exact for a line).
  double point_ts_s = 0.0;
  if (member(json, osc, "point_sampled_ts_s") != std::string::npos &&
      !get_number(json, osc, "point_sampled_ts_s", point_ts_s, err)) {
    err = "model_after.oscillation.point_sampled_ts_s malformed";
    return false;
  }
  const double x = kPi * f0 * point_ts_s;
  if (x > 0.0 && x < 0.5 * kPi) {
    const double averaged = osc_sigma * x / std::sin(x);
    dropped += std::string(dropped.empty() ? "" : "; ") + "oscillation of model_after (sigma " +
               num_text(osc_sigma) + " in point samples) sent as " + num_text(averaged) +
               ", the sigma the node's averaging sampler needs for the same ADEV";
    osc_sigma = averaged;
  }
  rec.osc_sigma = static_cast<float>(osc_sigma);
  rec.osc_f0_hz = static_cast<float>(f0);
  rec.osc_beta_per_s = static_cast<float>(beta);
  return true;
}


// The base a record keeps at the last stage of fit_to_node (no output filter, no oscillation,
// the bank narrowed): the node runs it beside `reserved` states of deterministic terms.
bool base_runs(hal::ModelRecord m, std::size_t reserved) {
  m.n_filter_s = 0.0F;
  m.osc_sigma = 0.0F;
  m.osc_f0_hz = 0.0F;
  m.osc_beta_per_s = 0.0F;
  (void)analyze::narrow_flicker_bank(m, 100.0F, reserved);
  ModelParams p{};
  return node::model_record_valid(m, p, reserved);
}

// model_after's ramp and sinusoids as a ModelSignalsRecord (has: any of them present), their
// memory the analysed record's length. False with err for a malformed number.
bool read_signals(const std::string& json, std::size_t root, std::size_t m, double r,
                  double sin_a, double sin2_a, hal::ModelSignalsRecord& out, bool& has,
                  std::string& err) {
  has = r > 0.0 || r < 0.0 || sin_a > 0.0 || sin2_a > 0.0;
  if (!has) {
    return true;
  }
  double f1 = 0.0;
  double f2 = 0.0;
  if ((sin_a > 0.0 && !get_number(json, m, "sin_f0_hz", f1, err)) ||
      (sin2_a > 0.0 && !get_number(json, m, "sin2_f0_hz", f2, err))) {
    return false;
  }
  double n_samples = 0.0;
  double fs_hz = 0.0;
  const bool length = number_at(json, member(json, root, "n_samples"), n_samples) &&
                      number_at(json, member(json, root, "fs_hz"), fs_hz) && fs_hz > 0.0;
  out = hal::ModelSignalsRecord{};
  out.ramp_r = static_cast<float>(r);
  out.sin_a[0] = static_cast<float>(sin_a);
  out.sin_f0_hz[0] = static_cast<float>(sin_a > 0.0 ? f1 : 0.0);
  out.sin_a[1] = static_cast<float>(sin2_a);
  out.sin_f0_hz[1] = static_cast<float>(sin2_a > 0.0 ? f2 : 0.0);
  const double memory = length ? n_samples / fs_hz : 0.0;
  const auto lo = static_cast<double>(node::kMinSignalMemoryS);
  const auto hi = static_cast<double>(node::kMaxSignalMemoryS);
  out.memory_s = static_cast<float>(memory < lo ? 0.0 : (memory > hi ? hi : memory));
  return true;
}

// model_from_analysis_json (both): with_signals = false leaves the deterministic terms out
// (said in `dropped`) and gives the stochastic terms every state.
bool read_node_model(const std::string& json, const std::string& channel_name,
                     std::size_t channel_index, bool with_signals, NodeModel& out,
                     std::string& dropped, std::string& err) {
  const std::size_t root = channel_object(json, channel_name, err);
  if (root == std::string::npos) {
    return false;
  }
  const std::size_t m = member(json, root, "model_after");
  if (m == std::string::npos || json[m] != '{') {
    err = "no \"model_after\" object (write it with imu-sim analyze FILE --channel C --json OUT)";
    return false;
  }
  double n = 0.0;
  double q = 0.0;
  double k = 0.0;
  double r = 0.0;
  double sin_a = 0.0;
  double sin2_a = 0.0;
  if (!get_number(json, m, "n", n, err) || !get_number(json, m, "q", q, err) ||
      !get_number(json, m, "k", k, err) || !get_number(json, m, "r", r, err) ||
      !get_number(json, m, "sin_a", sin_a, err) || !get_number(json, m, "sin2_a", sin2_a, err)) {
    return false;
  }
  // The output filter of the white noise: absent in an analysis that does not fit one (0).
  double n_filter_s = 0.0;
  if (member(json, m, "n_filter_s") != std::string::npos &&
      !get_number(json, m, "n_filter_s", n_filter_s, err)) {
    return false;
  }
  NodeModel nm{};
  hal::ModelRecord& rec = nm.rec;
  rec.version = hal::kModelVersion2;
  rec.channel = static_cast<std::uint8_t>(channel_index);
  rec.n = static_cast<float>(n);
  rec.q = static_cast<float>(q);
  rec.k = static_cast<float>(k);
  if (!read_gm_terms(json, m, rec, err) || !read_bias_instability(json, m, rec, err) ||
      !read_signals(json, root, m, r, sin_a, sin2_a, nm.signals, nm.has_signals, err)) {
    return false;
  }
  nm.signals.channel = rec.channel;
  dropped.clear();
  if (nm.has_signals && !with_signals) {
    dropped = "ramp/sinusoids of model_after not included (deterministic terms)";
    nm.has_signals = false;
  }
  rec.n_filter_s = static_cast<float>(n_filter_s);
  if (!read_oscillation(json, m, rec, dropped, err)) {
    return false;
  }
  // The deterministic terms' states first; where even the base does not fit beside them, they
  // go one at a time: the second sinusoid, the ramp, the first sinusoid.
  hal::ModelSignalsRecord& sg = nm.signals;
  const auto note = [&dropped](const std::string& t) {
    dropped += (dropped.empty() ? "" : "; ") + t;
  };
  const std::string room = " of model_after not sent: the node's " +
                           std::to_string(node::kNodeProcessStates) +
                           " states do not hold it beside the stochastic terms";
  if (nm.has_signals && !base_runs(rec, node::signal_states(sg)) && sg.sin_a[1] > 0.0F) {
    note("second sinusoid (" + num_text(static_cast<double>(sg.sin_f0_hz[1])) + " Hz)" + room);
    sg.sin_a[1] = 0.0F;
    sg.sin_f0_hz[1] = 0.0F;
  }
  if (nm.has_signals && !base_runs(rec, node::signal_states(sg)) &&
      (sg.ramp_r > 0.0F || sg.ramp_r < 0.0F)) {
    note("ramp" + room);
    sg.ramp_r = 0.0F;
  }
  if (nm.has_signals && !base_runs(rec, node::signal_states(sg)) && sg.sin_a[0] > 0.0F) {
    note("sinusoid (" + num_text(static_cast<double>(sg.sin_f0_hz[0])) + " Hz)" + room);
    sg.sin_a[0] = 0.0F;
    sg.sin_f0_hz[0] = 0.0F;
  }
  nm.has_signals = node::signal_states(sg) > 0;
  ModelParams check{};
  if (nm.has_signals && !node::model_signals_valid(sg, check)) {
    note("ramp/sinusoids of model_after not sent: out of the node's ranges");
    nm.has_signals = false;
  }
  if (!nm.has_signals) {
    sg = hal::ModelSignalsRecord{};
    sg.channel = rec.channel;
  }
  if (!fit_to_node(json, root, n, nm.has_signals ? node::signal_states(sg) : 0U, rec, dropped,
                   err)) {
    return false;
  }
  err.clear();
  out = nm;
  return true;
}

}  // namespace

bool model_from_analysis_json(const std::string& json, const std::string& channel_name,
                              std::size_t channel_index, NodeModel& out, std::string& dropped,
                              std::string& err) {
  return read_node_model(json, channel_name, channel_index, true, out, dropped, err);
}

bool model_from_analysis_json(const std::string& json, const std::string& channel_name,
                              std::size_t channel_index, hal::ModelRecord& out,
                              std::string& dropped, std::string& err) {
  NodeModel nm{};
  if (!read_node_model(json, channel_name, channel_index, false, nm, dropped, err)) {
    return false;
  }
  out = nm.rec;
  return true;
}

}  // namespace imu::sim

// Selection benchmark of `imu-sim analyze`: random synthetic records, each holding a random subset
// of the terms the analysis can name, and the confusion matrix of named against true terms; then
// what the report says about the non-stationary records (a warm-up transient, a noise-level
// change, a bias step). Prints tables; not a pass/fail test (the targets are read off its output).
//
//   bench_selection [RECORDS [THREADS [FIRST_SEED [MAX_SAMPLES [RECORDS_CSV]]]]]
//   (500 2 7100001 4194304; RECORDS_CSV: one line per record, its truth and what was named: the
//   transient's A, tau_w and event_z, the noise change's t_c and g, the step's time, size and
//   event_z, and per non-stationary kind its outcome, "+note" when a note gives a time in it;
//   last, the white noise N: truth, model_after's and its 95 % interval)
//   With BENCH_SELECTION_TEXT set in the environment each report's text goes to stderr: one
//   record's diagnosis is `BENCH_SELECTION_TEXT=1 bench_selection 1 1 SEED`. With
//   BENCH_SELECTION_NONSTATIONARY=1 every record is non-stationary: one that drew none of the
//   three kinds gets one of them (equally likely) drawn after everything else.
//
// Generator (seeds FIRST_SEED.., which no unit test uses): a gyroscope or an accelerometer scale
// (white N over two decades around 5e-4 rad/s/sqrt(Hz) or 3e-3 m/s^2/sqrt(Hz)), rate 50 to
// 1000 Hz and length 1 to 24 h (log-uniform; the record is cut to MAX_SAMPLES, which the table
// says; 2^22 is what analyze holds at full rate), the first-order base (white N and one GM: B
// over two decades around 0.3 N, its ADEV peak over two decades below T/40), and each term with
// probability 0.3, every parameter drawn log-uniform over two decades:
//   quantization Q (sqrt(3) Q / Ts against the white ADEV N / sqrt(Ts) at Ts: 0.1 to 10 x),
//   rate random walk K (meets the white noise at tau from T/1000 to T/10),
//   ramp R (R tau / sqrt 2 meets B at tau from T/1000 to T/10),
//   sinusoid (f from 5 / T to fs / 4; A from 0.1 to 10 x the white ADEV at its bump),
//   bias instability B_f (0.1 to 10 x the base B),
//   narrowband oscillation (f0 from 1 Hz to fs / 5, half-power width 1 % to 30 % of f0, sigma
//     0.03 to 3 x the white std per sample),
//   bias step (1 to 100 GM sigmas, at 10 % to 90 % of the record),
//   outliers (10 to 100 spikes of 8 to 15 white stds).
// Then, drawn after all of those (a seed keeps its terms), two non-stationary kinds that are no
// term of the analysis, each with probability 0.15, added to the synthesized samples:
//   warm-up transient A e^(-t / tau_w) (|A| 3 to 100 GM sigmas, either sign; tau_w T/200 to
//     T/10),
//   noise-level change (from t_c, uniform in [0.2 T, 0.8 T], independent white noise that
//     multiplies the white std per sample by g, 1.5 to 4: added std white_sd sqrt(g^2 - 1)).
// A term "dominates" when its ADEV is at least 2 x that of all the other true terms together over
// an octave of taus inside [Ts, T/10] (a step's AVAR: d^2 tau / (3 (T - 2 tau)); outliers,
// which never move the ADEV that much: spikes of at least 8 x the std per sample of white noise,
// quantization and oscillation together, see mark_dominant); those
// are the records where it should be named. The targets (see the README): named in at least
// 90 % of the records where it dominates, in at most 1 % of the records without it. The records
// with a transient or a noise change are left out of the "without it" columns (a name there may
// be the analysis's reading of the non-stationarity); the last table counts those names.
// Non-stationary records, per kind (transient, noise change, step): "named" (an effect of the
// kind's type at the event: bias_step for a step; the analysis has no effect type for the other
// two), else "unexplained with a time range" (an unexplained entry whose time range meets the
// event: the transient's [0, 3 tau_w], the change's or the step's time +- 5 % of T; the
// Report's UnexplainedRun carries tau ranges only, so this column counts only once it gains
// t_min_s / t_max_s), else "unexplained, tau only", else "nothing". A further column counts the
// reports with a note that gives a time ("t = ... s") inside the event.
// Cost: about 1.5 s of analysis per 10^6 samples per record, THREADS records at a time.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "imu/analyze/analyze.hpp"
#include "imu/analyze/synth.hpp"
#include "imu/error_model.hpp"

namespace {

namespace ia = imu::analyze;

enum Term : std::size_t {
  kQuant,
  kRrw,
  kRamp,
  kSine,
  kFlicker,
  kOsc,
  kStep,
  kOutliers,
  kTerms
};
constexpr const char* kName[kTerms] = {"quantization",    "rate_random_walk", "ramp",
                                       "sinusoid",        "bias_instability", "oscillation",
                                       "bias_step",       "outliers"};

// The non-stationary kinds: the bias step (a term above) and two applied to the synthesized
// samples here.
enum Kind : std::size_t { kTransient, kNoiseChange, kStepKind, kKinds };
constexpr const char* kKindName[kKinds] = {"transient", "noise_change", "bias_step"};
// The effect type that names each kind (nullptr: the analysis has none; see Effect::type).
constexpr const char* kKindEffect[kKinds] = {nullptr, nullptr, "bias_step"};
constexpr double kKindProbability = 0.15;  // transient, noise change: each
constexpr double kTimeTolerance = 0.05;    // of the record: a reported time "at" a change or step

// What the report says about one non-stationary kind of a record (the first that holds).
enum Fate : std::size_t { kNamed, kUnexplainedTimed, kUnexplainedTau, kNothing, kFates };
constexpr const char* kFateName[kFates] = {"named", "unexplained_time", "unexplained_tau",
                                           "nothing"};

struct Record {
  ia::SynthSpec spec;
  bool gyro = false;
  bool has[kTerms] = {};
  bool dominant[kTerms] = {};
  double truth[kTerms] = {};  // the main parameter of each present term
  double t_rec = 0.0;         // the record's length [s]
  bool has_kind[kKinds] = {};
  double transient_amp = 0.0;    // A of A e^(-t / tau_w)
  double transient_tau_s = 0.0;  // tau_w
  double noise_time_s = 0.0;     // t_c: the added white noise starts at the first sample after it
  double noise_gain = 1.0;       // g: the white std per sample after t_c over that before
  double oracle_z[kKinds] = {};  // the transient's and the step's event_z (0: none)
  double noise_add_sd = 0.0;     // the added noise's std per sample
  std::uint64_t noise_seed = 0;  // the added noise's stream
};

struct Outcome {
  bool ok = false;
  bool named[kTerms] = {};
  double estimate[kTerms] = {};
  double lo95[kTerms] = {};  // the main parameter's reported 95 % interval (|.|, sorted)
  double hi95[kTerms] = {};
  bool has95[kTerms] = {};
  double n_est = 0.0;        // the white noise N: model_after's, and its interval
  double n_lo95 = 0.0;
  double n_hi95 = 0.0;
  bool second_gm = false;
  bool walk_stand_in = false;  // the first-order GM slower than the record resolves, no walk
  bool output_filter = false;  // the generator's white noise is never filtered: always false
  bool unexplained = false;
  bool consistent = true;
  Fate fate[kKinds] = {kNothing, kNothing, kNothing};  // of each kind the record holds
  bool note_time[kKinds] = {};  // a note gives a time inside the kind's event
  bool any_time_range = false;  // an unexplained entry with a time range, anywhere
  int step_time_in = -1;  // the step named at the event: its time's interval holds the truth
  double cpu_s = 0.0;
};

double log_uniform(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
  return std::exp(u(rng));
}

// AVAR of term t of the record at tau (0 if absent).
double term_avar(const Record& r, Term t, double tau) {
  const ia::SynthSpec& s = r.spec;
  switch (t) {
    case kQuant: return s.q > 0.0 ? imu::avar_quantization(s.q, tau) : 0.0;
    case kRrw: return s.k > 0.0 ? imu::avar_rrw(s.k, tau) : 0.0;
    case kRamp: return s.ramp_r > 0.0 ? imu::avar_ramp(s.ramp_r, tau) : 0.0;
    case kSine: return s.sin_a > 0.0 ? imu::avar_sinusoid(s.sin_a, s.sin_f_hz, tau) : 0.0;
    case kFlicker: return s.flicker_b > 0.0 ? imu::avar_flicker_ideal(s.flicker_b) : 0.0;
    case kOsc:
      return s.osc_sigma > 0.0
                 ? imu::avar_oscillation(s.osc_sigma, s.osc_f0_hz, s.osc_beta_per_s, tau)
                 : 0.0;
    default: return 0.0;
  }
}

double base_avar(const ia::SynthSpec& s, double tau) {
  const double tb = s.tp_s / imu::kGmPeakTauFactor;
  const double sb = s.b * s.b / (imu::kGmPeakAdevFactor * imu::kGmPeakAdevFactor * tb);
  return imu::avar_white(s.n, tau) + imu::avar_gauss_markov(sb, tb, tau);
}

void draw_step(std::mt19937_64& rng, Record& r, double gm_sigma) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  ia::SynthSpec& s = r.spec;
  s.step_size = gm_sigma * log_uniform(rng, 1.0, 100.0) * (u01(rng) < 0.5 ? -1.0 : 1.0);
  s.step_time_s = r.t_rec * (0.1 + 0.8 * u01(rng));
  r.truth[kStep] = std::fabs(s.step_size);
}

void draw_transient(std::mt19937_64& rng, Record& r, double gm_sigma) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  r.transient_amp = gm_sigma * log_uniform(rng, 3.0, 100.0) * (u01(rng) < 0.5 ? -1.0 : 1.0);
  r.transient_tau_s = log_uniform(rng, r.t_rec / 200.0, r.t_rec / 10.0);
}

void draw_noise_change(std::mt19937_64& rng, Record& r, double white_sd) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  r.noise_time_s = r.t_rec * (0.2 + 0.6 * u01(rng));
  r.noise_gain = log_uniform(rng, 1.5, 4.0);
  r.noise_add_sd = white_sd * std::sqrt(r.noise_gain * r.noise_gain - 1.0);
}

// The two kinds that are no term of the analysis, drawn after every term (so that a seed keeps
// its terms); with BENCH_SELECTION_NONSTATIONARY set, a record left without any of the three
// kinds gets one.
void draw_nonstationary(std::mt19937_64& rng, Record& r, double gm_sigma, double white_sd) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  r.has_kind[kTransient] = u01(rng) < kKindProbability;
  if (r.has_kind[kTransient]) {
    draw_transient(rng, r, gm_sigma);
  }
  r.has_kind[kNoiseChange] = u01(rng) < kKindProbability;
  if (r.has_kind[kNoiseChange]) {
    draw_noise_change(rng, r, white_sd);
  }
  r.noise_seed = rng();
  const char* force = std::getenv("BENCH_SELECTION_NONSTATIONARY");
  const bool forced = force != nullptr && *force != '\0' && std::string(force) != "0";
  if (forced && !r.has_kind[kTransient] && !r.has_kind[kNoiseChange] && !r.has[kStep]) {
    const double u = u01(rng);
    if (u < 1.0 / 3.0) {
      r.has_kind[kTransient] = true;
      draw_transient(rng, r, gm_sigma);
    } else if (u < 2.0 / 3.0) {
      r.has_kind[kNoiseChange] = true;
      draw_noise_change(rng, r, white_sd);
    } else {
      r.has[kStep] = true;
      draw_step(rng, r, gm_sigma);
    }
  }
  r.has_kind[kStepKind] = r.has[kStep];
}

// The terms other than the base, each with probability 0.3.
void draw_terms(std::mt19937_64& rng, Record& r, double gm_sigma, double white_sd) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  ia::SynthSpec& s = r.spec;
  const double ts = 1.0 / s.fs_hz;
  const double t_rec = r.t_rec;
  for (std::size_t t = 0; t < kTerms; ++t) {
    r.has[t] = u01(rng) < 0.3;
  }
  if (r.has[kQuant]) {
    s.q = s.n * std::sqrt(ts) / std::sqrt(3.0) * log_uniform(rng, 0.1, 10.0);
    r.truth[kQuant] = s.q;
  }
  if (r.has[kRrw]) {
    s.k = std::sqrt(3.0) * s.n / log_uniform(rng, t_rec / 1000.0, t_rec / 10.0);
    r.truth[kRrw] = s.k;
  }
  if (r.has[kRamp]) {
    s.ramp_r = std::sqrt(2.0) * s.b / log_uniform(rng, t_rec / 1000.0, t_rec / 10.0);
    r.truth[kRamp] = s.ramp_r;
  }
  if (r.has[kSine]) {
    s.sin_f_hz = log_uniform(rng, 5.0 / t_rec, s.fs_hz / 4.0);
    const double tau_bump = 0.371 / s.sin_f_hz;
    s.sin_a = std::sqrt(base_avar(s, tau_bump)) * log_uniform(rng, 0.1, 10.0);
    r.truth[kSine] = s.sin_a;
  }
  if (r.has[kFlicker]) {
    s.flicker_b = s.b * log_uniform(rng, 0.1, 10.0);
    r.truth[kFlicker] = s.flicker_b;
  }
  if (r.has[kOsc]) {
    s.osc_f0_hz = log_uniform(rng, 1.0, s.fs_hz / 5.0);
    s.osc_beta_per_s = 3.14159265358979323846 * s.osc_f0_hz * log_uniform(rng, 0.01, 0.3);
    s.osc_sigma = white_sd * log_uniform(rng, 0.03, 3.0);
    r.truth[kOsc] = s.osc_sigma;
  }
  if (r.has[kStep]) {
    draw_step(rng, r, gm_sigma);
  }
  if (r.has[kOutliers]) {
    s.n_outliers = static_cast<std::size_t>(std::round(log_uniform(rng, 10.0, 100.0)));
    s.outlier_size = white_sd * (8.0 + 7.0 * u01(rng));
    r.truth[kOutliers] = static_cast<double>(s.n_outliers);
  }
}

// AVAR of a bias step of size d inside a record of length T, at tau no longer than the step's
// distance to either end: d^2 tau / (3 (T - 2 tau)) (of the T - 2 tau overlapping pairs of
// windows, those within tau of the step differ by d (1 - |offset| / tau)).
double step_avar(const Record& r, double tau) {
  const double d = r.spec.step_size;
  return r.has[kStep] ? d * d * tau / (3.0 * (r.t_rec - 2.0 * tau)) : 0.0;
}

// Dominance over an octave inside [Ts, T/10] (taus at 8 per octave): the term's AVAR at least
// 4x that of all the others (the base included) at every tau of the octave. The step's AVAR
// is step_avar (its time is in [0.1 T, 0.9 T], so every tau up to T/10 qualifies).
void mark_dominant(Record& r) {
  const ia::SynthSpec& s = r.spec;
  const double ts = 1.0 / s.fs_hz;
  const auto avar_of = [&r](std::size_t t, double tau) {
    return t == kStep ? step_avar(r, tau) : term_avar(r, static_cast<Term>(t), tau);
  };
  for (std::size_t t = 0; t <= kStep; ++t) {
    if (!r.has[t]) {
      continue;
    }
    double run_from = 0.0;
    const int n_tau = static_cast<int>(8.0 * std::log2(r.t_rec / 10.0 / ts));
    for (int i = 0; i <= n_tau; ++i) {
      const double tau = ts * std::pow(2.0, 0.125 * i);
      double rest = base_avar(s, tau);
      for (std::size_t o = 0; o <= kStep; ++o) {
        rest += o == t ? 0.0 : avar_of(o, tau);
      }
      const bool dom = avar_of(t, tau) >= 4.0 * rest;
      run_from = dom ? (run_from > 0.0 ? run_from : tau) : 0.0;
      if (run_from > 0.0 && tau >= 2.0 * run_from * 0.999) {
        r.dominant[t] = true;
      }
    }
  }
  // A spike adds k s^2 / n to the AVAR at Ts (k spikes of size s in n samples): far below the
  // white noise's, so the ADEV rule above never holds for it. Outliers "dominate" where each
  // stands out of its own sample's noise: the spike at least 8 x the std per sample of the
  // terms that move single samples (white, at its louder level where it changes; quantization,
  // 2 Q^2 / Ts^2; the oscillation, sigma^2). The gate's threshold is about 6 such stds
  // (alpha / n at 10^6 samples), so a spike of 8 is found on most draws.
  const double white_sd = s.n * std::sqrt(s.fs_hz) * std::max(1.0, r.noise_gain);
  const double sample_sd = std::sqrt(white_sd * white_sd + 2.0 * s.q * s.q / (ts * ts) +
                                     s.osc_sigma * s.osc_sigma);
  r.dominant[kOutliers] = r.has[kOutliers] && s.outlier_size >= 8.0 * sample_sd;
}

// How far an event stands out of the record's stationary noise, at its known time: the
// difference of the means of two adjacent windows of tau has variance 2 AVAR(tau) under the
// stationary terms (the AVAR's definition), so an event that moves it by s(tau) has
// z(tau) = s / sqrt(2 AVAR(tau)); the largest over tau = Ts 2^(j/2). A step d at t0: s = d,
// tau up to min(t0, T - t0); a warm-up transient A e^(-t / tau_w) over [0, tau] against
// [tau, 2 tau]: s = A (tau_w / tau) (1 - e^(-tau / tau_w))^2, tau up to T / 2. A search that
// does not know the time needs more than a test at it (the step's profile likelihood asks
// about 4 sd of it), so below some 4-5 the event is no failure of the analysis to name.
double event_z(const Record& r, std::size_t kind) {
  const ia::SynthSpec& s = r.spec;
  const double ts = 1.0 / s.fs_hz;
  double tau_max = r.t_rec / 2.0;
  if (kind == kStepKind) {
    tau_max = std::min(s.step_time_s, r.t_rec - s.step_time_s);
  }
  double best = 0.0;
  const int n_tau = tau_max > ts ? static_cast<int>(2.0 * std::log2(tau_max / ts)) : -1;
  for (int j = 0; j <= n_tau; ++j) {
    const double tau = ts * std::pow(2.0, 0.5 * j);
    double avar = base_avar(s, tau);
    for (std::size_t t = 0; t < kStep; ++t) {
      avar += term_avar(r, static_cast<Term>(t), tau);
    }
    const double w = r.transient_tau_s;
    const double sig = kind == kStepKind
                           ? std::fabs(s.step_size)
                           : std::fabs(r.transient_amp) * (w / tau) *
                                 std::pow(1.0 - std::exp(-tau / w), 2.0);
    best = std::max(best, sig / std::sqrt(2.0 * avar));
  }
  return best;
}

Record draw(std::uint64_t seed, std::size_t max_samples) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Record r;
  ia::SynthSpec& s = r.spec;
  s.seed = seed;
  r.gyro = u01(rng) < 0.5;
  const double n0 = r.gyro ? 5e-4 : 3e-3;
  s.n = log_uniform(rng, n0 / 10.0, n0 * 10.0);
  s.fs_hz = std::round(log_uniform(rng, 50.0, 1000.0));
  const double hours = log_uniform(rng, 1.0, 24.0);
  s.samples = std::min<std::size_t>(static_cast<std::size_t>(hours * 3600.0 * s.fs_hz),
                                    max_samples);
  r.t_rec = static_cast<double>(s.samples) / s.fs_hz;
  s.offset = r.gyro ? 0.0 : 9.80665;
  s.b = s.n * log_uniform(rng, 0.03, 3.0);
  s.tp_s = log_uniform(rng, r.t_rec / 4000.0, r.t_rec / 40.0);
  const double gm_sigma = s.b / (imu::kGmPeakAdevFactor * std::sqrt(2.0));
  const double white_sd = s.n * std::sqrt(s.fs_hz);
  draw_terms(rng, r, gm_sigma, white_sd);
  draw_nonstationary(rng, r, gm_sigma, white_sd);
  mark_dominant(r);
  for (const std::size_t k : {kTransient, kStepKind}) {
    r.oracle_z[k] = r.has_kind[k] ? event_z(r, k) : 0.0;
  }
  return r;
}

// The transient and the noise change, added to the synthesized samples.
void apply_nonstationary(const Record& rec, std::vector<double>& y) {
  const double ts = 1.0 / rec.spec.fs_hz;
  if (rec.has_kind[kTransient]) {
    for (std::size_t i = 0; i < y.size(); ++i) {
      y[i] += rec.transient_amp * std::exp(-static_cast<double>(i) * ts / rec.transient_tau_s);
    }
  }
  if (rec.has_kind[kNoiseChange]) {
    std::mt19937_64 rng(rec.noise_seed);
    std::normal_distribution<double> noise(0.0, rec.noise_add_sd);
    for (auto i = static_cast<std::size_t>(std::ceil(rec.noise_time_s / ts)); i < y.size(); ++i) {
      y[i] += noise(rng);
    }
  }
}

// The span of kind k's event that a reported time must meet: the transient's [0, 3 tau_w], the
// change's or the step's time +- kTimeTolerance T.
void event_window(const Record& r, Kind k, double& t0, double& t1) {
  const double at = k == kTransient ? 0.0 : k == kNoiseChange ? r.noise_time_s : r.spec.step_time_s;
  t0 = k == kTransient ? 0.0 : at - kTimeTolerance * r.t_rec;
  t1 = k == kTransient ? 3.0 * r.transient_tau_s : at + kTimeTolerance * r.t_rec;
}

// An unexplained entry's time range, when the Report's UnexplainedRun has one (t_min_s,
// t_max_s); otherwise (the second overload) it has tau ranges only.
template <typename U>
auto time_range(const U& u, double& t0, double& t1, int /*preferred*/)
    -> decltype(u.t_min_s + u.t_max_s, bool()) {
  t0 = u.t_min_s;
  t1 = u.t_max_s;
  return std::isfinite(t0) && std::isfinite(t1) && t1 > t0;
}
template <typename U>
bool time_range(const U& /*u*/, double& /*t0*/, double& /*t1*/, long /*fallback*/) {
  return false;
}

// Whether the note gives a time ("t = X s") inside [t0, t1].
bool note_time_in(const std::string& note, double t0, double t1) {
  for (std::size_t at = note.find(" t = "); at != std::string::npos;
       at = note.find(" t = ", at + 1)) {
    const char* from = note.c_str() + at + 5;
    char* end = nullptr;
    const double t = std::strtod(from, &end);
    if (end != from && t >= t0 && t <= t1) {
      return true;
    }
  }
  return false;
}

// The fate of each non-stationary kind the record holds (see the header).
void classify_kinds(const Record& rec, const ia::Report& r, Outcome& out) {
  for (const auto& u : r.unexplained) {
    double a = 0.0;
    double b = 0.0;
    out.any_time_range = out.any_time_range || time_range(u, a, b, 0);
  }
  for (std::size_t k = 0; k < kKinds; ++k) {
    if (!rec.has_kind[k]) {
      continue;
    }
    double w0 = 0.0;
    double w1 = 0.0;
    event_window(rec, static_cast<Kind>(k), w0, w1);
    bool named = false;
    double nearest_s = w1 - w0;
    for (const auto& e : r.effects) {
      const bool at_event = kKindEffect[k] != nullptr && e.type == kKindEffect[k] &&
                            e.time_s >= w0 && e.time_s <= w1;
      named = named || at_event;
      const double t_true = 0.5 * (w0 + w1);
      if (at_event && k == kStepKind && std::fabs(e.time_s - t_true) <= nearest_s) {
        nearest_s = std::fabs(e.time_s - t_true);
        for (const auto& iv : e.ci95) {
          if (iv.name == "time_s") {
            out.step_time_in = iv.lo <= t_true && t_true <= iv.hi ? 1 : 0;
          }
        }
      }
    }
    bool timed = false;
    for (const auto& u : r.unexplained) {
      double a = 0.0;
      double b = 0.0;
      timed = timed || (time_range(u, a, b, 0) && b >= w0 && a <= w1);
    }
    out.fate[k] = named                    ? kNamed
                  : timed                  ? kUnexplainedTimed
                  : !r.unexplained.empty() ? kUnexplainedTau
                                           : kNothing;
    for (const auto& n : r.notes) {
      out.note_time[k] = out.note_time[k] || note_time_in(n, w0, w1);
    }
  }
}

void read_effects(const ia::Report& r, Outcome& out) {
  for (const auto& e : r.effects) {
    out.second_gm = out.second_gm || e.type == "gauss_markov";
    for (std::size_t t = 0; t < kTerms; ++t) {
      if (e.type != kName[t] || out.named[t]) {
        continue;
      }
      out.named[t] = true;
      switch (t) {
        case kQuant: out.estimate[t] = e.q; break;
        case kRrw: out.estimate[t] = e.k; break;
        case kRamp: out.estimate[t] = std::fabs(e.r); break;
        case kFlicker: out.estimate[t] = e.b; break;
        case kStep: out.estimate[t] = std::fabs(e.size); break;
        case kOutliers: out.estimate[t] = static_cast<double>(e.count); break;
        default: out.estimate[t] = e.amplitude; break;
      }
      if (!e.ci95.empty()) {  // the first interval is the main parameter's
        const double a = std::fabs(e.ci95.front().lo);
        const double b = std::fabs(e.ci95.front().hi);
        const bool straddles = e.ci95.front().lo < 0.0 && e.ci95.front().hi > 0.0;
        out.lo95[t] = straddles ? 0.0 : std::min(a, b);
        out.hi95[t] = std::max(a, b);
        out.has95[t] = true;
      }
    }
  }
}

Outcome analyse(const Record& rec) {
  Outcome out;
  std::vector<double> y = ia::synthesize(rec.spec);
  if (y.empty()) {
    return out;
  }
  apply_nonstationary(rec, y);
  ia::Options o;
  o.fs_hz = rec.spec.fs_hz;
  ia::Report r;
  std::string err;
  if (!ia::analyze(std::move(y), "x", o, r, err)) {
    std::fprintf(stderr, "seed %llu: %s\n", static_cast<unsigned long long>(rec.spec.seed),
                 err.c_str());
    return out;
  }
  out.ok = true;
  if (std::getenv("BENCH_SELECTION_TEXT") != nullptr) {
    const ia::SynthSpec& s = rec.spec;
    std::fprintf(stderr,
                 "== seed %llu\ntruth: N %.4g, GM peak ADEV %.4g at Tp %.4g s, Q %.4g, K %.4g, "
                 "R %.4g, sinusoid %.4g at %.4g Hz, B %.4g, oscillation %.4g at %.4g Hz (beta "
                 "%.4g /s), step %.4g at %.4g s\n%s\n",
                 static_cast<unsigned long long>(s.seed), s.n, s.b, s.tp_s, s.q, s.k, s.ramp_r,
                 s.sin_a, s.sin_f_hz, s.flicker_b, s.osc_sigma, s.osc_f0_hz, s.osc_beta_per_s,
                 s.step_size, s.step_time_s, ia::to_text(r).c_str());
  }
  out.cpu_s = r.cpu_seconds;
  out.unexplained = !r.unexplained.empty();
  std::string why;
  out.consistent = ia::report_consistent(r, why);
  out.output_filter = r.model_after.n_filter_s > 0.0;
  out.walk_stand_in = ia::gm_stands_in_for_walk(r);
  read_effects(r, out);
  out.n_est = r.model_after.n;
  for (const auto& iv : r.model_after_ci95) {
    if (iv.name == "n") {
      out.n_lo95 = iv.lo;
      out.n_hi95 = iv.hi;
    }
  }
  classify_kinds(rec, r, out);
  return out;
}

std::string pct(std::size_t a, std::size_t b) {
  if (b == 0) {
    return "-";
  }
  const double p = 100.0 * static_cast<double>(a) / static_cast<double>(b);
  return std::to_string(a) + "/" + std::to_string(b) + " (" +
         std::to_string(static_cast<int>(std::lround(p))) + " %)";
}

// A transient or a noise change: no term of the analysis, left out of the false-name columns.
bool beyond_terms(const Record& r) {
  return r.has_kind[kTransient] || r.has_kind[kNoiseChange];
}

void print_confusion(const std::vector<Record>& recs, const std::vector<Outcome>& outs) {
  std::printf("\n| term | records with it | it dominates | named where it dominates | "
              "named where present, not dominant | records without it (no transient, no noise "
              "change) | named without it (false) | parameter within 25 %% (named, present) | "
              "truth inside the 95 %% interval (named, present) |\n"
              "|---|---|---|---|---|---|---|---|---|\n");
  for (std::size_t t = 0; t < kTerms; ++t) {
    std::size_t with = 0;
    std::size_t dom = 0;
    std::size_t dom_named = 0;
    std::size_t weak_named = 0;
    std::size_t without = 0;
    std::size_t false_named = 0;
    std::size_t est = 0;
    std::size_t est_ok = 0;
    std::size_t cov = 0;
    std::size_t cov_in = 0;
    for (std::size_t i = 0; i < recs.size(); ++i) {
      const Outcome& o = outs[i];
      if (!o.ok) {
        continue;
      }
      const Record& r = recs[i];
      if (r.has[t]) {
        ++with;
        dom += r.dominant[t] ? 1U : 0U;
        dom_named += r.dominant[t] && o.named[t] ? 1U : 0U;
        weak_named += !r.dominant[t] && o.named[t] ? 1U : 0U;
        if (o.named[t]) {
          ++est;
          est_ok += std::fabs(o.estimate[t] / r.truth[t] - 1.0) <= 0.25 ? 1U : 0U;
          if (o.has95[t]) {
            ++cov;
            cov_in += r.truth[t] >= o.lo95[t] && r.truth[t] <= o.hi95[t] ? 1U : 0U;
          }
        }
      } else if (!beyond_terms(r)) {
        ++without;
        false_named += o.named[t] ? 1U : 0U;
      }
    }
    std::printf("| %s | %zu | %zu | %s | %s | %zu | %s | %s | %s |\n", kName[t], with, dom,
                pct(dom_named, dom).c_str(), pct(weak_named, with - dom).c_str(), without,
                pct(false_named, without).c_str(), pct(est_ok, est).c_str(),
                pct(cov_in, cov).c_str());
  }
  // Where a walk dominates and is not named, the model after may hold the first-order GM
  // slower than the record resolves in its place (ia::gm_stands_in_for_walk): the walk's
  // covariance over the record, not its name. Counted apart, beside records without a walk.
  std::size_t dom = 0;
  std::size_t dom_in = 0;
  std::size_t without = 0;
  std::size_t without_in = 0;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    if (!outs[i].ok) {
      continue;
    }
    if (recs[i].has[kRrw] && recs[i].dominant[kRrw]) {
      ++dom;
      dom_in += outs[i].walk_stand_in ? 1U : 0U;
    } else if (!recs[i].has[kRrw] && !beyond_terms(recs[i])) {
      ++without;
      without_in += outs[i].walk_stand_in ? 1U : 0U;
    }
  }
  std::printf("\nrate_random_walk not named, the first-order GM with Tb open above in its place: "
              "%s of the records where a walk dominates, %s of the records without a walk (no "
              "transient, no noise change)\n",
              pct(dom_in, dom).c_str(), pct(without_in, without).c_str());
}

// Per non-stationary kind: what the report said about it; then the terms named that the record
// does not hold (the non-stationarity read as a walk, a ramp, ...), against the stationary records.
constexpr double kClearZ = 5.0;  // an event this far out at its known time should not go unseen

std::string fmt_z(double z) {
  char b[32];
  std::snprintf(b, sizeof b, " (z %.1f)", z);
  return b;
}

void print_nonstationary(const std::vector<Record>& recs, const std::vector<Outcome>& outs) {
  std::printf("\n| kind | records | named | unexplained with a time range over it | unexplained, "
              "tau only | nothing | a note gives a time in it |\n|---|---|---|---|---|---|---|\n");
  for (std::size_t k = 0; k < kKinds; ++k) {
    std::size_t n = 0;
    std::size_t by_fate[kFates] = {};
    std::size_t note = 0;
    for (std::size_t i = 0; i < recs.size(); ++i) {
      if (outs[i].ok && recs[i].has_kind[k]) {
        ++n;
        ++by_fate[outs[i].fate[k]];
        note += outs[i].note_time[k] ? 1U : 0U;
      }
    }
    std::printf("| %s | %zu | %s | %s | %s | %s | %s |\n", kKindName[k], n,
                pct(by_fate[kNamed], n).c_str(), pct(by_fate[kUnexplainedTimed], n).c_str(),
                pct(by_fate[kUnexplainedTau], n).c_str(), pct(by_fate[kNothing], n).c_str(),
                pct(note, n).c_str());
  }
  // "nothing" against how far the event stands out at its known time (event_z)
  for (const std::size_t k : {kTransient, kStepKind}) {
    std::size_t faint = 0;
    std::string clear;
    for (std::size_t i = 0; i < recs.size(); ++i) {
      if (outs[i].ok && recs[i].has_kind[k] && outs[i].fate[k] == kNothing) {
        const double z = recs[i].oracle_z[k];
        faint += z < kClearZ ? 1U : 0U;
        clear += z < kClearZ ? "" : " " + std::to_string(recs[i].spec.seed) + fmt_z(z);
      }
    }
    std::printf("%s with nothing: %zu below z = %.0f at its known time, the others:%s\n",
                kKindName[k], faint, kClearZ, clear.empty() ? " none" : clear.c_str());
  }
  std::printf("\nterms named that the record does not hold:\n\n| records with | records |");
  for (const char* name : kName) {
    std::printf(" %s |", name);
  }
  std::printf(" second GM | any of these |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (std::size_t k = 0; k <= kKinds; ++k) {  // kKinds: the records holding none of the kinds
    std::size_t n = 0;
    std::size_t wrong[kTerms + 1] = {};
    std::size_t any = 0;
    for (std::size_t i = 0; i < recs.size(); ++i) {
      const Record& r = recs[i];
      const bool none = !r.has_kind[kTransient] && !r.has_kind[kNoiseChange] && !r.has[kStep];
      if (!outs[i].ok || (k < kKinds ? !r.has_kind[k] : !none)) {
        continue;
      }
      ++n;
      bool some = outs[i].second_gm;
      wrong[kTerms] += outs[i].second_gm ? 1U : 0U;
      for (std::size_t t = 0; t < kTerms; ++t) {
        const bool w = outs[i].named[t] && !r.has[t];
        wrong[t] += w ? 1U : 0U;
        some = some || w;
      }
      any += some ? 1U : 0U;
    }
    std::printf("| %s | %zu |", k < kKinds ? kKindName[k] : "none of them", n);
    for (const std::size_t w : wrong) {
      std::printf(" %s |", pct(w, n).c_str());
    }
    std::printf(" %s |\n", pct(any, n).c_str());
  }
  // A time range on a record that holds no non-stationary kind is a false finding.
  std::size_t stationary = 0;
  std::size_t timed = 0;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const Record& r = recs[i];
    if (outs[i].ok && !r.has_kind[kTransient] && !r.has_kind[kNoiseChange] && !r.has[kStep]) {
      ++stationary;
      timed += outs[i].any_time_range ? 1U : 0U;
    }
  }
  std::printf("\nrecords with none of the kinds that get an unexplained time range: %s of %zu\n",
              pct(timed, stationary).c_str(), stationary);
}

bool write_csv(const char* path, const std::vector<Record>& recs,
               const std::vector<Outcome>& outs) {
  FILE* f = std::fopen(path, "w");
  if (f == nullptr) {
    std::fprintf(stderr, "cannot write %s\n", path);
    return false;
  }
  std::fprintf(f, "seed,fs_hz,samples,gyro,true,dominant,named,second_gm,output_filter,"
                  "unexplained,transient,noise_change,step,outcome,estimates,n\n");
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const Record& r = recs[i];
    std::string has;
    std::string dom;
    std::string named;
    std::string outcome;
    for (std::size_t t = 0; t < kTerms; ++t) {
      has += r.has[t] ? std::string(kName[t]) + " " : "";
      dom += r.dominant[t] ? std::string(kName[t]) + " " : "";
      named += outs[i].named[t] ? std::string(kName[t]) + " " : "";
    }
    for (std::size_t k = 0; k < kKinds; ++k) {
      if (r.has_kind[k] && outs[i].ok) {
        outcome += std::string(kKindName[k]) + ":" + kFateName[outs[i].fate[k]] +
                   (outs[i].note_time[k] ? "+note " : " ");
      }
    }
    char transient[64] = "";
    char change[64] = "";
    char step[64] = "";
    if (r.has_kind[kTransient]) {  // A [unit] and tau_w [s]
      std::snprintf(transient, sizeof transient, "%.4g %.4g z %.3g", r.transient_amp,
                    r.transient_tau_s, r.oracle_z[kTransient]);
    }
    if (r.has_kind[kNoiseChange]) {  // t_c [s] and g
      std::snprintf(change, sizeof change, "%.6g %.3g", r.noise_time_s, r.noise_gain);
    }
    if (r.has[kStep]) {  // its time [s] and size [unit]
      std::snprintf(step, sizeof step, "%.6g %.4g z %.3g", r.spec.step_time_s, r.spec.step_size,
                    r.oracle_z[kStepKind]);
    }
    std::string estimates;  // per named, present term: truth estimate [lo95 hi95]
    for (std::size_t t = 0; t < kTerms; ++t) {
      if (r.has[t] && outs[i].named[t]) {
        char one[160];
        std::snprintf(one, sizeof one, "%s %.4g %.4g [%.4g %.4g] ", kName[t], r.truth[t],
                      outs[i].estimate[t], outs[i].lo95[t], outs[i].hi95[t]);
        estimates += one;
      }
    }
    std::fprintf(f, "%llu,%g,%zu,%d,%s,%s,%s,%d,%d,%d,%s,%s,%s,%s,%s,%.5g %.5g [%.5g %.5g]\n",
                 static_cast<unsigned long long>(r.spec.seed), r.spec.fs_hz, r.spec.samples,
                 r.gyro ? 1 : 0, has.c_str(), dom.c_str(), named.c_str(),
                 outs[i].second_gm ? 1 : 0, outs[i].output_filter ? 1 : 0,
                 outs[i].unexplained ? 1 : 0, transient, change, step, outcome.c_str(),
                 estimates.c_str(), r.spec.n, outs[i].n_est, outs[i].n_lo95, outs[i].n_hi95);
  }
  return std::fclose(f) == 0;
}

void print_summary(const std::vector<Record>& recs, const std::vector<Outcome>& outs) {
  std::size_t ok = 0;
  std::size_t inconsistent = 0;
  std::size_t second_gm = 0;
  std::size_t output_filter = 0;
  std::size_t unexplained = 0;
  for (const Outcome& o : outs) {
    if (!o.ok) {
      continue;
    }
    ++ok;
    inconsistent += o.consistent ? 0U : 1U;
    second_gm += o.second_gm ? 1U : 0U;
    output_filter += o.output_filter ? 1U : 0U;
    unexplained += o.unexplained ? 1U : 0U;
  }
  std::size_t n_cov = 0;
  std::size_t n_in = 0;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    if (outs[i].ok && outs[i].n_hi95 > 0.0) {
      ++n_cov;
      n_in += recs[i].spec.n >= outs[i].n_lo95 && recs[i].spec.n <= outs[i].n_hi95 ? 1U : 0U;
    }
  }
  std::printf("\nwhite noise N inside its 95 %% interval: %zu of %zu\n", n_in, n_cov);
  std::size_t t_cov = 0;
  std::size_t t_in = 0;
  for (const Outcome& o : outs) {
    t_cov += o.ok && o.step_time_in >= 0 ? 1U : 0U;
    t_in += o.ok && o.step_time_in > 0 ? 1U : 0U;
  }
  std::printf("bias step time inside its 95 %% interval (the step named at the event): "
              "%zu of %zu\n", t_in, t_cov);
  std::printf("\nreports naming a second GM (the truth has one GM): %zu of %zu\n", second_gm, ok);
  std::printf("reports with an output filter on the white noise (the truth has none): %zu of %zu\n",
              output_filter, ok);
  std::printf("reports with an unexplained tau run: %zu of %zu\n", unexplained, ok);
  std::printf("reports whose effects and model disagree (report_consistent): %zu of %zu\n",
              inconsistent, ok);
}

// Analyses every record, `threads` at a time; returns the wall time [s].
double analyse_all(const std::vector<Record>& recs, unsigned threads, std::vector<Outcome>& outs) {
  const std::size_t n_rec = recs.size();
  outs.assign(n_rec, Outcome{});
  std::atomic<std::size_t> next{0};
  std::mutex print_mu;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::thread> pool;
  for (unsigned w = 0; w < std::max(1U, threads); ++w) {
    pool.emplace_back([&] {
      for (std::size_t i = next++; i < n_rec; i = next++) {
        outs[i] = analyse(recs[i]);
        if ((i + 1) % 50 == 0) {
          const std::lock_guard<std::mutex> lock(print_mu);
          std::fprintf(stderr, "%zu / %zu records\n", i + 1, n_rec);
        }
      }
    });
  }
  for (auto& t : pool) {
    t.join();
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n_rec = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 500;
  const unsigned threads = argc > 2 ? static_cast<unsigned>(std::strtoul(argv[2], nullptr, 10)) : 2U;
  const std::uint64_t first = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 7100001ULL;
  const std::size_t max_samples =
      argc > 4 ? std::strtoull(argv[4], nullptr, 10) : (std::size_t{1} << 22);
  std::vector<Record> recs;
  recs.reserve(n_rec);
  for (std::size_t i = 0; i < n_rec; ++i) {
    recs.push_back(draw(first + i, max_samples));
  }
  std::vector<Outcome> outs;
  const double wall_s = analyse_all(recs, threads, outs);
  std::size_t ok = 0;
  double samples = 0.0;
  double cpu = 0.0;
  for (std::size_t i = 0; i < n_rec; ++i) {
    if (outs[i].ok) {
      ++ok;
      samples += static_cast<double>(recs[i].spec.samples);
      cpu += outs[i].cpu_s;
    }
  }
  std::printf("records: %zu (seeds %llu..%llu), analysed %zu, at most %zu samples each; "
              "wall %.0f s on %u threads; analysis CPU %.2f s per 10^6 samples\n",
              n_rec, static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + n_rec - 1), ok, max_samples, wall_s,
              threads, 1e6 * cpu / std::max(samples, 1.0));
  print_confusion(recs, outs);
  print_nonstationary(recs, outs);
  print_summary(recs, outs);
  if (argc > 5 && !write_csv(argv[5], recs, outs)) {
    return 1;
  }
  return 0;
}

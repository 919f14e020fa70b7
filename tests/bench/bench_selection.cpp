// Selection benchmark of `imu-sim analyze`: random synthetic records, each holding a random subset
// of the terms the analysis can name, and the confusion matrix of named against true terms.
// Prints a table; not a pass/fail test (the targets are read off its output).
//
//   bench_selection [RECORDS [THREADS [FIRST_SEED [MAX_SAMPLES [RECORDS_CSV]]]]]
//   (500 2 7100001 4194304; RECORDS_CSV: one line per record, its truth and what was named)
//   With BENCH_SELECTION_TEXT set in the environment each report's text goes to stderr: one
//   record's diagnosis is `BENCH_SELECTION_TEXT=1 bench_selection 1 1 SEED`.
//
// Generator (seeds FIRST_SEED.., which no unit test uses): a gyroscope or an accelerometer scale
// (white N over two decades around 5e-4 rad/s/sqrt(Hz) or 3e-3 m/s^2/sqrt(Hz)), rate 50 to
// 1000 Hz and length 1 to 24 h (log-uniform; the record is cut to MAX_SAMPLES, which the table
// says; 2^22 is what analyze holds at full rate), the first-order base (white N and one GM: B over two decades around 0.3 N, its ADEV
// peak over two decades below T/40), and each term with probability 0.3, every parameter drawn
// log-uniform over two decades:
//   quantization Q (sqrt(3) Q / Ts against the white ADEV N / sqrt(Ts) at Ts: 0.1 to 10 x),
//   rate random walk K (meets the white noise at tau from T/1000 to T/10),
//   ramp R (R tau / sqrt 2 meets B at tau from T/1000 to T/10),
//   sinusoid (f from 20 / T to fs / 4; A from 0.1 to 10 x the white ADEV at its bump),
//   bias instability B_f (0.1 to 10 x the base B),
//   narrowband oscillation (f0 from 1 Hz to fs / 5, half-power width 1 % to 30 % of f0, sigma
//     0.03 to 3 x the white std per sample),
//   bias step (1 to 100 GM sigmas, at 10 % to 90 % of the record),
//   outliers (10 to 100 spikes of 8 to 15 white stds).
// A term "dominates" when its ADEV is at least 2 x that of all the other true terms together over
// an octave of taus inside [Ts, T/10] (steps: at least 5 GM sigmas; outliers: always); those
// are the records where it should be named. The targets (see the README): named in at least
// 90 % of the records where it dominates, in at most 1 % of the records without it.
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

struct Record {
  ia::SynthSpec spec;
  bool gyro = false;
  bool has[kTerms] = {};
  bool dominant[kTerms] = {};
  double truth[kTerms] = {};  // the main parameter of each present term
};

struct Outcome {
  bool ok = false;
  bool named[kTerms] = {};
  double estimate[kTerms] = {};
  double lo95[kTerms] = {};  // the main parameter's reported 95 % interval (|.|, sorted)
  double hi95[kTerms] = {};
  bool has95[kTerms] = {};
  double n_lo95 = 0.0;       // the white noise N's
  double n_hi95 = 0.0;
  bool second_gm = false;
  bool output_filter = false;  // the generator's white noise is never filtered: always false
  bool unexplained = false;
  bool consistent = true;
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
  const double ts = 1.0 / s.fs_hz;
  const double t_rec = static_cast<double>(s.samples) * ts;
  s.offset = r.gyro ? 0.0 : 9.80665;
  s.b = s.n * log_uniform(rng, 0.03, 3.0);
  s.tp_s = log_uniform(rng, t_rec / 4000.0, t_rec / 40.0);
  const double gm_sigma = s.b / (imu::kGmPeakAdevFactor * std::sqrt(2.0));
  const double white_sd = s.n * std::sqrt(s.fs_hz);
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
    s.sin_f_hz = log_uniform(rng, 20.0 / t_rec, s.fs_hz / 4.0);
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
    s.step_size = gm_sigma * log_uniform(rng, 1.0, 100.0) * (u01(rng) < 0.5 ? -1.0 : 1.0);
    s.step_time_s = t_rec * (0.1 + 0.8 * u01(rng));
    r.truth[kStep] = std::fabs(s.step_size);
  }
  if (r.has[kOutliers]) {
    s.n_outliers = static_cast<std::size_t>(std::round(log_uniform(rng, 10.0, 100.0)));
    s.outlier_size = white_sd * (8.0 + 7.0 * u01(rng));
    r.truth[kOutliers] = static_cast<double>(s.n_outliers);
  }
  // Dominance over an octave inside [Ts, T/10] (taus at 8 per octave).
  for (std::size_t t = 0; t < kStep; ++t) {
    if (!r.has[t]) {
      continue;
    }
    double run_from = 0.0;
    const int n_tau = static_cast<int>(8.0 * std::log2(t_rec / 10.0 / ts));
    for (int i = 0; i <= n_tau; ++i) {
      const double tau = ts * std::pow(2.0, 0.125 * i);
      double rest = base_avar(s, tau);
      for (std::size_t o = 0; o < kStep; ++o) {
        rest += o == t ? 0.0 : term_avar(r, static_cast<Term>(o), tau);
      }
      const bool dom = term_avar(r, static_cast<Term>(t), tau) >= 4.0 * rest;
      run_from = dom ? (run_from > 0.0 ? run_from : tau) : 0.0;
      if (run_from > 0.0 && tau >= 2.0 * run_from * 0.999) {
        r.dominant[t] = true;
      }
    }
  }
  r.dominant[kStep] = r.has[kStep] && std::fabs(s.step_size) >= 5.0 * gm_sigma;
  r.dominant[kOutliers] = r.has[kOutliers];
  return r;
}

Outcome analyse(const Record& rec) {
  Outcome out;
  std::vector<double> y = ia::synthesize(rec.spec);
  if (y.empty()) {
    return out;
  }
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
    std::fprintf(stderr, "== seed %llu\n%s\n", static_cast<unsigned long long>(rec.spec.seed),
                 ia::to_text(r).c_str());
  }
  out.cpu_s = r.cpu_seconds;
  out.unexplained = !r.unexplained.empty();
  std::string why;
  out.consistent = ia::report_consistent(r, why);
  out.output_filter = r.model_after.n_filter_s > 0.0;
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
  for (const auto& iv : r.model_after_ci95) {
    if (iv.name == "n") {
      out.n_lo95 = iv.lo;
      out.n_hi95 = iv.hi;
    }
  }
  return out;
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
  std::vector<Outcome> outs(n_rec);
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
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::size_t ok = 0;
  std::size_t inconsistent = 0;
  std::size_t second_gm = 0;
  std::size_t output_filter = 0;
  std::size_t unexplained = 0;
  double samples = 0.0;
  double cpu = 0.0;
  for (std::size_t i = 0; i < n_rec; ++i) {
    if (!outs[i].ok) {
      continue;
    }
    ++ok;
    inconsistent += outs[i].consistent ? 0U : 1U;
    second_gm += outs[i].second_gm ? 1U : 0U;
    output_filter += outs[i].output_filter ? 1U : 0U;
    unexplained += outs[i].unexplained ? 1U : 0U;
    samples += static_cast<double>(recs[i].spec.samples);
    cpu += outs[i].cpu_s;
  }
  std::printf("records: %zu (seeds %llu..%llu), analysed %zu, at most %zu samples each; "
              "wall %.0f s on %u threads; analysis CPU %.2f s per 10^6 samples\n",
              n_rec, static_cast<unsigned long long>(first),
              static_cast<unsigned long long>(first + n_rec - 1), ok, max_samples, wall_s,
              threads, 1e6 * cpu / std::max(samples, 1.0));
  std::printf("\n| term | records with it | it dominates | named where it dominates | "
              "named where present, not dominant | records without it | named without it "
              "(false) | parameter within 25 %% (named, present) | truth inside the 95 %% interval (named, "
              "present) |\n|---|---|---|---|---|---|---|---|---|\n");
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
    for (std::size_t i = 0; i < n_rec; ++i) {
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
      } else {
        ++without;
        false_named += o.named[t] ? 1U : 0U;
      }
    }
    const auto pct = [](std::size_t a, std::size_t b) {
      return b == 0 ? std::string("-")
                    : std::to_string(a) + "/" + std::to_string(b) + " (" +
                          std::to_string(static_cast<int>(std::lround(100.0 * static_cast<double>(a) /
                                                                      static_cast<double>(b)))) +
                          " %)";
    };
    std::printf("| %s | %zu | %zu | %s | %s | %zu | %s | %s | %s |\n", kName[t], with, dom,
                pct(dom_named, dom).c_str(), pct(weak_named, with - dom).c_str(), without,
                pct(false_named, without).c_str(), pct(est_ok, est).c_str(),
                pct(cov_in, cov).c_str());
  }
  std::size_t n_cov = 0;
  std::size_t n_in = 0;
  for (std::size_t i = 0; i < n_rec; ++i) {
    if (outs[i].ok && outs[i].n_hi95 > 0.0) {
      ++n_cov;
      n_in += recs[i].spec.n >= outs[i].n_lo95 && recs[i].spec.n <= outs[i].n_hi95 ? 1U : 0U;
    }
  }
  std::printf("\nwhite noise N inside its 95 %% interval: %zu of %zu\n", n_in, n_cov);
  if (argc > 5) {
    FILE* f = std::fopen(argv[5], "w");
    if (f == nullptr) {
      std::fprintf(stderr, "cannot write %s\n", argv[5]);
      return 1;
    }
    std::fprintf(f, "seed,fs_hz,samples,gyro,true,dominant,named,second_gm,output_filter,unexplained\n");
    for (std::size_t i = 0; i < n_rec; ++i) {
      std::string has;
      std::string dom;
      std::string named;
      for (std::size_t t = 0; t < kTerms; ++t) {
        has += recs[i].has[t] ? std::string(kName[t]) + " " : "";
        dom += recs[i].dominant[t] ? std::string(kName[t]) + " " : "";
        named += outs[i].named[t] ? std::string(kName[t]) + " " : "";
      }
      std::fprintf(f, "%llu,%g,%zu,%d,%s,%s,%s,%d,%d,%d\n",
                   static_cast<unsigned long long>(recs[i].spec.seed), recs[i].spec.fs_hz,
                   recs[i].spec.samples, recs[i].gyro ? 1 : 0, has.c_str(), dom.c_str(),
                   named.c_str(), outs[i].second_gm ? 1 : 0, outs[i].output_filter ? 1 : 0,
                   outs[i].unexplained ? 1 : 0);
    }
    std::fclose(f);
  }
  std::printf("\nreports naming a second GM (the truth has one GM): %zu of %zu\n", second_gm, ok);
  std::printf("reports with an output filter on the white noise (the truth has none): %zu of %zu\n",
              output_filter, ok);
  std::printf("reports with an unexplained tau run: %zu of %zu\n", unexplained, ok);
  std::printf("reports whose effects and model disagree (report_consistent): %zu of %zu\n",
              inconsistent, ok);
  return 0;
}

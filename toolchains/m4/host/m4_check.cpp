// Host twin of the Cortex-M4 program: runs the same workload (demo.cpp, same samples) natively
// and checks it.
//   imu_m4_check --emit         print the host's lines (the format of demo.hpp)
//   imu_m4_check --self         check the host's lines against an independent direct ADEV
//   imu_m4_check --compare LOG  also compare LOG (the target's semihosting output) with the
//                               host's lines, field by field
// Exit 0 when every check passes, 1 on a mismatch, 2 on bad usage or an unreadable log.
//
// The independent reference: the overlapping ADEV computed directly from the phase
// x_j = sum of the first j samples, every term (x_p - 2 x_{p-m} + x_{p-2m})^2 at the stride the
// estimator reports, summed in long double. It shares no code with fw/ (only the sample
// generator, which is input, not result).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "demo.hpp"
#include "samples.hpp"

namespace {

using imu::m4::kChannels;
using imu::m4::kSamples;

struct Fields {
  std::string tag;                          // first word ("P", "C", "IMU-M4")
  std::map<std::string, std::string> kv;    // key=value pairs
};

Fields parse_line(const std::string& line) {
  Fields f;
  std::istringstream in(line);
  std::string word;
  in >> f.tag;
  while (in >> word) {
    const auto eq = word.find('=');
    if (eq == std::string::npos) {
      f.kv[word] = "";
    } else {
      f.kv[word.substr(0, eq)] = word.substr(eq + 1);
    }
  }
  return f;
}

float bits_to_float(const std::string& hex) {
  const auto bits = static_cast<std::uint32_t>(std::stoul(hex, nullptr, 16));
  float v = 0.0F;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

double bits_to_double(const std::string& hex) {
  const std::uint64_t bits = std::stoull(hex, nullptr, 16);
  double v = 0.0;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::uint64_t to_u64(const std::string& s) { return std::stoull(s, nullptr, 10); }

double rel_diff(double a, double b) {
  const double scale = std::fmax(std::fabs(a), std::fabs(b));
  return scale > 0.0 ? std::fabs(a - b) / scale : 0.0;
}

std::vector<std::string> host_lines() {
  std::vector<std::string> lines;
  const auto collect = [](const char* text, void* ctx) {
    auto* out = static_cast<std::vector<std::string>*>(ctx);
    std::string s(text);
    if (!s.empty() && s.back() == '\n') {
      s.pop_back();
    }
    out->push_back(s);
  };
  if (imu::m4::run_demo(collect, &lines) != imu::m4::DemoStatus::kOk) {
    std::fprintf(stderr, "host run_demo reported a truncated line\n");
  }
  return lines;
}

// Phase of every channel: x[c][j] = sum of the first j samples (x[c][0] = 0); true bias at
// the end of the run (counts) in truth[c].
std::vector<std::vector<std::int64_t>> phases(std::vector<std::int32_t>& truth) {
  std::vector<std::vector<std::int64_t>> x(kChannels, std::vector<std::int64_t>(kSamples + 1, 0));
  truth.assign(kChannels, 0);
  for (std::size_t c = 0; c < kChannels; ++c) {
    imu::m4::SampleSource src(static_cast<std::uint32_t>(c));
    for (std::uint32_t j = 0; j < kSamples; ++j) {
      x[c][j + 1] = x[c][j] + src.next();
    }
    truth[c] = src.bias_counts();
  }
  return x;
}

struct Reference {
  std::uint64_t n_terms;
  long double avar;
};

Reference direct_adev(const std::vector<std::int64_t>& x, std::uint64_t af, std::uint64_t stride) {
  Reference r{0, 0.0L};
  long double sum = 0.0L;
  for (std::uint64_t p = 2 * af; p <= kSamples; p += stride) {
    const std::int64_t d = x[p] - 2 * x[p - af] + x[p - 2 * af];
    const auto dl = static_cast<long double>(d);
    sum += dl * dl;
    ++r.n_terms;
  }
  if (r.n_terms > 0) {
    const auto afl = static_cast<long double>(af);
    const auto lsb = static_cast<long double>(imu::m4::kLsb);
    r.avar = lsb * lsb * sum / (2.0L * afl * afl * static_cast<long double>(r.n_terms));
  }
  return r;
}

// A bias filter's K line: counters exact; the estimate within 4 of its own sigmas of the true
// bias (the input is deterministic, so this is not a flaky statistical test: it either holds
// for this data or not; 4 sigma leaves room for the GM model approximating the walk). Prints it.
bool filter_line_holds(const Fields& f, const std::vector<std::int32_t>& truth,
                       std::uint64_t static_samples, const char* who) {
  const std::uint64_t c = to_u64(f.kv.at("c"));
  const double bias = static_cast<double>(bits_to_float(f.kv.at("bias")));
  const double var = static_cast<double>(bits_to_float(f.kv.at("var")));
  const double printed_truth = bits_to_double(f.kv.at("truth"));
  const double ref_truth = c < kChannels ? static_cast<double>(truth[c]) * imu::m4::kLsb : 0.0;
  std::printf("  %s filter c=%llu bias=%.6f truth=%.6f sigma=%.6f updates=%s\n", who,
              static_cast<unsigned long long>(c), bias, ref_truth, std::sqrt(var),
              f.kv.at("updates").c_str());
  return c < kChannels && to_u64(f.kv.at("predictions")) == kSamples &&
         to_u64(f.kv.at("updates")) == static_samples &&
         // exact: an integer times 2^-10 on both sides (no == on floats)
         !(printed_truth < ref_truth) && !(printed_truth > ref_truth) && var > 0.0 &&
         std::fabs(bias - ref_truth) <= 4.0 * std::sqrt(var);
}

// The points per channel: every tau that has at least one term is reported (level 0 has
// m = 1..M, level k >= 1 has m = M/2+1..M at stride 2^k, while 2 m 2^k <= N).
std::size_t expected_points() {
  std::size_t expected = 0;
  for (std::uint64_t m = 1; m <= imu::m4::kAdevM; ++m) {
    expected += 2 * m <= kSamples ? 1 : 0;
  }
  for (std::uint64_t k = 1; k <= imu::m4::kAdevL; ++k) {
    for (std::uint64_t m = imu::m4::kAdevM / 2 + 1; m <= imu::m4::kAdevM; ++m) {
      expected += (2 * m) << k <= kSamples ? 1 : 0;
    }
  }
  return expected;
}

// Every P line of `lines` against the direct reference; counts points per channel.
int check_against_reference(const std::vector<std::string>& lines, const char* who) {
  std::vector<std::int32_t> truth;
  const auto x = phases(truth);
  int failures = 0;
  std::size_t checked = 0;
  std::size_t filters = 0;
  double worst = 0.0;
  std::vector<std::size_t> points(kChannels, 0);
  std::uint64_t static_samples = 0;
  for (std::uint32_t i = 0; i < kSamples; ++i) {
    static_samples += imu::m4::is_static_sample(i) ? 1u : 0u;
  }
  for (const auto& line : lines) {
    const Fields f = parse_line(line);
    if (f.tag == "K") {
      if (!filter_line_holds(f, truth, static_samples, who)) {
        std::printf("FAIL %s: filter line %s\n", who, line.c_str());
        ++failures;
      }
      ++filters;
      continue;
    }
    if (f.tag != "P") {
      continue;
    }
    const std::uint64_t c = to_u64(f.kv.at("c"));
    const std::uint64_t af = to_u64(f.kv.at("af"));
    const std::uint64_t st = to_u64(f.kv.at("st"));
    const std::uint64_t n = to_u64(f.kv.at("n"));
    const double avar = bits_to_double(f.kv.at("avar"));
    const double adev = bits_to_double(f.kv.at("adev"));
    const double edf = bits_to_double(f.kv.at("edf"));
    const double lo = bits_to_double(f.kv.at("lo"));
    const double hi = bits_to_double(f.kv.at("hi"));
    if (c >= kChannels) {
      std::printf("FAIL %s: channel %llu out of range\n", who, static_cast<unsigned long long>(c));
      ++failures;
      continue;
    }
    ++points[c];
    const Reference ref = direct_adev(x[c], af, st);
    // Tolerance 1e-11 relative: fw/ sums squared differences in double in blocks of 2^16
    // positive terms; the plain-sum bound is 2^16 * 1.1e-16 = 7.3e-12 relative. The long
    // double reference is 2^11 times more precise, so the bound is fw's alone.
    const double d = rel_diff(avar, static_cast<double>(ref.avar));
    worst = std::fmax(worst, d);
    const bool ok_terms = ref.n_terms == n;
    const bool ok_avar = d <= 1e-11;
    // adev = sqrt(avar): sqrt is correctly rounded, 1e-15 covers it with margin.
    const bool ok_adev = rel_diff(adev * adev, avar) <= 1e-15 * 4.0;
    const bool ok_ci = edf > 0.0 && lo > 0.0 && lo < adev && adev < hi;
    if (!(ok_terms && ok_avar && ok_adev && ok_ci)) {
      std::printf("FAIL %s: c=%llu af=%llu n=%llu (ref %llu) avar rel diff %.3g edf %.6g ci [%.6g, %.6g] adev %.6g\n",
                  who, static_cast<unsigned long long>(c), static_cast<unsigned long long>(af),
                  static_cast<unsigned long long>(n), static_cast<unsigned long long>(ref.n_terms),
                  d, edf, lo, hi, adev);
      ++failures;
    }
    ++checked;
  }
  const std::size_t expected = expected_points();
  for (std::size_t c = 0; c < kChannels; ++c) {
    if (points[c] != expected) {
      std::printf("FAIL %s: channel %zu has %zu points, expected %zu\n", who, c, points[c], expected);
      ++failures;
    }
  }
  if (filters != kChannels) {
    std::printf("FAIL %s: %zu filter lines, expected %zu\n", who, filters, kChannels);
    ++failures;
  }
  std::printf("%s vs direct ADEV: %zu points checked, worst avar rel diff %.3g (tol 1e-11); %zu filters; %d failures\n",
              who, checked, worst, filters, failures);
  return failures;
}

// Field-by-field comparison of the target's lines with the host's.
int compare_with_host(const std::vector<std::string>& target, const std::vector<std::string>& host) {
  int failures = 0;
  std::vector<std::string> t;
  bool stack_seen = false;
  for (const auto& line : target) {
    const Fields f = parse_line(line);
    if (f.tag == "IMU-M4" && f.kv.count("STACK") != 0) {
      stack_seen = true;
      std::printf("target stack: used %s of %s bytes\n", f.kv.at("used").c_str(), f.kv.at("of").c_str());
      continue;
    }
    if (f.tag == "P" || f.tag == "C" || f.tag == "K" || f.tag == "IMU-M4") {
      t.push_back(line);
    }
  }
  if (!stack_seen) {
    std::printf("FAIL: the target log has no STACK line (did the program finish?)\n");
    ++failures;
  }
  if (t.size() != host.size()) {
    std::printf("FAIL: target has %zu lines, host %zu\n", t.size(), host.size());
    return failures + 1;
  }
  std::size_t identical_lines = 0;
  std::map<std::string, std::size_t> bit_identical;
  std::map<std::string, double> worst;
  const char* exact_keys[] = {"c", "af", "st", "n", "samples", "points", "channels", "M", "L",
                              "ts_bits", "lsb_bits", "status", "lines", "truth", "predictions",
                              "updates"};
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] == host[i]) {
      ++identical_lines;
    }
    const Fields a = parse_line(t[i]);
    const Fields b = parse_line(host[i]);
    if (a.tag != b.tag || a.kv.size() != b.kv.size()) {
      std::printf("FAIL line %zu: shape differs:\n  target: %s\n  host:   %s\n", i + 1, t[i].c_str(), host[i].c_str());
      ++failures;
      continue;
    }
    for (const char* k : exact_keys) {
      if (a.kv.count(k) != b.kv.count(k) || (a.kv.count(k) != 0 && a.kv.at(k) != b.kv.at(k))) {
        std::printf("FAIL line %zu: field %s differs:\n  target: %s\n  host:   %s\n", i + 1, k, t[i].c_str(), host[i].c_str());
        ++failures;
      }
    }
    if (a.tag == "K") {
      for (const char* k : {"bias", "var"}) {
        const double va = static_cast<double>(bits_to_float(a.kv.at(k)));
        const double vb = static_cast<double>(bits_to_float(b.kv.at(k)));
        const double d = rel_diff(va, vb);
        const std::string key = std::string("kf_") + k;
        worst[key] = std::fmax(worst[key], d);
        bit_identical[key] += a.kv.at(k) == b.kv.at(k) ? 1u : 0u;
        // Float filter: not bit-identical by design of the compilers: arm-none-eabi-g++ fuses
        // a*b+c into vfma.f32 (GCC's C++ default -ffp-contract=fast; 3 vfma in the image),
        // x86-64 g++ cannot (no FMA in the baseline ISA). One rounding less per fused step,
        // ~6e-8 relative, and the filter forgets old errors (time constant sqrt(R / Qw) ~ 1000
        // samples), so the difference stays ~1e-7; 1e-5 relative is the bound with margin.
        if (d > 1e-5) {
          std::printf("FAIL line %zu: filter %s differs by %.3g relative (tol 1e-5)\n", i + 1, k, d);
          ++failures;
        }
      }
      continue;
    }
    if (a.tag != "P") {
      continue;
    }
    for (const char* k : {"avar", "adev", "edf", "lo", "hi"}) {
      const double va = bits_to_double(a.kv.at(k));
      const double vb = bits_to_double(b.kv.at(k));
      const double d = rel_diff(va, vb);
      worst[k] = std::fmax(worst[k], d);
      bit_identical[k] += a.kv.at(k) == b.kv.at(k) ? 1u : 0u;
      // avar, adev, edf: the same IEEE-754 operations in the same order on both sides (the M4
      // does double in software, correctly rounded; no FMA contraction on either side for
      // double), so they are expected bit-identical; 4 ulp (1e-15) of slack.
      // lo, hi: chi-square quantiles use lgamma, exp, log, erfc, whose last bits differ between
      // newlib and glibc (<= a few ulp), and a Newton iteration that stops at a 1e-14 relative
      // step; 1e-12 covers both with margin.
      const double tol = (std::strcmp(k, "lo") == 0 || std::strcmp(k, "hi") == 0) ? 1e-12 : 1e-15;
      if (d > tol) {
        std::printf("FAIL line %zu: %s differs by %.3g relative (tol %.0e)\n", i + 1, k, d, tol);
        ++failures;
      }
    }
  }
  std::printf("target vs host: %zu lines, %zu byte-identical\n", t.size(), identical_lines);
  for (const char* k : {"avar", "adev", "edf", "lo", "hi", "kf_bias", "kf_var"}) {
    std::printf("  %-7s bit-identical %zu, worst rel diff %.3g\n", k, bit_identical[k], worst[k]);
  }
  return failures;
}

std::vector<std::string> read_lines(const char* path, bool& ok) {
  std::vector<std::string> lines;
  std::ifstream in(path);
  ok = static_cast<bool>(in);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') {
      line.pop_back();
    }
    lines.push_back(line);
  }
  return lines;
}

// One human-readable summary line per channel: ADEV at tau = Ts and at the longest tau.
void print_summary(const std::vector<std::string>& lines) {
  for (const auto& line : lines) {
    const Fields f = parse_line(line);
    if (f.tag == "P" && (f.kv.at("af") == "1" || f.kv.at("af") == "128")) {
      std::printf("  c=%s tau=%gs adev=%.9g [%.9g, %.9g] n=%s\n", f.kv.at("c").c_str(),
                  static_cast<double>(to_u64(f.kv.at("af"))) * imu::m4::kSamplePeriodS,
                  bits_to_double(f.kv.at("adev")), bits_to_double(f.kv.at("lo")),
                  bits_to_double(f.kv.at("hi")), f.kv.at("n").c_str());
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc >= 2 ? argv[1] : "";
  if (mode == "--emit" && argc == 2) {
    for (const auto& l : host_lines()) {
      std::printf("%s\n", l.c_str());
    }
    return 0;
  }
  if (mode == "--self" && argc == 2) {
    const auto host = host_lines();
    print_summary(host);
    const int failures = check_against_reference(host, "host");
    std::printf(failures == 0 ? "M4-CHECK PASS (host self-check)\n" : "M4-CHECK FAIL\n");
    return failures == 0 ? 0 : 1;
  }
  if (mode == "--compare" && argc == 3) {
    bool ok = false;
    const auto target = read_lines(argv[2], ok);
    if (!ok) {
      std::fprintf(stderr, "imu_m4_check: cannot read %s\n", argv[2]);
      return 2;
    }
    const auto host = host_lines();
    print_summary(target);
    int failures = check_against_reference(target, "target");
    failures += compare_with_host(target, host);
    std::printf(failures == 0 ? "M4-CHECK PASS (target == host)\n" : "M4-CHECK FAIL\n");
    return failures == 0 ? 0 : 1;
  }
  std::fprintf(stderr, "usage: imu_m4_check --emit | --self | --compare <target log>\n");
  return 2;
}

// `imu-sim adev --deviation adev,mdev,hdev,tdev`: against allantools (oadev, mdev, ohdev, tdev;
// tests/host_sim/deviations/allantools_dev.csv, written by allantools outside this repository
// by make_golden.py there) on its tau lists, against a direct double-precision evaluation of
// NIST SP 1065 (Riley 2008) eqns. 13 and 19 with gaps, and the option's rules and outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "sim_test_util.hpp"

namespace {

const std::string kDir = IMU_DEVIATIONS_DIR;
const char* const kKinds[] = {"adev", "mdev", "hdev", "tdev"};

struct Row {
  std::uint64_t af = 0;
  double tau_s = 0.0;
  double dev = 0.0;
  double edf = 0.0;
  double ci_lo = 0.0;
  double ci_hi = 0.0;
  std::uint64_t n = 0;
};

// The rows of the JSON list under key `kind` (the writer puts one object per line).
std::vector<Row> json_rows(const std::string& json, const std::string& kind) {
  std::vector<Row> out;
  const std::size_t start = json.find("\"" + kind + "\": [");
  if (start == std::string::npos) {
    return out;
  }
  const std::size_t end = json.find(']', start);
  std::istringstream in(json.substr(start, end - start));
  const std::string fmt = " {\"tau_s\": %lf, \"" + kind +
                          "\": %lf, \"edf\": %lf, \"ci_lo\": %lf, \"ci_hi\": %lf, "
                          "\"n_terms\": %llu, \"af\": %llu";
  std::string line;
  while (std::getline(in, line)) {
    Row r;
    unsigned long long n = 0;
    unsigned long long af = 0;
    if (std::sscanf(line.c_str(), fmt.c_str(), &r.tau_s, &r.dev, &r.edf, &r.ci_lo, &r.ci_hi, &n,
                    &af) == 7) {
      r.n = n;
      r.af = af;
      out.push_back(r);
    }
  }
  return out;
}

// allantools' rows of one grid ("octave", "decade", "all60"), by deviation.
std::map<std::string, std::vector<Row>> golden(const std::string& grid) {
  std::map<std::string, std::vector<Row>> out;
  std::ifstream f(kDir + "/allantools_dev.csv");
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("grid,", 0) == 0) {
      continue;
    }
    char g[16] = {};
    char k[8] = {};
    Row r;
    unsigned long long af = 0;
    unsigned long long n = 0;
    if (std::sscanf(line.c_str(), "%15[^,],%7[^,],%llu,%lf,%lf,%llu,%lf,%lf,%lf", g, k, &af,
                    &r.tau_s, &r.dev, &n, &r.edf, &r.ci_lo, &r.ci_hi) == 9 &&
        grid == g) {
      r.af = af;
      r.n = n;
      out[k].push_back(r);
    }
  }
  return out;
}

std::vector<std::uint64_t> afs(const std::vector<Row>& rows) {
  std::vector<std::uint64_t> v;
  v.reserve(rows.size());
  for (const Row& r : rows) {
    v.push_back(r.af);
  }
  return v;
}

// The input's first `n` samples (all: 0) as its own file.
std::string input_prefix(simtest::TempDir& tmp, std::size_t n) {
  const std::string all = simtest::read_text(kDir + "/dev_input.csv");
  if (n == 0) {
    return kDir + "/dev_input.csv";
  }
  std::size_t pos = 0;
  for (std::size_t lines = 0; lines < n + 1; ++lines) {  // header + n rows
    pos = all.find('\n', pos) + 1;
  }
  std::string path = tmp.file("prefix.csv");
  std::ofstream(path) << all.substr(0, pos);
  return path;
}

// `input`: a file of the directory to read instead of dev_input.csv's first n samples, without
// --lsb (float values, no grid).
void expect_like_allantools(const std::string& grid, const std::string& taus, std::size_t n,
                            const std::string& input = "") {
  SCOPED_TRACE(grid);
  simtest::TempDir tmp;
  const std::string json = tmp.file("d.json");
  std::vector<std::string> args = {"adev", input.empty() ? input_prefix(tmp, n) : kDir + "/" + input,
                                   "--channel", "y", "--taus", taus, "--deviation",
                                   "adev,mdev,hdev,tdev", "--json", json};
  if (input.empty()) {
    args.insert(args.end(), {"--lsb", "1e-6"});
  }
  const auto r = simtest::run(args);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j = simtest::read_text(json);
  EXPECT_NE(j.find(input.empty() ? "\"lsb\": 1e-06" : "\"lsb\": null"), std::string::npos) << j;
  const auto gold = golden(grid);
  for (const char* kind : kKinds) {
    SCOPED_TRACE(kind);
    const std::vector<Row> ours = json_rows(j, kind);
    const auto it = gold.find(kind);
    ASSERT_NE(it, gold.end());
    const std::vector<Row>& ref = it->second;
    ASSERT_EQ(afs(ours), afs(ref));  // the same tau list
    for (std::size_t i = 0; i < ours.size(); ++i) {
      const Row& o = ours[i];
      const Row& g = ref[i];
      // The same estimator on the same data: 1e-8 covers the JSON's 10 digits and allantools'
      // floating-point phase (cumulative sum of the mean-removed frequency data); we sum exact
      // integers.
      EXPECT_NEAR(o.dev, g.dev, 1e-8 * g.dev) << "af " << o.af;
      EXPECT_NEAR(o.tau_s, g.tau_s, 1e-12 * g.tau_s) << "af " << o.af;
      EXPECT_EQ(o.n, g.n) << "af " << o.af;
      // Greenhall-Riley EDF, the same closed forms implemented independently, and the interval
      // from it (NIST SP 1065 eqn. 45): 1e-8 as the values (the JSON's 10 digits).
      EXPECT_NEAR(o.edf, g.edf, 1e-8 * g.edf) << "af " << o.af;
      EXPECT_NEAR(o.ci_lo, g.ci_lo, 1e-8 * g.ci_lo) << "af " << o.af;
      EXPECT_NEAR(o.ci_hi, g.ci_hi, 1e-8 * g.ci_hi) << "af " << o.af;
    }
  }
}

TEST(Deviations, MatchAllantoolsOctave) { expect_like_allantools("octave", "octave", 0); }
TEST(Deviations, MatchAllantoolsDecade) { expect_like_allantools("decade", "decade", 0); }
// Every averaging factor on 60 samples: each deviation's last tau as allantools keeps it (adev
// 29, mdev and tdev 20, hdev 19).
TEST(Deviations, MatchAllantoolsAllTaus) { expect_like_allantools("all60", "all", 60); }
// Float values on no grid (an accelerometer's 9.8 m/s^2 offset, steps of 1e-6 / sqrt(2) plus a
// uniform fraction) without an LSB: taken as they are, as allantools takes them.
TEST(Deviations, MatchAllantoolsOnFloatValuesWithoutLsb) {
  expect_like_allantools("float_octave", "octave", 0, "dev_input_float.csv");
}

// Frequency samples y (NaN: missing), averaging factor m: the mean of y[i .. i+m-1].
double ybar(const std::vector<double>& y, std::size_t i, std::size_t m) {
  double s = 0.0;
  for (std::size_t k = i; k < i + m; ++k) {
    s += y[k];
  }
  return s / static_cast<double>(m);
}

// Direct evaluation from averages of the frequency data (not from phase differences): NIST SP
// 1065 eqn. 13, Mod sigma^2(tau) = sum_j {sum_{i=j}^{j+m-1} [ybar_{i+m} - ybar_i]}^2 /
// (2 m^2 terms), and eqn. 19 (overlapping Hadamard), sum_j (ybar_{j+2m} - 2 ybar_{j+m} +
// ybar_j)^2 / (6 terms). A term with a missing sample is NaN and left out. O(n m^2).
struct Direct {
  double var = 0.0;
  std::uint64_t terms = 0;
};

Direct direct_mvar(const std::vector<double>& y, std::size_t m) {
  Direct d;
  double sum = 0.0;
  for (std::size_t j = 0; j + 3 * m - 1 <= y.size(); ++j) {
    double inner = 0.0;
    for (std::size_t i = j; i < j + m; ++i) {
      inner += ybar(y, i + m, m) - ybar(y, i, m);
    }
    if (!std::isnan(inner)) {
      sum += inner * inner;
      ++d.terms;
    }
  }
  d.var = sum / (2.0 * static_cast<double>(m * m) * static_cast<double>(d.terms));
  return d;
}

Direct direct_hvar(const std::vector<double>& y, std::size_t m) {
  Direct d;
  double sum = 0.0;
  for (std::size_t j = 0; j + 3 * m <= y.size(); ++j) {
    const double h = ybar(y, j + 2 * m, m) - 2.0 * ybar(y, j + m, m) + ybar(y, j, m);
    if (!std::isnan(h)) {
      sum += h * h;
      ++d.terms;
    }
  }
  d.var = sum / (6.0 * static_cast<double>(d.terms));
  return d;
}

// Gaps: the first 240 samples with three missing (NaN) inside, every tau. Each row against the
// direct evaluation; a term touching a gap is left out (the term counts show it), tdev is
// tau mdev / sqrt(3) (SP 1065 eqn. 15).
TEST(Deviations, GapsAgainstDirectEvaluation) {
  std::ifstream f(kDir + "/dev_input.csv");
  std::string line;
  std::getline(f, line);
  std::vector<double> y;
  while (std::getline(f, line) && y.size() < 240) {
    y.push_back(std::strtod(line.c_str() + line.find(',') + 1, nullptr));
  }
  ASSERT_EQ(y.size(), 240U);
  y[50] = y[51] = y[130] = std::nan("");
  simtest::TempDir tmp;
  const std::string csv = tmp.file("gaps.csv");
  {
    std::ofstream out(csv);
    out << "t,y\n";
    char buf[64];
    for (std::size_t k = 0; k < y.size(); ++k) {
      std::snprintf(buf, sizeof buf, "%.2f,%.17g\n", static_cast<double>(k) * 0.01, y[k]);
      out << (std::isnan(y[k]) ? std::string(buf, std::string(buf).find(',')) + ",nan\n" : buf);
    }
  }
  const std::string json = tmp.file("g.json");
  const auto r = simtest::run({"adev", csv, "--channel", "y", "--lsb", "1e-6", "--fs", "100",
                               "--taus", "all", "--deviation", "mdev,hdev,tdev", "--json",
                               json});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j = simtest::read_text(json);
  const std::vector<Row> md = json_rows(j, "mdev");
  const std::vector<Row> hd = json_rows(j, "hdev");
  const std::vector<Row> td = json_rows(j, "tdev");
  ASSERT_EQ(afs(td), afs(md));
  // Every m up to the last (mdev 240 / 3, hdev 239 / 3) that keeps a term.
  std::vector<std::uint64_t> m_mdev;
  std::vector<std::uint64_t> m_hdev;
  for (std::size_t m = 1; m <= 80; ++m) {
    if (direct_mvar(y, m).terms > 0) {
      m_mdev.push_back(m);
    }
    if (m <= 79 && direct_hvar(y, m).terms > 0) {
      m_hdev.push_back(m);
    }
  }
  EXPECT_EQ(afs(md), m_mdev);
  EXPECT_EQ(afs(hd), m_hdev);
  EXPECT_GT(m_mdev.size(), 30U);
  EXPECT_LT(m_mdev.size(), 80U);  // the longest taus have no term without a gap
  // Reason for 1e-9: the direct sums in double lose about 1e-13 relative to the cancellation of
  // the averages (offset 1e-3, fluctuations 1e-4); the JSON prints 10 digits.
  for (std::size_t i = 0; i < md.size(); ++i) {
    const auto m = static_cast<std::size_t>(md[i].af);
    const Direct d = direct_mvar(y, m);
    EXPECT_EQ(md[i].n, d.terms) << "m " << m;
    EXPECT_NEAR(md[i].dev, std::sqrt(d.var), 1e-9 * std::sqrt(d.var)) << "m " << m;
    const double tdev = md[i].tau_s * std::sqrt(d.var) / std::sqrt(3.0);
    EXPECT_NEAR(td[i].dev, tdev, 1e-9 * tdev) << "m " << m;
    EXPECT_EQ(td[i].n, d.terms);
    EXPECT_NEAR(td[i].edf, md[i].edf, 1e-9 * md[i].edf);
  }
  for (const Row& h : hd) {
    const auto m = static_cast<std::size_t>(h.af);
    const Direct d = direct_hvar(y, m);
    EXPECT_EQ(h.n, d.terms) << "m " << m;
    EXPECT_NEAR(h.dev, std::sqrt(d.var), 1e-9 * std::sqrt(d.var)) << "m " << m;
  }
  // m = 1: the mdev term j spans samples j .. j+1, so the 3 gaps (two adjacent) remove 5 of
  // its 239 terms; hdev's j .. j+2 remove 7 of 238.
  ASSERT_FALSE(md.empty());
  ASSERT_FALSE(hd.empty());
  EXPECT_EQ(md[0].n, 239U - 5U);
  EXPECT_EQ(hd[0].n, 238U - 7U);
}

// The option: several deviations in one table each, the CSV's columns, usage errors, and the
// plain `adev` output without a deviation column or heading.
TEST(Deviations, OptionOutputsAndErrors) {
  simtest::TempDir tmp;
  const std::string in = kDir + "/dev_input.csv";
  const std::string csv = tmp.file("d.csv");
  auto r = simtest::run({"adev", in, "--channel", "y", "--deviation", "mdev", "--csv", csv});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(simtest::read_text(csv).rfind("tau_s,af,mdev,ci_lo,ci_hi,edf,n_terms\n", 0), 0U);
  EXPECT_NE(r.out.find("mdev: modified Allan deviation\n"), std::string::npos) << r.out;
  r = simtest::run({"adev", in, "--channel", "y", "--deviation", "tdev,hdev,tdev", "--csv", csv});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string two = simtest::read_text(csv);
  EXPECT_EQ(two.rfind("deviation,tau_s,af,dev,ci_lo,ci_hi,edf,n_terms\ntdev,0.01,1,", 0), 0U)
      << two.substr(0, 120);
  EXPECT_NE(two.find("\nhdev,0.01,1,"), std::string::npos);
  EXPECT_EQ(two.find("\nadev,"), std::string::npos);
  EXPECT_LT(r.out.find("tdev: time deviation"), r.out.find("hdev: overlapping Hadamard"));
  r = simtest::run({"adev", in, "--channel", "y", "--csv", csv});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(simtest::read_text(csv).rfind("tau_s,af,adev,ci_lo,", 0), 0U);
  EXPECT_EQ(r.out.find("adev: Allan deviation"), std::string::npos);
  EXPECT_NE(r.out.find("online ADEV"), std::string::npos);
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"adev", in, "--channel", "y", "--deviation", "mdev",
                                 "--estimator", "online"},
        std::vector<std::string>{"adev", in, "--channel", "y", "--deviation", "odev"},
        std::vector<std::string>{"adev", in, "--channel", "y", "--deviation", "mdev,"}}) {
    r = simtest::run(bad);
    EXPECT_EQ(r.status, 2) << bad[4] << " " << bad[5];
    EXPECT_NE(r.err.find("--deviation"), std::string::npos) << r.err;
  }
  // The online estimator keeps accepting the plain ADEV.
  r = simtest::run({"adev", in, "--channel", "y", "--deviation", "adev", "--estimator", "online"});
  EXPECT_EQ(r.status, 0) << r.err;
}

}  // namespace

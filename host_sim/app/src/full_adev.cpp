// See full_adev.hpp.
#include "full_adev.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "imu/edf.hpp"

namespace imu::sim {
namespace {

// 128-bit integers (GCC and Clang): the modified sums S_j reach m * 2m * 2^31, beyond int64 for
// m above 2^15 when the counts span int32.
__extension__ using Int128 = __int128;

// The integer phase x[k] = sum of the first k counts (|x| <= n 2^31: exact in int64) and gx[k],
// the number of missing samples among them.
struct Phase {
  std::vector<std::int64_t> x;
  std::vector<std::uint32_t> gx;
};

Phase integer_phase(const FullAdevSink& data) {
  const std::vector<std::int32_t>& c = data.counts();
  const std::vector<std::uint8_t>& g = data.gaps();
  const std::size_t n = c.size();
  Phase p;
  p.x.assign(n + 1, 0);
  p.gx.assign(n + 1, 0);
  for (std::size_t k = 0; k < n; ++k) {
    p.x[k + 1] = p.x[k] + c[k];
    p.gx[k + 1] = p.gx[k] + g[k];
  }
  return p;
}

// A row from its variance in the data's unit squared, the EDF and the term count.
AdevRow deviation_row(std::uint64_t m, double ts_s, double var, double edf, std::uint64_t terms) {
  AdevRow r;
  r.tau_s = static_cast<double>(m) * ts_s;
  r.af = m;
  r.adev = std::sqrt(var);
  r.n_terms = terms;
  r.edf = edf;
  const DevInterval ci = deviation_interval(r.adev, r.edf);
  r.ci_lo = ci.lo;
  r.ci_hi = ci.hi;
  return r;
}

// Sum over j of S_j^2 (see full_deviation), the terms whose 3m - 1 samples have no gap.
long double modified_sum(const Phase& p, std::size_t m, std::uint64_t& terms) {
  const std::vector<std::int64_t>& x = p.x;
  const std::size_t last = x.size() - 3 * m;  // j = 0 .. n + 1 - 3m
  Int128 s = 0;
  for (std::size_t i = 0; i < m; ++i) {
    s += x[i + 2 * m] - 2 * x[i + m] + x[i];
  }
  long double sum = 0.0L;
  terms = 0;
  for (std::size_t j = 0;; ++j) {
    if (p.gx[j + 3 * m - 1] == p.gx[j]) {
      const auto v = static_cast<long double>(s);
      sum += v * v;
      ++terms;
    }
    if (j == last) {
      break;
    }
    s += x[j + 3 * m] - 3 * x[j + 2 * m] + 3 * x[j + m] - x[j];
  }
  return sum;
}

// Sum over j of the squared third differences whose 3m samples have no gap.
long double hadamard_sum(const Phase& p, std::size_t m, std::uint64_t& terms) {
  const std::vector<std::int64_t>& x = p.x;
  long double sum = 0.0L;
  terms = 0;
  for (std::size_t j = 0; j + 3 * m < x.size(); ++j) {
    if (p.gx[j + 3 * m] != p.gx[j]) {
      continue;
    }
    const std::int64_t h = x[j + 3 * m] - 3 * x[j + 2 * m] + 3 * x[j + m] - x[j];
    const auto v = static_cast<long double>(h);
    sum += v * v;
    ++terms;
  }
  return sum;
}

}  // namespace

void FullAdevSink::push(const std::int32_t* counts, std::size_t n) {
  counts_.insert(counts_.end(), counts, counts + n);
  gaps_.insert(gaps_.end(), n, 0);
}

void FullAdevSink::gap(std::size_t n) {
  counts_.insert(counts_.end(), n, 0);
  gaps_.insert(gaps_.end(), n, 1);
}

bool tau_grid(const std::string& kind, std::uint64_t n, std::vector<std::uint64_t>& m) {
  m.clear();
  const std::uint64_t m_max = n >= 3 ? (n - 1) / 2 : 0;
  if (kind == "octave") {
    for (std::uint64_t v = 1; v <= m_max; v *= 2) {
      m.push_back(v);
    }
  } else if (kind == "decade") {
    for (std::uint64_t d = 1; d <= m_max; d *= 10) {
      for (const std::uint64_t f : {1U, 2U, 4U}) {
        if (f * d <= m_max) {
          m.push_back(f * d);
        }
      }
    }
  } else if (kind == "quarter") {
    for (int k = 0;; ++k) {
      const auto v = static_cast<std::uint64_t>(std::llround(std::pow(2.0, k / 4.0)));
      if (v > m_max) {
        break;
      }
      if (m.empty() || m.back() != v) {
        m.push_back(v);
      }
    }
  } else if (kind == "all") {
    for (std::uint64_t v = 1; v <= m_max; ++v) {
      m.push_back(v);
    }
  } else {
    return false;
  }
  return true;
}

double full_adev_cost(std::uint64_t n, const std::vector<std::uint64_t>& m) {
  double c = 0.0;
  for (const std::uint64_t v : m) {
    c += static_cast<double>(n) - 2.0 * static_cast<double>(v);
  }
  return c;
}

std::vector<AdevRow> full_adev(const FullAdevSink& data, const std::vector<std::uint64_t>& m,
                               double ts_s, double lsb) {
  const Phase p = integer_phase(data);
  const std::vector<std::int64_t>& x = p.x;
  const std::vector<std::uint32_t>& gx = p.gx;
  const std::size_t n = data.counts().size();
  std::vector<AdevRow> rows;
  for (const std::uint64_t mm : m) {
    const auto mi = static_cast<std::size_t>(mm);
    if (mi == 0 || 2 * mi >= n + 1) {
      continue;
    }
    long double sum = 0.0L;
    std::uint64_t terms = 0;
    for (std::size_t i = 0; i + 2 * mi <= n; ++i) {
      if (gx[i + 2 * mi] != gx[i]) {
        continue;
      }
      const std::int64_t d = x[i + 2 * mi] - 2 * x[i + mi] + x[i];
      const auto dd = static_cast<long double>(d);
      sum += dd * dd;
      ++terms;
    }
    if (terms == 0) {
      continue;
    }
    const double md = static_cast<double>(mm);
    const double avar = static_cast<double>(sum / static_cast<long double>(terms)) /
                        (2.0 * md * md) * lsb * lsb;
    // stride 1: S = m
    rows.push_back(deviation_row(mm, ts_s, avar,
                                 edf_greenhall(0, 2, md, md, static_cast<double>(terms)), terms));
  }
  return rows;
}

const char* deviation_name(Deviation d) {
  switch (d) {
    case Deviation::kAdev: return "adev";
    case Deviation::kMdev: return "mdev";
    case Deviation::kHdev: return "hdev";
    case Deviation::kTdev: return "tdev";
  }
  return "adev";
}

bool parse_deviations(const std::string& list, std::vector<Deviation>& out, std::string& err) {
  out.clear();
  std::size_t pos = 0;
  for (;;) {
    const std::size_t comma = list.find(',', pos);
    const std::string name = list.substr(pos, comma == std::string::npos ? comma : comma - pos);
    bool known = false;
    for (const Deviation d : {Deviation::kAdev, Deviation::kMdev, Deviation::kHdev,
                              Deviation::kTdev}) {
      if (name == deviation_name(d)) {
        known = true;
        if (std::find(out.begin(), out.end(), d) == out.end()) {
          out.push_back(d);
        }
      }
    }
    if (!known) {
      err = "'" + name + "': adev, mdev, hdev or tdev (a comma list for several)";
      return false;
    }
    if (comma == std::string::npos) {
      return true;
    }
    pos = comma + 1;
  }
}

std::uint64_t deviation_max_af(Deviation d, std::uint64_t n) {
  switch (d) {
    case Deviation::kAdev: return n >= 3 ? (n - 1) / 2 : 0;
    case Deviation::kMdev:
    case Deviation::kTdev: return n / 3;
    case Deviation::kHdev: return n >= 4 ? (n - 1) / 3 : 0;
  }
  return 0;
}

std::vector<AdevRow> full_deviation(const FullAdevSink& data, Deviation d,
                                    const std::vector<std::uint64_t>& m, double ts_s, double lsb) {
  if (d == Deviation::kAdev) {
    return full_adev(data, m, ts_s, lsb);
  }
  const Phase p = integer_phase(data);
  const std::uint64_t m_max = deviation_max_af(d, data.counts().size());
  std::vector<AdevRow> rows;
  for (const std::uint64_t mm : m) {
    if (mm == 0 || mm > m_max) {
      continue;
    }
    const auto mi = static_cast<std::size_t>(mm);
    const double md = static_cast<double>(mm);
    std::uint64_t terms = 0;
    if (d == Deviation::kHdev) {
      const long double sum = hadamard_sum(p, mi, terms);
      if (terms == 0) {
        continue;
      }
      const double hvar = static_cast<double>(sum / static_cast<long double>(terms)) /
                          (6.0 * md * md) * lsb * lsb;
      rows.push_back(deviation_row(mm, ts_s, hvar,
                                   edf_greenhall(0, 3, md, md, static_cast<double>(terms)),
                                   terms));
      continue;
    }
    const long double sum = modified_sum(p, mi, terms);
    if (terms == 0) {
      continue;
    }
    const double mvar = static_cast<double>(sum / static_cast<long double>(terms)) /
                        (2.0 * md * md * md * md) * lsb * lsb;
    const double edf = edf_greenhall_modified(0, 2, md, md, static_cast<double>(terms));
    AdevRow r = deviation_row(mm, ts_s, mvar, edf, terms);
    if (d == Deviation::kTdev) {
      const double k = r.tau_s / std::sqrt(3.0);  // TVAR = tau^2 MVAR / 3 (SP 1065 eqn. 15)
      r.adev *= k;
      r.ci_lo *= k;
      r.ci_hi *= k;
    }
    rows.push_back(r);
  }
  return rows;
}

std::vector<AdevRow> rows_on_grid(const std::vector<AdevRow>& rows,
                                  const std::vector<std::uint64_t>& m) {
  std::vector<AdevRow> out;
  for (const AdevRow& r : rows) {
    if (std::binary_search(m.begin(), m.end(), r.af)) {
      out.push_back(r);
    }
  }
  return out;
}

std::string adev_csv(const std::vector<AdevRow>& rows, const char* value) {
  std::string s = std::string("tau_s,af,") + value + ",ci_lo,ci_hi,edf,n_terms\n";
  char buf[192];
  for (const AdevRow& r : rows) {
    std::snprintf(buf, sizeof buf, "%.10g,%llu,%.10g,%.10g,%.10g,%.6g,%llu\n", r.tau_s,
                  static_cast<unsigned long long>(r.af), r.adev, r.ci_lo, r.ci_hi, r.edf,
                  static_cast<unsigned long long>(r.n_terms));
    s += buf;
  }
  return s;
}

}  // namespace imu::sim

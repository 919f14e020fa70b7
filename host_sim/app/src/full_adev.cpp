// See full_adev.hpp.
#include "full_adev.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "imu/edf.hpp"

namespace imu::sim {

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
  const std::vector<std::int32_t>& c = data.counts();
  const std::vector<std::uint8_t>& g = data.gaps();
  const std::size_t n = c.size();
  std::vector<std::int64_t> x(n + 1, 0);     // integer phase: |x| <= n 2^31, exact
  std::vector<std::uint32_t> gx(n + 1, 0);   // missing samples before k
  for (std::size_t k = 0; k < n; ++k) {
    x[k + 1] = x[k] + c[k];
    gx[k + 1] = gx[k] + g[k];
  }
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
    AdevRow r;
    r.tau_s = md * ts_s;
    r.af = mm;
    r.adev = std::sqrt(avar);
    r.n_terms = terms;
    r.edf = edf_greenhall(0, 2, md, md, static_cast<double>(terms));  // stride 1: S = m
    const DevInterval ci = deviation_interval(r.adev, r.edf);
    r.ci_lo = ci.lo;
    r.ci_hi = ci.hi;
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

std::string adev_csv(const std::vector<AdevRow>& rows) {
  std::string s = "tau_s,af,adev,ci_lo,ci_hi,edf,n_terms\n";
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

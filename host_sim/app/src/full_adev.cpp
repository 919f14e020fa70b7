// See full_adev.hpp.
#include "full_adev.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <type_traits>

#include "imu/edf.hpp"

namespace imu::sim {
namespace {

// 128-bit integers (GCC and Clang), for the modified sums of counts.
__extension__ using Int128 = __int128;

// The phase x[k] = sum of the first k samples and gx[k], the number of missing samples among
// them. Counts: integers (|x| <= n 2^31: exact in int64), the sums of differences in 128 bits
// (the modified sums S_j reach m * 2m * 2^31, beyond int64 for m above 2^15 when the counts span
// int32). Values: the mean-removed samples summed in long double, kept in double.
template <typename T>
struct Phase {
  using Sum = std::conditional_t<std::is_integral_v<T>, Int128, long double>;
  std::vector<T> x;
  std::vector<std::uint32_t> gx;
};

Phase<std::int64_t> integer_phase(const FullAdevSink& data) {
  const std::vector<std::int32_t>& c = data.counts();
  const std::vector<std::uint8_t>& g = data.gaps();
  const std::size_t n = c.size();
  Phase<std::int64_t> p;
  p.x.assign(n + 1, 0);
  p.gx.assign(n + 1, 0);
  for (std::size_t k = 0; k < n; ++k) {
    p.x[k + 1] = p.x[k] + c[k];
    p.gx[k + 1] = p.gx[k] + g[k];
  }
  return p;
}

// The mean does not change a difference of second (or higher) order; removing it keeps the
// phase small, so its double rounding stays far below the differences.
Phase<double> value_phase(const FullAdevSink& data) {
  const std::vector<double>& v = data.values();
  const std::vector<std::uint8_t>& g = data.gaps();
  const std::size_t n = v.size();
  long double mean = 0.0L;
  std::size_t present = 0;
  for (std::size_t k = 0; k < n; ++k) {
    mean += g[k] != 0 ? 0.0L : static_cast<long double>(v[k]);
    present += g[k] != 0 ? 0U : 1U;
  }
  mean /= static_cast<long double>(present > 0 ? present : 1U);
  Phase<double> p;
  p.x.assign(n + 1, 0.0);
  p.gx.assign(n + 1, 0);
  long double acc = 0.0L;
  for (std::size_t k = 0; k < n; ++k) {
    acc += g[k] != 0 ? 0.0L : static_cast<long double>(v[k]) - mean;
    p.x[k + 1] = static_cast<double>(acc);
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

// Sum over j of diff(j)^2 for the terms whose `span` + 1 phase points (span samples) have no
// gap: the Allan (second differences, span 2m) and Hadamard (third, span 3m) sums.
template <typename T, class Diff>
long double gapless_squared_sum(const Phase<T>& p, std::size_t span, std::uint64_t& terms,
                                Diff diff) {
  long double sum = 0.0L;
  terms = 0;
  for (std::size_t j = 0; j + span < p.x.size(); ++j) {
    if (p.gx[j + span] != p.gx[j]) {
      continue;
    }
    const auto v = static_cast<long double>(diff(j));
    sum += v * v;
    ++terms;
  }
  return sum;
}

template <typename T>
long double allan_sum(const Phase<T>& p, std::size_t m, std::uint64_t& terms) {
  const std::vector<T>& x = p.x;
  return gapless_squared_sum(p, 2 * m, terms,
                             [&x, m](std::size_t i) { return x[i + 2 * m] - 2 * x[i + m] + x[i]; });
}

// Sum over j of S_j^2 (see full_deviation), the terms whose 3m - 1 samples have no gap.
template <typename T>
long double modified_sum(const Phase<T>& p, std::size_t m, std::uint64_t& terms) {
  const std::vector<T>& x = p.x;
  const std::size_t last = x.size() - 3 * m;  // j = 0 .. n + 1 - 3m
  typename Phase<T>::Sum s = 0;
  for (std::size_t i = 0; i < m; ++i) {
    s += static_cast<typename Phase<T>::Sum>(x[i + 2 * m] - 2 * x[i + m] + x[i]);
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
    s += static_cast<typename Phase<T>::Sum>(x[j + 3 * m] - 3 * x[j + 2 * m] + 3 * x[j + m] - x[j]);
  }
  return sum;
}

template <typename T>
long double hadamard_sum(const Phase<T>& p, std::size_t m, std::uint64_t& terms) {
  const std::vector<T>& x = p.x;
  return gapless_squared_sum(p, 3 * m, terms, [&x, m](std::size_t j) {
    return x[j + 3 * m] - 3 * x[j + 2 * m] + 3 * x[j + m] - x[j];
  });
}

// The deviation d at each m of the grid up to m_max, from the phase p; `scale` the unit of one
// phase step (the LSB for counts, 1 for values).
template <typename T>
std::vector<AdevRow> deviation_rows(const Phase<T>& p, Deviation d,
                                    const std::vector<std::uint64_t>& m, std::uint64_t m_max,
                                    double ts_s, double scale) {
  std::vector<AdevRow> rows;
  for (const std::uint64_t mm : m) {
    if (mm == 0 || mm > m_max) {
      continue;
    }
    const auto mi = static_cast<std::size_t>(mm);
    const double md = static_cast<double>(mm);
    std::uint64_t terms = 0;
    const long double sum = d == Deviation::kAdev   ? allan_sum(p, mi, terms)
                            : d == Deviation::kHdev ? hadamard_sum(p, mi, terms)
                                                    : modified_sum(p, mi, terms);
    if (terms == 0) {
      continue;
    }
    const double mean_sq = static_cast<double>(sum / static_cast<long double>(terms)) * scale * scale;
    if (d == Deviation::kAdev) {
      // stride 1: S = m
      rows.push_back(deviation_row(mm, ts_s, mean_sq / (2.0 * md * md),
                                   edf_greenhall(0, 2, md, md, static_cast<double>(terms)),
                                   terms));
      continue;
    }
    if (d == Deviation::kHdev) {
      rows.push_back(deviation_row(mm, ts_s, mean_sq / (6.0 * md * md),
                                   edf_greenhall(0, 3, md, md, static_cast<double>(terms)),
                                   terms));
      continue;
    }
    const double edf = edf_greenhall_modified(0, 2, md, md, static_cast<double>(terms));
    AdevRow r = deviation_row(mm, ts_s, mean_sq / (2.0 * md * md * md * md), edf, terms);
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

}  // namespace

void FullAdevSink::push(const std::int32_t* counts, std::size_t n) {
  counts_.insert(counts_.end(), counts, counts + n);
  gaps_.insert(gaps_.end(), n, 0);
}

void FullAdevSink::gap(std::size_t n) {
  if (values_mode_) {
    values_.insert(values_.end(), n, 0.0);
  } else {
    counts_.insert(counts_.end(), n, 0);
  }
  gaps_.insert(gaps_.end(), n, 1);
}

void FullAdevSink::push_values(const double* values, std::size_t n) {
  values_.insert(values_.end(), values, values + n);
  gaps_.insert(gaps_.end(), n, 0);
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
  const std::uint64_t m_max = deviation_max_af(d, data.size());
  if (data.takes_values()) {
    return deviation_rows(value_phase(data), d, m, m_max, ts_s, 1.0);
  }
  return deviation_rows(integer_phase(data), d, m, m_max, ts_s, lsb);
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

// Reader of ../shared/golden/oadev_*.csv (allantools oadev: af,tau_s,adev,n_terms,ci_lo,ci_hi),
// shared by the EDF test and the golden ADEV test.
#ifndef IMU_TESTS_GOLDEN_CSV_HPP
#define IMU_TESTS_GOLDEN_CSV_HPP

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace imu::test {

struct GoldenRow {
  double af = 0.0;
  double tau_s = 0.0;
  double adev = 0.0;
  double n_terms = 0.0;
  double lo = 0.0;
  double hi = 0.0;
};

inline std::vector<GoldenRow> read_golden(const std::string& path) {
  std::vector<GoldenRow> rows;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'a') {  // comments and the header row
      continue;
    }
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    GoldenRow r;
    is >> r.af >> r.tau_s >> r.adev >> r.n_terms >> r.lo >> r.hi;
    rows.push_back(r);
  }
  return rows;
}

}  // namespace imu::test

#endif  // IMU_TESTS_GOLDEN_CSV_HPP

// Text input (see imu/cli/text_input.hpp).
#include "imu/cli/text_input.hpp"

#include "imu/cli/args.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace imu::cli {
namespace {

// Fields of a line: split at `delim`, or at runs of blanks when delim is ' '.
std::vector<std::string> split(const std::string& line, char delim) {
  std::vector<std::string> out;
  if (delim == ' ') {
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) {
        ++i;
      }
      std::size_t j = i;
      while (j < line.size() && line[j] != ' ' && line[j] != '\t') {
        ++j;
      }
      if (j > i) {
        out.push_back(line.substr(i, j - i));
      }
      i = j;
    }
    return out;
  }
  std::size_t i = 0;
  while (true) {
    const std::size_t j = line.find(delim, i);
    std::string f = line.substr(i, j == std::string::npos ? std::string::npos : j - i);
    const auto b = f.find_first_not_of(" \t\"");
    const auto e = f.find_last_not_of(" \t\"");
    out.push_back(b == std::string::npos ? std::string() : f.substr(b, e - b + 1));
    if (j == std::string::npos) {
      return out;
    }
    i = j + 1;
  }
}

bool parse_field(const std::string& f, double& v) {
  if (f.empty() || f == "nan" || f == "NaN" || f == "NAN") {
    v = std::nan("");
    return true;
  }
  char* end = nullptr;
  errno = 0;
  v = std::strtod(f.c_str(), &end);
  return end != f.c_str() && *end == '\0' && errno != ERANGE;
}

}  // namespace

bool looks_like_text(const std::string& path) {
  // A MAT-file starts with "MATLAB" text or carries its endian mark "IM"/"MI" at byte 126; any
  // NUL byte in the first 512 makes it binary too (the MAT reader then says what is wrong).
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    return false;  // never open a FIFO or a device to look (the MAT reader refuses it by stat)
  }
  std::ifstream f(path, std::ios::binary);
  char head[512] = {};
  f.read(head, sizeof head);
  const auto n = static_cast<std::size_t>(f.gcount());
  if (n >= 6 && std::memcmp(head, "MATLAB", 6) == 0) {
    return false;
  }
  if (n >= 128 && ((head[126] == 'I' && head[127] == 'M') || (head[126] == 'M' && head[127] == 'I'))) {
    return false;
  }
  return n > 0 && std::memchr(head, '\0', n) == nullptr;
}

bool read_text_table(const std::string& path, TextTable& table, std::string& err,
                     std::uint64_t max_bytes) {
  table = TextTable{};
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    err = path + ": " + std::strerror(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    err = path + ": not a regular file";
    return false;
  }
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
    err = path + ": " + std::to_string(st.st_size) + " bytes of text, above the " +
          std::to_string(max_bytes) + "-byte limit";
    return false;
  }
  std::ifstream f(path);
  std::string line;
  std::uint64_t line_no = 0;
  char delim = ' ';
  while (std::getline(f, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') {
      line.pop_back();
    }
    if (line.empty() || line[0] == '#') {
      continue;
    }
    if (table.names.empty()) {
      delim = line.find(',') != std::string::npos ? ',' : (line.find('\t') != std::string::npos
                                                               ? '\t' : ' ');
      table.names = split(line, delim);
      double probe = 0.0;
      for (const auto& n : table.names) {
        if (n.empty() || parse_field(n, probe)) {
          err = path + ": line " + std::to_string(line_no) +
                ": the first row must name the columns (a header), e.g. t,acc_x,acc_y";
          return false;
        }
      }
      table.cols.assign(table.names.size(), {});
      continue;
    }
    const std::vector<std::string> fields = split(line, delim);
    if (fields.size() != table.names.size()) {
      err = path + ": line " + std::to_string(line_no) + " has " + std::to_string(fields.size()) +
            " fields, the header " + std::to_string(table.names.size());
      return false;
    }
    for (std::size_t c = 0; c < fields.size(); ++c) {
      double v = 0.0;
      if (!parse_field(fields[c], v)) {
        err = path + ": line " + std::to_string(line_no) + ", column " + table.names[c] + ": '" +
              fields[c] + "' is not a number";
        return false;
      }
      table.cols[c].push_back(v);
    }
  }
  if (table.names.empty() || table.cols[0].empty()) {
    err = path + ": no header and data rows (text input: a header row, then one row per sample)";
    return false;
  }
  return true;
}

bool text_channel(const TextTable& table, const std::string& name, double fs_hz,
                  TextChannel& out, std::string& err) {
  out = TextChannel{};
  std::size_t ci = table.names.size();
  std::size_t ti = table.names.size();
  for (std::size_t c = 0; c < table.names.size(); ++c) {
    ci = table.names[c] == name ? c : ci;
    const std::string& n = table.names[c];
    if (ti == table.names.size() && (n == "t" || n == "time" || n == "timestamp")) {
      ti = c;
    }
  }
  if (ci == table.names.size()) {
    std::string held;
    for (const auto& n : table.names) {
      held += (held.empty() ? "" : ", ") + n;
    }
    err = "no column '" + name + "'; the columns: " + held;
    return false;
  }
  const std::vector<double>& v = table.cols[ci];
  if (ti == table.names.size()) {
    if (!(fs_hz > 0.0)) {
      err = "no --fs and no time column (t, time or timestamp) to take the rate from";
      return false;
    }
    out.samples = v;
    out.fs_hz = fs_hz;
    return true;
  }
  const std::vector<double>& t = table.cols[ti];
  out.time_column = table.names[ti];
  std::vector<double> steps;
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (!(t[i] > t[i - 1])) {
      err = "the time column '" + table.names[ti] + "' does not increase at row " +
            std::to_string(i + 1) + " (" + std::to_string(t[i - 1]) + " then " +
            std::to_string(t[i]) + ")";
      return false;
    }
    steps.push_back(t[i] - t[i - 1]);
  }
  double ts = 0.0;
  if (fs_hz > 0.0) {
    ts = 1.0 / fs_hz;
  } else {
    if (steps.empty()) {
      err = "one row: no rate from the time column";
      return false;
    }
    std::vector<double> s = steps;
    std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2), s.end());
    ts = s[s.size() / 2];
  }
  out.fs_hz = 1.0 / ts;
  out.samples.reserve(v.size());
  out.samples.push_back(v[0]);
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double k = std::round(steps[i - 1] / ts);
    if (k >= 2.0) {
      if (k > 1e8) {
        err = "the time column jumps by " + std::to_string(steps[i - 1]) + " s at row " +
              std::to_string(i + 1) + ": more than 1e8 missing samples";
        return false;
      }
      const auto missing = static_cast<std::uint64_t>(k) - 1;
      out.samples.insert(out.samples.end(), missing, std::nan(""));
      out.time_gap_samples += missing;
    }
    out.samples.push_back(v[i]);
  }
  return true;
}

bool text_channels(const TextTable& table, const std::string& spec,
                   std::vector<std::string>& out, std::string& err) {
  if (expand_channels(spec, table.names, out, err)) {
    return true;
  }
  if (spec != "all") {
    return false;
  }
  for (const auto& n : table.names) {
    if (n != "t" && n != "time" && n != "timestamp") {
      out.push_back(n);
    }
  }
  if (out.empty()) {
    return false;  // err: expand_channels' (the file holds no channel column)
  }
  err.clear();
  return true;
}

}  // namespace imu::cli

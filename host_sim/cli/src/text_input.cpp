// Text input (see imu/cli/text_input.hpp).
#include "imu/cli/text_input.hpp"

#include "imu/cli/args.hpp"
#include "imu/cli/json.hpp"
#include "imu/cli/rosbag.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
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

// A line without data: empty, blanks only, or a comment ('#' first).
bool blank_or_comment(const std::string& line) {
  const std::size_t i = line.find_first_not_of(" \t");
  return i == std::string::npos || line[0] == '#';
}

// A header field's name and unit: "w_RS_S_x [rad s^-1]" is w_RS_S_x in rad s^-1 (EuRoC's
// layout); a bracket or parenthesis after a blank, at the end, is the unit. "gyro_rad[0]" (an
// index, no blank) stays the name.
std::pair<std::string, std::string> name_and_unit(const std::string& field) {
  const std::size_t n = field.size();
  if (n >= 3 && (field[n - 1] == ']' || field[n - 1] == ')')) {
    const char open = field[n - 1] == ']' ? '[' : '(';
    const std::size_t at = field.rfind(open);
    if (at != std::string::npos && at > 0 && (field[at - 1] == ' ' || field[at - 1] == '\t')) {
      const std::size_t end = field.find_last_not_of(" \t", at - 1);
      if (end != std::string::npos) {
        return {field.substr(0, end + 1), field.substr(at + 1, n - at - 2)};
      }
    }
  }
  return {field, std::string()};
}

// An integer field ("1403636579758555392"): its exact value. Epoch nanoseconds need all 19
// digits; as a double their steps would be off by up to 256 ns.
bool parse_integer(const std::string& f, long long& v) {
  if (f.empty() || f.size() > 19 || f.find_first_not_of("+-0123456789") != std::string::npos) {
    return false;
  }
  char* end = nullptr;
  errno = 0;
  v = std::strtoll(f.c_str(), &end, 10);
  return end != f.c_str() && *end == '\0' && errno != ERANGE;
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

// A row of names: every field present and not a number.
bool names_row(const std::vector<std::string>& fields) {
  double probe = 0.0;
  for (const auto& n : fields) {
    if (n.empty() || parse_field(n, probe)) {
      return false;
    }
  }
  return !fields.empty();
}

}  // namespace

bool time_unit_option(const Args& a, double& unit_s, std::string& err) {
  unit_s = 0.0;
  if (!a.has("--time-unit")) {
    return true;
  }
  unit_s = time_unit_s(a.get("--time-unit"));
  if (!(unit_s > 0.0)) {
    err = "--time-unit " + a.get("--time-unit") + ": s, ms, us or ns";
    return false;
  }
  return true;
}

double time_unit_s(const std::string& unit) {
  static const std::pair<const char*, double> kUnits[] = {
      {"s", 1.0},     {"sec", 1.0},    {"seconds", 1.0}, {"ms", 1e-3},   {"msec", 1e-3},
      {"us", 1e-6},   {"usec", 1e-6},  {"\xc2\xb5s", 1e-6}, {"ns", 1e-9},   {"nsec", 1e-9}};
  for (const auto& [name, s] : kUnits) {
    if (unit == name) {
      return s;
    }
  }
  return 0.0;
}

bool is_time_name(const std::string& name, double* unit_s) {
  double u = 0.0;
  if (name == "t" || name == "time" || name == "timestamp" || name == "%time") {
    u = 0.0;  // the unit from the header or the steps
  } else {
    const std::size_t us = name.rfind('_');
    if (us == std::string::npos) {
      return false;
    }
    const std::string stem = name.substr(0, us);
    u = time_unit_s(name.substr(us + 1));
    if ((stem != "t" && stem != "time" && stem != "timestamp") || !(u > 0.0)) {
      return false;
    }
  }
  if (unit_s != nullptr) {
    *unit_s = u;
  }
  return true;
}

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

int TextRows::read_line(std::string& err) {
  line_.clear();
  std::streambuf* sb = in_.rdbuf();
  bool any = false;
  for (;;) {
    const int c = sb->sbumpc();
    if (c == std::char_traits<char>::eof()) {
      return any ? 1 : 0;
    }
    any = true;
    if (c == '\n') {
      break;
    }
    if (line_.size() >= kMaxLineBytes) {
      err = path_ + ": line " + std::to_string(line_no_ + 1) + " is longer than " +
            std::to_string(kMaxLineBytes) + " bytes (text input: one row per sample)";
      return -1;
    }
    line_.push_back(static_cast<char>(c));
  }
  ++line_no_;
  if (!line_.empty() && line_.back() == '\r') {
    line_.pop_back();
  }
  return 1;
}

bool TextRows::open(const std::string& path, std::string& err, std::uint64_t max_bytes) {
  path_ = path;
  names_.clear();
  line_no_ = 0;
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
  in_.close();
  in_.clear();
  in_.open(path, std::ios::binary);
  pending_ = false;
  needed_.clear();
  exact_column_ = kNoColumn;
  err.clear();
  std::string last_comment;
  int got = 0;
  while ((got = read_line(err)) > 0) {
    if (blank_or_comment(line_)) {
      if (!line_.empty() && line_[0] == '#') {
        last_comment = line_;
      }
      continue;
    }
    delim_ = line_.find(',') != std::string::npos ? ','
             : (line_.find('\t') != std::string::npos ? '\t' : ' ');
    std::vector<std::string> fields = split(line_, delim_);
    if (fields.size() > kMaxColumns) {
      err = path + ": line " + std::to_string(line_no_) + ": " + std::to_string(fields.size()) +
            " columns, more than " + std::to_string(kMaxColumns) + " (text input of IMU channels)";
      return false;
    }
    if (!names_row(fields)) {
      // EuRoC and other loggers put the names in the last comment line before the data
      // ("#timestamp [ns],w_RS_S_x [rad s^-1],..."): that line, if it names every column.
      std::vector<std::string> named;
      if (!last_comment.empty()) {
        const std::size_t b = last_comment.find_first_not_of("# \t");
        named = split(b == std::string::npos ? std::string() : last_comment.substr(b), delim_);
      }
      if (named.size() != fields.size() || !names_row(named)) {
        err = path + ": line " + std::to_string(line_no_) +
              ": the first row must name the columns (a header, or a last '#' comment line "
              "before the data with one name per column), e.g. t,acc_x,acc_y";
        return false;
      }
      fields = named;
      pending_ = true;  // line_ is the first data row
    }
    names_.clear();
    units_.clear();
    for (const auto& f : fields) {
      auto nu = name_and_unit(f);
      names_.push_back(std::move(nu.first));
      units_.push_back(std::move(nu.second));
    }
    return true;
  }
  if (got < 0) {
    return false;
  }
  err = path + ": no header and data rows (text input: a header row, then one row per sample)";
  return false;
}

void TextRows::only(const std::vector<std::size_t>& columns) {
  needed_.assign(names_.size(), false);
  for (const std::size_t c : columns) {
    if (c < needed_.size()) {
      needed_[c] = true;
    }
  }
}

bool TextRows::next(std::vector<double>& row, std::string& err) {
  err.clear();
  while (pending_ || read_line(err) > 0) {
    pending_ = false;
    if (blank_or_comment(line_)) {
      continue;
    }
    const std::vector<std::string> fields = split(line_, delim_);
    if (fields.size() != names_.size()) {
      err = path_ + ": line " + std::to_string(line_no_) + " has " +
            std::to_string(fields.size()) + " fields, the header " +
            std::to_string(names_.size());
      return false;
    }
    row.resize(fields.size());
    has_exact_ = exact_column_ < fields.size() && parse_integer(fields[exact_column_], exact_);
    for (std::size_t c = 0; c < fields.size(); ++c) {
      if (!needed_.empty() && !needed_[c]) {
        row[c] = std::nan("");  // a column not read (a frame name, a covariance): not parsed
        continue;
      }
      if (!parse_field(fields[c], row[c])) {
        err = path_ + ": line " + std::to_string(line_no_) + ", column " + names_[c] + ": '" +
              fields[c] + "' is not a number";
        return false;
      }
    }
    return true;
  }
  return false;
}

bool read_text_table(const std::string& path, TextTable& table, std::string& err,
                     std::uint64_t max_bytes) {
  table = TextTable{};
  TextRows rows;
  if (!rows.open(path, err, max_bytes)) {
    return false;
  }
  table.names = rows.names();
  table.units = rows.units();
  table.cols.assign(table.names.size(), {});
  std::vector<double> row;
  while (rows.next(row, err)) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      table.cols[c].push_back(row[c]);
    }
  }
  if (!err.empty()) {
    return false;
  }
  if (table.cols[0].empty()) {
    err = path + ": no header and data rows (text input: a header row, then one row per sample)";
    return false;
  }
  return true;
}

std::size_t time_column(const std::vector<std::string>& names) {
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (is_time_name(names[c], nullptr)) {
      return c;
    }
  }
  return names.size();
}

namespace {

// The median of the steps t[i] - t[i-1] > 0 over t[0..n); 0 if there is none.
double median_step(const double* t, std::size_t n) {
  std::vector<double> steps;
  steps.reserve(n);
  for (std::size_t i = 1; i < n; ++i) {
    if (t[i] > t[i - 1]) {
      steps.push_back(t[i] - t[i - 1]);
    }
  }
  if (steps.empty()) {
    return 0.0;
  }
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2),
                   steps.end());
  return steps[steps.size() / 2];
}

}  // namespace

void time_scale(const double* t, std::size_t n, double fs_hz, double stated_s, double& unit_s,
                bool& detected) {
  detected = false;
  unit_s = stated_s > 0.0 ? stated_s : 1.0;
  if (stated_s > 0.0) {
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t[i]) || std::fabs(t[i] - std::floor(t[i])) > 0.0) {
      return;  // times that are not all integers are seconds
    }
  }
  const double median = median_step(t, n);
  if (!(median > 0.0)) {
    return;
  }
  static constexpr double kUnits[] = {1.0, 1e-3, 1e-6, 1e-9};
  for (const double u : kUnits) {
    // A given rate picks the unit it agrees with; else the first unit in which the steps are an
    // IMU's rate.
    if (fs_hz > 0.0 ? std::fabs(median * u * fs_hz - 1.0) <= 0.02
                    : 1.0 / (median * u) >= kMinDetectedRateHz) {
      unit_s = u;
      detected = u < 1.0;
      return;
    }
  }
}

namespace {

// The sample period from the first rows' times (t[0..n)): fs_hz if given, else the median
// step. False with err: one row, or a time that does not increase (as TimeGrid says it).
bool grid_period(const double* t, std::size_t n, double fs_hz, const std::string& column,
                 double& ts_s, std::string& err) {
  for (std::size_t i = 1; i < n; ++i) {
    if (!(t[i] > t[i - 1])) {
      err = "the time column '" + column + "' does not increase at row " + std::to_string(i + 1) +
            " (" + num_text(t[i - 1]) + " then " + num_text(t[i]) + ")";
      return false;
    }
  }
  if (n < 2) {
    if (fs_hz > 0.0) {
      ts_s = 1.0 / fs_hz;
      return true;
    }
    err = "one row: no rate from the time column";
    return false;
  }
  const double median_s = median_step(t, n);
  if (fs_hz > 0.0) {
    // A given rate must agree with the time column it places the samples by.
    if (!(std::fabs(median_s * fs_hz - 1.0) <= 0.02)) {
      err = "--fs " + num_text(fs_hz) + " Hz contradicts the time column '" + column +
            "': its median step " + num_text(median_s) + " s is " + num_text(1.0 / median_s) +
            " Hz (drop --fs, or give the column's rate or its unit with --time-unit)";
      return false;
    }
    ts_s = 1.0 / fs_hz;
    return true;
  }
  ts_s = median_s;
  return true;
}

// The clock of a time column from its first raw times: the unit (stated_s if > 0, else
// time_scale's), the first time (the origin: epoch nanoseconds keep their steps), and the
// sample period (grid_period over the times in seconds). A note when the unit was detected.
bool head_clock(const std::vector<double>& raw, double fs_hz, double stated_s,
                const std::string& column, double& ts_s, double& unit_s, double& t0,
                std::string& note, std::string& err) {
  bool detected = false;
  time_scale(raw.data(), raw.size(), fs_hz, stated_s, unit_s, detected);
  t0 = raw.empty() ? 0.0 : raw[0];
  std::vector<double> t(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    t[i] = (raw[i] - t0) * unit_s;
  }
  note.clear();
  if (detected) {
    const char* name = unit_s > 5e-4 ? "ms" : (unit_s > 5e-7 ? "us" : "ns");
    note = std::string("the time column '") + column + "' read in " + name +
           " (from its steps; --time-unit s|ms|us|ns says otherwise)";
  }
  return grid_period(t.data(), t.size(), fs_hz, column, ts_s, err);
}

// The unit a time column states: stated_s (an option) if > 0, else its name's suffix
// (timestamp_ns), else its header's bracketed unit ([ns]); 0 if none.
double stated_unit(const std::string& name, const std::string& header_unit, double stated_s) {
  double u = 0.0;
  if (stated_s > 0.0) {
    return stated_s;
  }
  if (is_time_name(name, &u) && u > 0.0) {
    return u;
  }
  return time_unit_s(header_unit);
}

std::string no_column(const std::vector<std::string>& names, const std::string& name) {
  std::string held;
  for (const auto& n : names) {
    held += (held.empty() ? "" : ", ") + n;
  }
  return "no column '" + name + "'; the columns: " + held;
}

}  // namespace

bool TimeGrid::place(double t_s, std::uint64_t row, const std::string& column,
                     std::uint64_t& missing, std::string& err) {
  missing = 0;
  if (!started_) {
    started_ = true;
    last_t_s_ = t_s;
    return true;
  }
  if (!(t_s > last_t_s_)) {
    err = "the time column '" + column + "' does not increase at row " + std::to_string(row) +
          " (" + num_text(last_t_s_) + " then " + num_text(t_s) + ")";
    return false;
  }
  const double step = t_s - last_t_s_;
  const double periods = step / ts_s_;
  const double k = std::round(periods);
  const std::string at = "the time column '" + column + "' steps by " + num_text(step) +
                         " s at row " + std::to_string(row);
  if (k < 1.0) {
    err = at + ", under half the sample period " + num_text(ts_s_) + " s (" +
          num_text(1.0 / ts_s_) + " Hz): the rate rises there (split the file at that row)";
    return false;
  }
  if (std::fabs(periods - k) > kJitterPeriods &&
      ++off_grid_ > 16 + row / 100) {
    err = "the time column '" + column + "' is too irregular for one rate: " +
          std::to_string(off_grid_) + " of its first " + std::to_string(row) +
          " steps are off the " + num_text(ts_s_) + " s grid by more than " +
          num_text(kJitterPeriods) + " period (resample the log to a constant rate)";
    return false;
  }
  if (k >= 2.0) {
    // (a step of more periods than 2^62 is a gap like any other: one run key for all of them)
    const auto whole = static_cast<std::uint64_t>(std::min(k, 4.6e18));
    run_ = whole == run_k_ ? run_ + 1 : 1;
    run_k_ = whole;
    if (run_ >= kRateRunSteps) {
      err = "the time column '" + column + "' changes rate: rows " +
            std::to_string(row - run_) + " to " + std::to_string(row) + " step by " +
            num_text(k) + " sample periods each (" + num_text(1.0 / (k * ts_s_)) +
            " Hz), the record's median step is " + num_text(ts_s_) + " s (" +
            num_text(1.0 / ts_s_) + " Hz): split the file where the rate changes";
      return false;
    }
    const double cap = static_cast<double>(kGapAllowance) + 4.0 * static_cast<double>(row);
    if (static_cast<double>(gap_samples_) + (k - 1.0) > cap) {
      err = at + ": the gaps would fill in " + num_text(static_cast<double>(gap_samples_) + k - 1.0) +
            " missing samples by then, more than " + num_text(cap) +
            " (2^20 + 4 per row; split the file at its long gaps)";
      return false;
    }
    missing = static_cast<std::uint64_t>(k) - 1;
    gap_samples_ += missing;
  } else {
    run_ = 0;
  }
  last_t_s_ = t_s;
  return true;
}

bool text_channel(const TextTable& table, const std::string& name, double fs_hz,
                  TextChannel& out, std::string& err, double time_unit_s_given) {
  out = TextChannel{};
  const auto it = std::find(table.names.begin(), table.names.end(), name);
  if (it == table.names.end()) {
    err = no_column(table.names, name);
    return false;
  }
  const std::vector<double>& v = table.cols[static_cast<std::size_t>(it - table.names.begin())];
  const std::size_t ti = time_column(table.names);
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
  double ts = 0.0;
  double t0 = 0.0;
  const std::vector<double> head(t.begin(),
                                 t.begin() + static_cast<std::ptrdiff_t>(std::min(t.size(), kRateRows + 1)));
  const double stated =
      stated_unit(out.time_column, ti < table.units.size() ? table.units[ti] : std::string(),
                  time_unit_s_given);
  if (!head_clock(head, fs_hz, stated, out.time_column, ts, out.time_unit_s, t0, out.time_note,
                  err)) {
    return false;
  }
  out.fs_hz = 1.0 / ts;
  TimeGrid grid(ts);
  out.samples.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::uint64_t missing = 0;
    if (!grid.place((t[i] - t0) * out.time_unit_s, i + 1, out.time_column, missing, err)) {
      return false;
    }
    out.samples.insert(out.samples.end(), missing, std::nan(""));
    out.samples.push_back(v[i]);
  }
  out.time_gap_samples = grid.gap_samples();
  return true;
}

bool TextColumnStream::open(const std::string& path, const std::string& name, double fs_hz,
                            std::string& err, double time_unit_s_given, const std::string& topic) {
  return open(path, std::vector<std::string>{name}, fs_hz, err, time_unit_s_given, topic);
}

std::unique_ptr<RowSource> open_rows(const std::string& path, const std::string& topic,
                                     std::string& err) {
  if (looks_like_bag(path)) {
    auto bag = std::make_unique<BagRows>();
    if (!bag->open(path, topic, err)) {
      return nullptr;
    }
    return bag;
  }
  if (!topic.empty()) {
    err = "--topic " + topic + ": " + path + " is not a ROS bag (--topic reads one)";
    return nullptr;
  }
  auto text = std::make_unique<TextRows>();
  if (!text->open(path, err)) {
    return nullptr;
  }
  return text;
}

double TextColumnStream::raw_time() {
  if (time_ >= row_.size()) {
    return 0.0;
  }
  if (!have_origin_) {
    have_origin_ = true;
    origin_exact_ = rows_->has_exact();
    origin_i_ = rows_->exact();
    origin_ = row_[time_];
  }
  // From the first row: exactly when both are integers (epoch nanoseconds), else in double.
  return origin_exact_ && rows_->has_exact() ? static_cast<double>(rows_->exact() - origin_i_)
                                             : row_[time_] - origin_;
}

void TextColumnStream::hold(std::vector<double>& to) {
  to.push_back(raw_time());  // in the column's unit: the clock is known later
  for (const std::size_t c : cols_) {
    to.push_back(row_[c]);
  }
}

bool TextColumnStream::open(const std::string& path, const std::vector<std::string>& names_in,
                            double fs_hz, std::string& err, double time_unit_s_given,
                            const std::string& topic) {
  head_pos_ = 0;
  row_no_ = 0;
  pending_missing_ = 0;
  have_pending_ = false;
  time_name_.clear();
  time_note_.clear();
  unit_s_ = 1.0;
  have_origin_ = false;
  cols_.clear();
  rows_ = open_rows(path, topic, err);
  if (rows_ == nullptr) {
    return false;
  }
  source_ = rows_->origin();
  const std::vector<std::string>& names = rows_->names();
  std::string column_err;
  for (const auto& name : names_in) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) {
      column_err = no_column(names, name);
      break;
    }
    cols_.push_back(static_cast<std::size_t>(it - names.begin()));
  }
  time_ = time_column(names);
  std::vector<std::size_t> read_cols = cols_;
  read_cols.push_back(time_);
  rows_->only(read_cols);  // the other columns (a frame name, covariances) are not parsed
  rows_->exact_integers(time_);
  // A file without data rows is refused as such before its columns are looked at (as
  // read_text_table refuses it before text_channel).
  const bool first = rows_->next(row_, err);
  if (!first && err.empty()) {
    err = path + ": no header and data rows (text input: a header row, then one row per sample)";
  }
  if (!first) {
    return false;
  }
  if (!column_err.empty()) {
    err = column_err;
    return false;
  }
  if (cols_.empty()) {
    err = "no column asked for";
    return false;
  }
  pending_values_.assign(cols_.size(), 0.0);
  values_.assign(cols_.size(), 0.0);
  if (time_ == names.size() && !(fs_hz > 0.0)) {
    err = "no --fs and no time column (t, time or timestamp) to take the rate from";
    return false;
  }
  // The rows that decide the rate (as text_channel's), held until they are given out.
  const std::size_t stride = cols_.size() + 1;
  head_.clear();
  hold(head_);
  while (head_.size() < (kRateRows + 1) * stride && rows_->next(row_, err)) {
    hold(head_);
  }
  if (!err.empty()) {
    return false;
  }
  double ts = fs_hz > 0.0 ? 1.0 / fs_hz : 0.0;
  if (time_ < names.size()) {
    time_name_ = names[time_];
    std::vector<double> raw(head_.size() / stride);
    for (std::size_t i = 0; i < raw.size(); ++i) {
      raw[i] = head_[i * stride];
    }
    const double stated = stated_unit(time_name_, rows_->units()[time_], time_unit_s_given);
    double t0 = 0.0;  // 0: raw_time() is already from the first row
    if (!head_clock(raw, fs_hz, stated, time_name_, ts, unit_s_, t0, time_note_, err)) {
      return false;
    }
  }
  const std::string source_note = rows_->note();
  if (!source_note.empty()) {
    time_note_ = source_note + (time_note_.empty() ? "" : "; " + time_note_);
  }
  fs_hz_ = 1.0 / ts;
  grid_ = TimeGrid(ts);
  return true;
}

bool TextColumnStream::next_row(double& t, bool& have, std::string& err) {
  have = false;
  const std::size_t k = cols_.size();
  if (head_pos_ < head_.size() / (k + 1)) {
    const double* r = head_.data() + head_pos_ * (k + 1);
    t = r[0] * unit_s_;
    std::copy(r + 1, r + 1 + k, values_.begin());
    have = true;
    if (++head_pos_ == head_.size() / (k + 1)) {
      head_ = {};  // the rate is known: hold no more rows
    }
    return true;
  }
  if (head_pos_ > 0 && head_.empty() && rows_->next(row_, err)) {
    t = raw_time() * unit_s_;
    for (std::size_t c = 0; c < k; ++c) {
      values_[c] = row_[cols_[c]];
    }
    have = true;
  }
  return err.empty();
}

bool TextColumnStream::read(double* out, std::size_t n, std::size_t& got, std::string& err) {
  got = 0;
  const std::size_t k = cols_.size();
  while (got < n) {
    if (pending_missing_ > 0) {
      std::fill(out + got * k, out + (got + 1) * k, std::nan(""));
      ++got;
      --pending_missing_;
      continue;
    }
    if (have_pending_) {
      std::copy(pending_values_.begin(), pending_values_.end(), out + got * k);
      ++got;
      have_pending_ = false;
      continue;
    }
    double t = 0.0;
    bool have = false;
    if (!next_row(t, have, err)) {
      return false;
    }
    if (!have) {
      break;
    }
    ++row_no_;
    std::uint64_t missing = 0;
    if (!time_name_.empty() && !grid_.place(t, row_no_, time_name_, missing, err)) {
      return false;
    }
    pending_missing_ = missing;
    pending_values_.swap(values_);
    have_pending_ = true;
  }
  return true;
}

bool text_channels(const std::vector<std::string>& names, const std::string& spec,
                   std::vector<std::string>& out, std::string& err) {
  if (expand_channels(spec, names, out, err)) {
    return true;
  }
  if (spec != "all") {
    return false;
  }
  for (const auto& n : names) {
    if (!is_time_name(n, nullptr)) {
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

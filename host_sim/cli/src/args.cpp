// The shared command-line parser (see imu/cli/args.hpp).
#include "imu/cli/args.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <system_error>
#include <thread>

namespace imu::cli {
namespace {

// "1e-06" rather than "0.000001" in messages about ranges.
std::string num_text(double v) {
  char buf[32];
  (void)std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool is_option_like(const std::string& a) { return a.size() > 1 && a[0] == '-'; }

// Edit distance with adjacent transpositions (optimal string alignment): "adve" is 1 from
// "adev". Names are short: a full table.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  const std::size_t w = b.size() + 1;
  std::vector<std::size_t> d((a.size() + 1) * w);
  for (std::size_t i = 0; i <= a.size(); ++i) {
    d[i * w] = i;
  }
  for (std::size_t j = 0; j <= b.size(); ++j) {
    d[j] = j;
  }
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0U : 1U;
      std::size_t v = std::min({d[(i - 1) * w + j] + 1, d[i * w + j - 1] + 1,
                                d[(i - 1) * w + j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        v = std::min(v, d[(i - 2) * w + j - 2] + 1);
      }
      d[i * w + j] = v;
    }
  }
  return d[a.size() * w + b.size()];
}

}  // namespace

std::string closest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::max<std::size_t>(1, word.size() / 3) + 1;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

bool Args::parse(int argc, char** argv, int first, const std::vector<OptSpec>& specs,
                 std::size_t max_positional, std::string& err) {
  for (int i = first; i < argc; ++i) {
    if (std::string(argv[i]) == "-h" || std::string(argv[i]) == "--help") {
      help_ = true;
      return true;
    }
  }
  for (int i = first; i < argc; ++i) {
    const std::string a = argv[i];
    if (!is_option_like(a)) {
      if (pos_.size() >= max_positional) {
        err = "unexpected argument '" + a + "'";
        return false;
      }
      pos_.push_back(a);
      continue;
    }
    std::string name = a;
    std::string value;
    const std::size_t eq = a.find('=');
    const bool inline_value = eq != std::string::npos;
    if (inline_value) {
      name = a.substr(0, eq);
      value = a.substr(eq + 1);
    }
    const OptSpec* spec = nullptr;
    for (const OptSpec& s : specs) {
      if (name == s.name) {
        spec = &s;
      }
    }
    if (spec == nullptr) {
      std::vector<std::string> names;
      names.reserve(specs.size());
      for (const OptSpec& o : specs) {
        names.emplace_back(o.name);
      }
      const std::string near = closest(name, names);
      err = "unknown option '" + name + "'" + (near.empty() ? "" : "; did you mean " + near + "?");
      return false;
    }
    if (spec->has_value && !inline_value) {
      if (i + 1 >= argc) {
        err = "option '" + name + "' needs a value";
        return false;
      }
      value = argv[++i];
    } else if (!spec->has_value && inline_value) {
      err = "option '" + name + "' takes no value";
      return false;
    }
    opts_[name] = value;
  }
  return true;
}

std::string Args::get(const std::string& name, const std::string& def) const {
  const auto it = opts_.find(name);
  return it == opts_.end() ? def : it->second;
}

bool Args::number(const std::string& name, double def, double lo, double hi, double& out,
                  std::string& err) const {
  const auto it = opts_.find(name);
  if (it == opts_.end()) {
    out = def;
    return true;
  }
  const char* s = it->second.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s, &end);
  if (end == s || *end != '\0' || !std::isfinite(v)) {
    err = "option '" + name + "': '" + it->second + "' is not a number";
    return false;
  }
  if (!(v >= lo && v <= hi)) {
    err = "option '" + name + "': " + it->second + " is out of range [" + num_text(lo) + ", " +
          num_text(hi) + "]";
    return false;
  }
  out = v;
  return true;
}

bool Args::number(const std::string& name, double def, double& out, std::string& err) const {
  constexpr double kMax = std::numeric_limits<double>::max();
  return number(name, def, -kMax, kMax, out, err);
}

bool Args::integer(const std::string& name, std::uint64_t def, std::uint64_t lo,
                   std::uint64_t hi, std::uint64_t& out, std::string& err) const {
  double v = 0.0;
  if (!number(name, static_cast<double>(def), static_cast<double>(lo), static_cast<double>(hi),
              v, err)) {
    return false;
  }
  if (std::floor(v) < v) {
    err = "option '" + name + "': '" + get(name) + "' is not an integer";
    return false;
  }
  out = static_cast<std::uint64_t>(v);  // in [lo, hi] <= 2^53: exact
  return true;
}

bool parse_channel_spec(const std::string& text, ChannelSpec& out, std::string& err) {
  out = ChannelSpec{};
  out.name = text;
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos) {
    return true;
  }
  const std::string k = text.substr(colon + 1);
  char* end = nullptr;
  const unsigned long v = std::strtoul(k.c_str(), &end, 10);
  if (k.empty() || end == nullptr || *end != '\0' || v < 1 || v > 1000000) {
    err = "--channel " + text + ": the column after ':' must be a number in [1, 1e6]";
    return false;
  }
  out.name = text.substr(0, colon);
  out.column = static_cast<std::size_t>(v - 1);
  out.has_column = true;
  return true;
}

std::vector<std::string> lsb_candidates(const std::string& channel) {
  const std::string name = channel.substr(0, channel.rfind(':'));  // NAME:K -> NAME
  const std::size_t dot = name.rfind('.');
  const std::string field = dot == std::string::npos ? name : name.substr(dot + 1);
  const std::size_t us = field.find('_');
  std::vector<std::string> own;
  if (us != std::string::npos && us > 0) {
    own.push_back(field.substr(0, us) + "_lsb");
  }
  own.push_back(field + "_lsb");
  own.emplace_back("lsb");
  std::vector<std::string> out;
  if (dot != std::string::npos) {
    for (const auto& n : own) {
      out.push_back(name.substr(0, dot + 1) + n);
    }
  }
  out.insert(out.end(), own.begin(), own.end());
  return out;
}

bool file_lsb(const std::string& channel, const std::string& file,
              const std::function<bool(const std::string&)>& held,
              const std::function<bool(const std::string&, double&, std::string&)>& read,
              double& lsb, std::string& err) {
  lsb = 0.0;
  for (const std::string& cand : lsb_candidates(channel)) {
    const bool in_struct = cand.find('.') != std::string::npos;
    if (!in_struct && !held(cand)) {
      continue;
    }
    double v = 0.0;
    std::string read_err;
    if (!read(cand, v, read_err)) {
      if (in_struct) {
        continue;  // the struct has no such field
      }
      err = read_err;
      return false;
    }
    if (!(v > 0.0) || !std::isfinite(v)) {
      err = file;
      err += ": ";
      err += cand;
      err += " is not a positive number";
      return false;
    }
    lsb = v;
    return true;
  }
  return true;
}

bool expand_channels(const std::string& spec, const std::vector<std::string>& held,
                     std::vector<std::string>& out, std::string& err) {
  out.clear();
  if (spec == "all") {
    for (const char* name : kImuChannelNames) {
      if (std::find(held.begin(), held.end(), name) != held.end()) {
        out.emplace_back(name);
      }
    }
    if (out.empty()) {
      std::string list;
      for (const auto& h : held) {
        list += (list.empty() ? "" : ", ") + h;
      }
      err = "--channel all: none of acc_x..gyro_z in the file (it holds: " + list +
            "); name the channels";
      return false;
    }
    return true;
  }
  std::size_t pos = 0;
  for (;;) {
    const std::size_t comma = spec.find(',', pos);
    std::string name = spec.substr(pos, comma == std::string::npos ? std::string::npos
                                                                    : comma - pos);
    if (name.empty()) {
      err = "--channel '" + spec + "': an empty name in the list";
      return false;
    }
    if (std::find(out.begin(), out.end(), name) == out.end()) {
      out.push_back(std::move(name));
    }
    if (comma == std::string::npos) {
      return true;
    }
    pos = comma + 1;
  }
}

void parallel_for(std::size_t n, const std::function<void(std::size_t)>& job) {
  std::atomic<std::size_t> next{0};
  const auto work = [&job, &next, n]() {
    for (std::size_t i = next++; i < n; i = next++) {
      job(i);
    }
  };
  const std::size_t cores = std::getenv("IMU_NO_THREADS") != nullptr
                                ? 1U
                                : std::max(1U, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < std::min(cores, n); ++t) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;  // no more threads: the ones running (and this one) take the rest
    }
  }
  work();
  for (auto& t : pool) {
    t.join();
  }
}

std::string with_suggestion(const std::string& msg) {
  // The missing name between the first quotes after the marker, the listed names after the
  // list's colon (comma separated, to the end of the message).
  for (const char* marker : {"variable '", "no column '"}) {
    const std::size_t at = msg.find(marker);
    if (at == std::string::npos) {
      continue;
    }
    const std::size_t start = at + std::char_traits<char>::length(marker);
    const std::size_t end = msg.find('\'', start);
    const std::size_t list = end == std::string::npos ? end : msg.find(": ", end);
    if (list == std::string::npos) {
      return msg;
    }
    std::vector<std::string> names;
    for (std::size_t p = list + 2; p < msg.size();) {
      const std::size_t comma = std::min(msg.find(", ", p), msg.size());
      names.push_back(msg.substr(p, comma - p));
      p = comma + 2;
    }
    const std::string near = closest(msg.substr(start, end - start), names);
    if (near.empty()) {
      return msg;
    }
    std::string out = msg;
    out += "; did you mean ";
    out += near;
    out += "?";
    return out;
  }
  return msg;
}

bool names_missing_channel(const std::string& err) {
  return err.find("no column '") != std::string::npos ||
         err.find("' not found; ") != std::string::npos ||
         err.find("does not exist") != std::string::npos ||
         err.find("--topic") != std::string::npos;
}

}  // namespace imu::cli

// `analyze FILE.mat --channel NAME [--fs HZ] [--lsb UNITS] [--json OUT] [--plots DIR]`
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "imu/analyze/analyze.hpp"
#include "imu/mat/mat_reader.hpp"

namespace imu::analyze {
namespace {

int fail(const std::string& msg) {
  std::fprintf(stderr, "analyze: %s\n", msg.c_str());
  return 2;
}

bool parse_positive(const char* text, double& out) {
  char* end = nullptr;
  out = std::strtod(text, &end);
  return end != text && *end == '\0' && out > 0.0 && out < 1e300;
}

}  // namespace

int cli_main(int argc, char** argv) {
  std::string file;
  std::string channel;
  std::string json;
  std::string plots;
  double fs = 0.0;
  double lsb = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--channel" && has_value) {
      channel = argv[++i];
    } else if (a == "--json" && has_value) {
      json = argv[++i];
    } else if (a == "--plots" && has_value) {
      plots = argv[++i];
    } else if (a == "--fs" && has_value) {
      if (!parse_positive(argv[++i], fs)) {
        return fail("--fs needs a positive number, got '" + std::string(argv[i]) + "'");
      }
    } else if (a == "--lsb" && has_value) {
      if (!parse_positive(argv[++i], lsb)) {
        return fail("--lsb needs a positive number, got '" + std::string(argv[i]) + "'");
      }
    } else if (a == "--help" || a == "-h") {
      std::printf("usage: analyze FILE.mat --channel NAME [--fs HZ] [--lsb UNITS] [--json OUT] "
                  "[--plots DIR]\n");
      return 0;
    } else if (!a.empty() && a[0] != '-' && file.empty()) {
      file = a;
    } else {
      return fail("unexpected argument '" + a +
                  "' (usage: analyze FILE.mat --channel NAME [--fs HZ] [--json OUT] [--plots DIR])");
    }
  }
  if (file.empty() || channel.empty()) {
    return fail("usage: analyze FILE.mat --channel NAME [--fs HZ] [--json OUT] [--plots DIR]");
  }
  auto mf = imu::mat::MatFile::open(file);
  if (!mf) {
    return fail(mf.error().message);
  }
  const imu::mat::MatFile& m = mf.value();
  auto col = m.read_column(channel);
  if (!col) {
    return fail(col.error().message);
  }
  Options o;
  if (fs > 0.0) {
    o.fs_hz = fs;
  } else {
    auto f = m.read_scalar("fs");
    if (!f || !(f.value() > 0.0)) {
      return fail(file + ": no --fs given and no positive scalar 'fs' in the file");
    }
    o.fs_hz = f.value();
  }
  if (lsb > 0.0) {
    o.lsb = lsb;
  } else {
    // acc_x -> acc_lsb, gyro_z -> gyro_lsb; also NAME_lsb and lsb.
    const std::size_t us = channel.find('_');
    const std::string names[3] = {
        us != std::string::npos ? channel.substr(0, us) + "_lsb" : std::string(),
        channel + "_lsb", "lsb"};
    for (const auto& n : names) {
      if (n.empty()) {
        continue;
      }
      auto v = m.read_scalar(n);
      if (v && v.value() > 0.0) {
        o.lsb = v.value();
        break;
      }
    }
  }
  Report r;
  std::string err;
  if (!analyze(col.value(), channel, o, r, err)) {
    return fail(err);
  }
  if (o.lsb > 0.0 && lsb <= 0.0) {
    r.lsb_note = "LSB from the file: " + r.lsb_note.substr(r.lsb_note.find(':') + 2);
  }
  std::fputs(to_text(r).c_str(), stdout);
  if (!json.empty()) {
    std::ofstream f(json);
    if (!f) {
      return fail("cannot write " + json);
    }
    f << to_json(r);
    if (!f) {
      return fail("error writing " + json);
    }
    std::printf("wrote %s\n", json.c_str());
  }
  if (!plots.empty()) {
    std::string msg;
    if (!write_plots(r, plots, msg)) {
      return fail(msg);
    }
    std::printf("%s\n", msg.c_str());
  }
  return 0;
}

}  // namespace imu::analyze

// Loading a sensor recording (see data.hpp).
#include "data.hpp"

#include <cmath>

#include "imu/mat/mat_reader.hpp"
#include "imu/online_adev.hpp"

namespace imu::sim {

bool load_sensor(const std::string& path, const bool (&want)[kNumChannels],
                 const bool (&required)[kNumChannels], const double (&lsb_override)[kNumChannels],
                 double fs_override, SensorData& out, std::string& err) {
  out = SensorData{};
  out.path = path;
  auto file = mat::MatFile::open(path);
  if (!file.ok()) {
    err = file.error().message;
    return false;
  }
  const mat::MatFile& mf = file.value();
  auto vars = mf.list_variables();
  if (!vars.ok()) {
    err = vars.error().message;
    return false;
  }
  auto has_var = [&](const char* name) {
    for (const auto& v : vars.value()) {
      if (v.name == name) {
        return true;
      }
    }
    return false;
  };
  if (fs_override > 0.0) {
    out.fs_hz = fs_override;
  } else {
    auto fs = mf.read_scalar("fs");
    if (!fs.ok()) {
      err = fs.error().message + " (give --fs)";
      return false;
    }
    out.fs_hz = fs.value();
    if (!(out.fs_hz > 0.0) || !std::isfinite(out.fs_hz)) {
      err = path + ": fs = " + std::to_string(out.fs_hz) + " is not a positive rate";
      return false;
    }
  }
  double file_lsb[2] = {0.0, 0.0};
  const char* lsb_names[2] = {"acc_lsb", "gyro_lsb"};
  for (int g = 0; g < 2; ++g) {
    if (has_var(lsb_names[g])) {
      auto l = mf.read_scalar(lsb_names[g]);
      if (!l.ok()) {
        err = l.error().message;
        return false;
      }
      if (!(l.value() > 0.0) || !std::isfinite(l.value())) {
        err = path + ": " + lsb_names[g] + " is not a positive number";
        return false;
      }
      file_lsb[g] = l.value();
    }
  }
  bool any = false;
  for (std::size_t c = 0; c < kNumChannels; ++c) {
    if (!want[c]) {
      continue;
    }
    if (!has_var(kChannelNames[c]) && !required[c]) {
      continue;
    }
    ChannelData& ch = out.ch[c];
    auto col = mf.read_column(kChannelNames[c]);
    if (!col.ok()) {
      err = col.error().message;
      return false;
    }
    ch.values = std::move(col.value());
    if (ch.values.empty()) {
      err = path + ": variable '" + kChannelNames[c] + "' is empty";
      return false;
    }
    if (any && ch.values.size() != out.n_samples) {
      err = path + ": variable '" + kChannelNames[c] + "' has " +
            std::to_string(ch.values.size()) + " samples, others " +
            std::to_string(out.n_samples);
      return false;
    }
    out.n_samples = ch.values.size();
    any = true;
    ch.present = true;
    const double fl = file_lsb[c < 3 ? 0 : 1];
    if (lsb_override[c] > 0.0) {
      ch.lsb = lsb_override[c];
    } else if (fl > 0.0) {
      ch.lsb = fl;
      ch.lsb_from_file = true;
    } else {
      ch.lsb = default_lsb(c);
    }
  }
  if (!any) {
    err = path + ": none of the channels acc_x .. gyro_z is in the file";
    return false;
  }
  return true;
}

void to_counts(ChannelData& ch, std::vector<std::int32_t>& counts) {
  counts.resize(ch.values.size());
  ch.saturated = 0;
  ch.off_grid = 0;
  for (std::size_t i = 0; i < ch.values.size(); ++i) {
    const QuantizeResult q = quantize(ch.values[i], ch.lsb);
    counts[i] = q.counts;
    ch.saturated += q.saturated ? 1U : 0U;
    const double resid = ch.values[i] / ch.lsb - static_cast<double>(q.counts);
    ch.off_grid += std::fabs(resid) > 1e-6 ? 1U : 0U;
  }
}

}  // namespace imu::sim

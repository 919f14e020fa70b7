// Host twin of the M4 node image: runs the same node workload
// (toolchains/m4/src/node_workload.cpp, the same Node and codec built for the host) and
//   node_check              prints its lines (what the target must print);
//   node_check --compare LOG  compares every T and END line of a qemu-system-arm log with its
//                           own, byte for byte: telemetry equal to the host's. Prints
//                           "NODE-CHECK PASS" (exit 0) or the first differences (exit 1), and
//                           the target's cost per sample per channel from its COST line.
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "node_workload.hpp"

namespace {

void collect(const char* line, void* ctx) {
  static_cast<std::vector<std::string>*>(ctx)->emplace_back(line);
}

bool relevant(const std::string& l) {
  return l.rfind("T ", 0) == 0 || l.rfind("IMU-NODE END", 0) == 0 ||
         l.rfind("IMU-NODE STEADY ", 0) == 0;
}

// What the target's log holds: its telemetry lines (relevant()) and its cost counters.
struct TargetLog {
  std::vector<std::string> lines;
  unsigned long long ticks = 0;
  unsigned long long cal_ticks = 0;
  unsigned long long cal_insns = 0;
  unsigned long long steady_ticks = 0;
  unsigned long long steady_samples = 0;
  unsigned long long adev_frame_ticks = 0;
  unsigned long long adev_frames = 0;
  unsigned long long adev_block_ticks = 0;
  unsigned long long adev_samples = 0;
  unsigned long long kf_tv_ticks = 0;
  unsigned long long kf_steady_ticks = 0;
  unsigned long long kf_steps = 0;
};

// Reads a qemu-system-arm log; false if it cannot be opened. Echoes the target's banners.
bool read_target(const char* path, TargetLog& t) {
  std::ifstream in(path);
  if (!in) {
    return false;
  }
  std::string l;
  while (std::getline(in, l)) {
    l += "\n";
    if (relevant(l)) {
      t.lines.push_back(l);
    }
    if (l.rfind("IMU-NODE BEGIN", 0) == 0 || l.rfind("IMU-M4 STACK", 0) == 0) {
      std::printf("target: %s", l.c_str());
    }
    std::sscanf(l.c_str(), "IMU-NODE COST ticks=%llu cal_ticks=%llu cal_insns=%llu", &t.ticks,
                &t.cal_ticks, &t.cal_insns);
    std::sscanf(l.c_str(), "IMU-NODE STEADY-COST ticks=%llu samples=%llu", &t.steady_ticks,
                &t.steady_samples);
    if (l.rfind("IMU-NODE STEADY ", 0) == 0) {
      std::printf("target: %s", l.c_str());
    }
    std::sscanf(l.c_str(),
                "IMU-ADEV COST frame_ticks=%llu frames=%llu block_ticks=%llu samples=%llu",
                &t.adev_frame_ticks, &t.adev_frames, &t.adev_block_ticks, &t.adev_samples);
    std::sscanf(l.c_str(), "IMU-KF COST tv_ticks=%llu steady_ticks=%llu steps=%llu",
                &t.kf_tv_ticks, &t.kf_steady_ticks, &t.kf_steps);
  }
  return true;
}

// The target's cost per sample per channel: the whole node, in steady state, the ADEV kernel.
void print_costs(const TargetLog& t) {
  if (t.cal_ticks > 0 && t.ticks > 0) {
    const double insns = static_cast<double>(t.ticks) * static_cast<double>(t.cal_insns) /
                         static_cast<double>(t.cal_ticks);
    std::printf("node-check: target cost %.0f instructions for %u samples x 6 channels = %.0f "
                "instructions per sample per channel (SysTick under -icount shift=0, "
                "calibrated: %llu ticks for %llu instructions)\n",
                insns, imu::m4::kNodeSamples, insns / (imu::m4::kNodeSamples * 6.0), t.cal_ticks,
                t.cal_insns);
  }
  if (t.cal_ticks > 0 && t.steady_ticks > 0 && t.steady_samples > 0) {
    const double insns = static_cast<double>(t.steady_ticks) * static_cast<double>(t.cal_insns) /
                         static_cast<double>(t.cal_ticks);
    std::printf("node-check: steady state (after %u samples, gains frozen): %.0f instructions "
                "for %llu samples x 6 channels = %.0f instructions per sample per channel\n",
                imu::m4::kSteadyWarmSamples, insns, t.steady_samples,
                insns / (static_cast<double>(t.steady_samples) * 6.0));
  }
  if (t.cal_ticks > 0 && t.adev_frames > 0 && t.adev_samples > 0) {
    const double per_tick = static_cast<double>(t.cal_insns) / static_cast<double>(t.cal_ticks);
    std::printf("node-check: ADEV kernel alone: %.0f instructions per sample per channel through "
                "MultiAdev<6,8,22>::push_frame (%llu frames), %.0f through "
                "OnlineAdev<8,22>::push_block (%llu samples)\n",
                static_cast<double>(t.adev_frame_ticks) * per_tick /
                    (static_cast<double>(t.adev_frames) * 6.0),
                t.adev_frames,
                static_cast<double>(t.adev_block_ticks) * per_tick /
                    static_cast<double>(t.adev_samples),
                t.adev_samples);
  }
  if (t.cal_ticks > 0 && t.kf_steps > 0) {
    const double per_tick = static_cast<double>(t.cal_insns) / static_cast<double>(t.cal_ticks);
    const double steps = static_cast<double>(t.kf_steps);
    std::printf("node-check: the node's filter alone (largest model): %.0f instructions per "
                "time-varying step, %.0f per frozen-gain step (%llu steps each)\n",
                static_cast<double>(t.kf_tv_ticks) * per_tick / steps,
                static_cast<double>(t.kf_steady_ticks) * per_tick / steps, t.kf_steps);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> host;
  imu::m4::NodeRunStatus st = imu::m4::run_node_workload(collect, nullptr, &host);
  if (st == imu::m4::NodeRunStatus::kOk) {
    st = imu::m4::run_node_steady(collect, nullptr, &host);
  }
  if (st != imu::m4::NodeRunStatus::kOk) {
    std::printf("NODE-CHECK FAIL: host run status %d\n", static_cast<int>(st));
    return 1;
  }
  if (argc < 3 || std::strcmp(argv[1], "--compare") != 0) {
    for (const std::string& l : host) {
      std::fputs(l.c_str(), stdout);
    }
    return 0;
  }
  TargetLog t;
  if (!read_target(argv[2], t)) {
    std::printf("NODE-CHECK FAIL: cannot read %s\n", argv[2]);
    return 1;
  }
  const std::vector<std::string>& target = t.lines;
  std::vector<std::string> want;
  for (const std::string& h : host) {
    if (h.rfind("IMU-NODE BEGIN", 0) == 0) {
      std::printf("host:   %s", h.c_str());
    }
    if (relevant(h)) {
      want.push_back(h);
    }
  }
  std::size_t diffs = 0;
  const std::size_t n = want.size() > target.size() ? want.size() : target.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::string a = i < want.size() ? want[i] : std::string("(none)\n");
    const std::string b = i < target.size() ? target[i] : std::string("(none)\n");
    if (a != b) {
      if (++diffs <= 5) {
        std::printf("line %zu differs:\n  host:   %s  target: %s", i, a.c_str(), b.c_str());
      }
    }
  }
  std::size_t frames = 0;
  for (const std::string& w : want) {
    frames += w.rfind("T ", 0) == 0 ? 1U : 0U;
  }
  std::printf("node-check: %zu lines compared (%zu telemetry frames), %zu differ\n", n, frames,
              diffs);
  print_costs(t);
  if (diffs != 0 || target.empty()) {
    std::printf("NODE-CHECK FAIL\n");
    return 1;
  }
  std::printf("NODE-CHECK PASS\n");
  return 0;
}

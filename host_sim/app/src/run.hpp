// Subcommands of imu-sim (internal).
#ifndef IMU_SIM_RUN_HPP
#define IMU_SIM_RUN_HPP

#include <string>

namespace imu::sim {

/// imu-sim run ... (argv[1] == "run").
[[nodiscard]] int cmd_run(int argc, char** argv);

/// The usage of one subcommand ("synth", "model", "adev", "run", "analyze"): "usage: imu-sim
/// <cmd> ..." and what it does; "" for an unknown one. Defined in cli.cpp.
[[nodiscard]] const char* command_usage(const std::string& cmd);

/// Print command_usage(cmd) on stdout; returns kExitOk (for --help).
int print_help(const std::string& cmd);

}  // namespace imu::sim

#endif  // IMU_SIM_RUN_HPP

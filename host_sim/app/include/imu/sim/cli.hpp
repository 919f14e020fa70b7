// Entry point of imu-sim, callable in-process (tests) as well as from main():
//
//   imu-sim synth | model | adev | run | analyze ...   (cli_main; see host_sim/README.md)
//
// (imu-fw's is imu/node/fw_main.hpp, host_sim/node.) It returns the process exit status:
// 0 success, 1 a run-time failure (bad file, bus error,
// no telemetry), 2 a command-line error. Every failure prints one line on stderr that names the
// command and the problem. Host code: allocates, uses the OS, never lets an exception escape.
#ifndef IMU_SIM_CLI_HPP
#define IMU_SIM_CLI_HPP

namespace imu::sim {

/// imu-sim. argv[0] is the program name; argv[1] the subcommand.
[[nodiscard]] int cli_main(int argc, char** argv);

}  // namespace imu::sim

#endif  // IMU_SIM_CLI_HPP

// Subcommands of imu-sim (internal).
#ifndef IMU_SIM_RUN_HPP
#define IMU_SIM_RUN_HPP

namespace imu::sim {

/// imu-sim run ... (argv[1] == "run").
[[nodiscard]] int cmd_run(int argc, char** argv);

}  // namespace imu::sim

#endif  // IMU_SIM_RUN_HPP

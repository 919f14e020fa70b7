// imu-fw's Linux main, callable in-process (tests) as well as from main():
//
//   imu-fw --bus loopback|vcan0|can0 [...]   (usage: imu-fw --help; host_sim/README.md)
//
// Returns the process exit status: 0 success, 1 a run-time failure (bus error, peer gone),
// 2 a command-line error; every failure prints one line on stderr that starts "imu-fw: ".
// Linux host code (allocates, uses the OS, never lets an exception escape); depends only on
// the node (fw/node) and the Linux HAL backends.
#ifndef IMU_NODE_FW_MAIN_HPP
#define IMU_NODE_FW_MAIN_HPP

namespace imu::node {

/// imu-fw. argv[0] is the program name.
[[nodiscard]] int fw_main(int argc, char** argv);

}  // namespace imu::node

#endif  // IMU_NODE_FW_MAIN_HPP

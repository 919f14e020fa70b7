// imu-fw executable: see imu/node/fw_main.hpp and host_sim/README.md.
#include "imu/node/fw_main.hpp"

int main(int argc, char** argv) { return imu::node::fw_main(argc, argv); }

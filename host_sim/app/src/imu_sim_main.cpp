// imu-sim executable: see imu/sim/cli.hpp and host_sim/README.md.
#include "imu/sim/cli.hpp"

int main(int argc, char** argv) { return imu::sim::cli_main(argc, argv); }

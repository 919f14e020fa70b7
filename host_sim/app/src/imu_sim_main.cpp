// imu-sim executable: see imu/sim/cli.hpp and host_sim/README.md.
#include "imu/cli/file_out.hpp"
#include "imu/sim/cli.hpp"

int main(int argc, char** argv) {
  imu::cli::install_cleanup_handlers();  // no temporary output file outlives a SIGTERM
  return imu::sim::cli_main(argc, argv);
}

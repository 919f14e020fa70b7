// Standalone `imu-analyze` (same as `imu-sim analyze`): argv[0] is replaced by "analyze".
#include "imu/analyze/analyze.hpp"
#include "imu/cli/file_out.hpp"

int main(int argc, char** argv) {
  imu::cli::install_cleanup_handlers();  // no temporary output file outlives a SIGTERM
  return imu::analyze::cli_main(argc, argv);
}

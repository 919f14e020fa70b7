// Standalone `imu-analyze` (same as `imu-sim analyze`): argv[0] is replaced by "analyze".
#include "imu/analyze/analyze.hpp"

int main(int argc, char** argv) { return imu::analyze::cli_main(argc, argv); }

#pragma once

#include <filesystem>

// Where this build put what the tests run. Defined in a file the build generates
// (tests/CMakeLists.txt), not by compile flags, so the tests' objects hold no path of one
// checkout and a fresh clone compiles them from ccache.
namespace epipole::test {

const char* source_dir();             // the source tree: board/, scripts/
const char* tool_path();              // the epipole host tool; empty where it is not built
const char* firmware_path();          // epipole-fw
const char* sim_output_dir();         // what the sim_cli_run fixture writes
const char* default_data_dir();       // the data sets, unless EPIPOLE_DATA_DIR says otherwise
const char* ros2_listener_path();     // the tests' ROS 2 subscriber; empty in cross builds
const char* fastdds_listener_path();  // the same of another DDS vendor (Fast DDS)

// The folder of the running test program: the build puts there what the program's fixture makes
// (the virtual board's initramfs, the deployment test's run folder).
std::filesystem::path program_folder();

}  // namespace epipole::test

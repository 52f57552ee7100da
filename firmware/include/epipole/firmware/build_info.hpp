#pragma once

#include <string>

namespace epipole::firmware {

// One line naming the version, build type, compiler and the kernel path this CPU runs,
// for --version and the first health message.
std::string build_info();

}  // namespace epipole::firmware

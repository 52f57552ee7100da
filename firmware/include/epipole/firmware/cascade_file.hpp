#pragma once

// A compiled cascade file (epipole cascade-compile) for the firmware: read and checked with no
// XML library (vision::CascadeModel::from_binary). Start-up code.

#include <filesystem>
#include <string>

#include "epipole/vision/cascade_model.hpp"

namespace epipole::firmware {

// Throws Error naming the file when it cannot be read or is not a valid compiled cascade.
vision::CascadeModel load_compiled_cascade(const std::filesystem::path& file);

// OpenCV's cascade XML that `compiled` is made from: the file of the same name in the data cache
// of scripts/fetch-data.sh (haarcascades or lbpcascades), or empty when it is not there.
std::filesystem::path opencv_cascade_xml(const std::filesystem::path& compiled);
// The one command that makes a missing compiled cascade (epipole cascade-compile), from
// opencv_cascade_xml() when it is there.
std::string cascade_compile_command(const std::filesystem::path& compiled);

}  // namespace epipole::firmware

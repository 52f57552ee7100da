#pragma once

// A compiled cascade file (epipole cascade-compile) for the firmware: read and checked with no
// XML library (vision::CascadeModel::from_binary). Start-up code.

#include <filesystem>

#include "epipole/vision/cascade_model.hpp"

namespace epipole::firmware {

// Throws Error naming the file when it cannot be read or is not a valid compiled cascade.
vision::CascadeModel load_compiled_cascade(const std::filesystem::path& file);

}  // namespace epipole::firmware

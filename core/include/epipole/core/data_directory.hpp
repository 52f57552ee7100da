#pragma once

#include <filesystem>

namespace epipole {

// The data cache folder of scripts/fetch-data.sh: $EPIPOLE_DATA_DIR, else
// ${XDG_CACHE_HOME:-$HOME/.cache}/epipole/data.
std::filesystem::path default_data_directory();

}  // namespace epipole

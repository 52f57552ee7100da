#include "epipole/core/data_directory.hpp"

#include <cstdlib>

namespace epipole {

std::filesystem::path default_data_directory() {
  namespace fs = std::filesystem;
  if (const char* dir = std::getenv("EPIPOLE_DATA_DIR"); dir != nullptr && *dir != '\0') {
    return dir;
  }
  if (const char* cache = std::getenv("XDG_CACHE_HOME"); cache != nullptr && *cache != '\0') {
    return fs::path(cache) / "epipole" / "data";
  }
  const char* home = std::getenv("HOME");
  return fs::path(home != nullptr ? home : ".") / ".cache" / "epipole" / "data";
}

}  // namespace epipole

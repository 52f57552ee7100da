#include "test_data.hpp"

#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace epipole::test {

std::filesystem::path data_file(std::string_view relative) {
  const char* env = std::getenv("EPIPOLE_DATA_DIR");
  const std::filesystem::path root = env != nullptr && *env != 0 ? env : default_data_dir();
  std::filesystem::path file = root / relative;
  if (!std::filesystem::exists(file)) {
    throw std::runtime_error("data file " + file.string() +
                             " is missing: run scripts/fetch-data.sh (or set EPIPOLE_DATA_DIR)");
  }
  return file;
}

}  // namespace epipole::test

#include "epipole/core/temporary_folder.hpp"

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

#include "epipole/core/error.hpp"

namespace epipole {

TemporaryFolder::TemporaryFolder(std::string_view prefix, const std::filesystem::path& parent) {
  std::string pattern = (parent / (std::string(prefix) + "-XXXXXX")).string();
  require(::mkdtemp(pattern.data()) != nullptr, "a temporary folder in ", parent.string(), ": ",
          std::strerror(errno));
  path_ = pattern;
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace epipole

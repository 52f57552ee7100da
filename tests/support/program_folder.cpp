#include <stdexcept>
#include <system_error>

#include "test_paths.hpp"

namespace epipole::test {

std::filesystem::path program_folder() {
  std::error_code error;
  const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) throw std::runtime_error("cannot find the test program: " + error.message());
  return program.parent_path();
}

}  // namespace epipole::test

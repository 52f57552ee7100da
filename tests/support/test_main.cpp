// The main of every test program: runs its tests with a temporary folder of its own as
// ::testing::TempDir() (GoogleTest reads TEST_TMPDIR), so that test programs running side by
// side (ctest -j, two checkouts on one machine) never write the same file.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

int main(int argc, char** argv) {
  std::string folder = (std::filesystem::temp_directory_path() / "epipole-test-XXXXXX").string();
  if (::mkdtemp(folder.data()) == nullptr) {
    std::perror("mkdtemp");
    return 2;
  }
  ::setenv("TEST_TMPDIR", folder.c_str(), 1);
  ::testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS();
  std::error_code ignored;
  std::filesystem::remove_all(folder, ignored);
  return result;
}

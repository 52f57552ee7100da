#pragma once

#include <filesystem>
#include <string_view>

namespace epipole {

// A new empty folder `prefix`-XXXXXX in `parent`, removed with everything in it when this goes.
// Throws Error (naming the parent and the system's reason) when it cannot be made.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(
      std::string_view prefix = "epipole",
      const std::filesystem::path& parent = std::filesystem::temp_directory_path());
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace epipole

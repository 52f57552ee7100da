#pragma once

// For fuzz targets whose parser reads files: the input written to a file of a folder made once
// per process, so each run reads what libFuzzer gave it. The folder is under $TMPDIR when it is
// set, else in /dev/shm (memory) when there is one, else /tmp: a disk that stalls (a busy
// machine writing an image) must not stall a run of millions of tiny files.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <system_error>

namespace epipole::fuzz {

// Made on first use, removed when the process exits normally.
struct FuzzFolder {
  FuzzFolder() {
    const char* tmp = std::getenv("TMPDIR");
    std::string base = tmp != nullptr && *tmp != '\0' ? tmp : "";
    if (base.empty()) base = ::access("/dev/shm", W_OK | X_OK) == 0 ? "/dev/shm" : "/tmp";
    std::string pattern = base + "/epipole-fuzz-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) std::abort();
    path = pattern;
  }
  ~FuzzFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  FuzzFolder(const FuzzFolder&) = delete;
  FuzzFolder& operator=(const FuzzFolder&) = delete;
  std::filesystem::path path;
};

inline const std::filesystem::path& folder() {
  static const FuzzFolder made;
  return made.path;
}

inline std::filesystem::path write_file(const std::string& name,
                                        std::span<const std::uint8_t> bytes) {
  const std::filesystem::path file = folder() / name;
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) std::abort();
  return file;
}

}  // namespace epipole::fuzz

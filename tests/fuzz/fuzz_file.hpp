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

#include "epipole/core/temporary_folder.hpp"

namespace epipole::fuzz {

// Made on first use, removed when the process exits normally; a run that cannot make it stops.
inline const std::filesystem::path& folder() {
  static const TemporaryFolder made = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::filesystem::path parent = tmp != nullptr && *tmp != '\0' ? tmp : "";
    if (parent.empty()) parent = ::access("/dev/shm", W_OK | X_OK) == 0 ? "/dev/shm" : "/tmp";
    try {
      return TemporaryFolder("epipole-fuzz", parent);
    } catch (...) {
      std::abort();
    }
  }();
  return made.path();
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

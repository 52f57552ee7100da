#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace epipole::firmware::record {

// The folder a recording writes its files into, bounded as the snapshots' folder is: at most
// `total_bytes` of recordings (its own files: epipole-*.mcap) and never less than
// `min_free_bytes` left free on its file system. Before each new file of at most `file_bytes`,
// the oldest recordings are removed until it fits both bounds; none is removed when removing
// them all would not make room (the disk filled with other files).
struct RingLimits {
  std::uint64_t file_bytes = 256ull << 20;
  std::uint64_t total_bytes = 2048ull << 20;
  std::uint64_t min_free_bytes = 512ull << 20;
};

class RecordingRing {
 public:
  RecordingRing(std::filesystem::path directory, RingLimits limits);

  // Makes room and names the next file (the folder is made when it is not there): the UTC time
  // `system_ns` in its name, never one that exists. Throws Error naming the folder when there is
  // no room even without any of its recordings, or the folder cannot be made, listed or its
  // free space told.
  std::filesystem::path next_file(std::int64_t system_ns);
  // Recordings removed to make room, since the start.
  std::uint64_t removed() const { return removed_; }
  const std::filesystem::path& directory() const { return directory_; }
  const RingLimits& limits() const { return limits_; }

 private:
  std::filesystem::path directory_;
  RingLimits limits_;
  std::uint64_t removed_ = 0;
};

// Whether a file name is one of a recording ring's.
bool is_recording_name(const std::string& name);

}  // namespace epipole::firmware::record

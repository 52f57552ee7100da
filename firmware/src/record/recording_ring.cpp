#include "record/recording_ring.hpp"

#include <sys/statvfs.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <system_error>
#include <utility>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole::firmware::record {

namespace fs = std::filesystem;

bool is_recording_name(const std::string& name) {
  return name.starts_with("epipole-") && name.ends_with(".mcap");
}

RecordingRing::RecordingRing(fs::path directory, RingLimits limits)
    : directory_(std::move(directory)), limits_(limits) {}

namespace {

std::uint64_t free_bytes(const fs::path& directory) {
  struct statvfs s {};
  if (::statvfs(directory.c_str(), &s) != 0) {
    throw Error(cat(directory.string(), ": cannot tell its free space: ", std::strerror(errno)));
  }
  return static_cast<std::uint64_t>(s.f_bavail) * s.f_frsize;
}

// A recording's place in time: its name's UTC time, then its number within that second
// (epipole-20261207T084320Z.mcap, then -1, -2, ... -10).
std::pair<std::string, unsigned long> age_of(const fs::path& file) {
  const std::string stem = file.stem().string();  // epipole-<time>[-<n>]
  const std::size_t dash = stem.find('-', 8);
  if (dash == std::string::npos) return {stem, 0};
  return {stem.substr(0, dash), std::strtoul(stem.c_str() + dash + 1, nullptr, 10)};
}

}  // namespace

fs::path RecordingRing::next_file(std::int64_t system_ns) {
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (ec) throw Error(cat(directory_.string(), ": cannot make the folder: ", ec.message()));
  struct Recording {
    fs::path path;
    std::uint64_t bytes;
  };
  std::vector<Recording> recordings;
  std::uint64_t total = 0;
  for (fs::directory_iterator it(directory_, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file() || !is_recording_name(it->path().filename().string())) continue;
    const std::uint64_t bytes = it->file_size();
    recordings.push_back({it->path(), bytes});
    total += bytes;
  }
  if (ec) throw Error(cat(directory_.string(), ": cannot list the folder: ", ec.message()));
  std::sort(recordings.begin(), recordings.end(), [](const Recording& a, const Recording& b) {
    return age_of(a.path) < age_of(b.path);  // oldest first
  });
  // What must go: enough for both bounds, or nothing when even all of them would not do (the
  // disk filled with something else): a recording is never removed for nothing.
  const std::uint64_t free = free_bytes(directory_);
  const std::uint64_t needed_free = limits_.min_free_bytes + limits_.file_bytes;
  const std::uint64_t for_space = needed_free > free ? needed_free - free : 0;
  const std::uint64_t for_total = total + limits_.file_bytes > limits_.total_bytes
                                      ? total + limits_.file_bytes - limits_.total_bytes
                                      : 0;
  const std::uint64_t to_remove = std::max(for_space, for_total);
  if (to_remove > total) {
    throw Error(cat(directory_.string(), ": no room for another recording of ",
                    limits_.file_bytes >> 20, " MiB (recordings may take ",
                    limits_.total_bytes >> 20, " MiB and leave ", limits_.min_free_bytes >> 20,
                    " MiB free; ", free >> 20, " MiB are free with ", total >> 20,
                    " MiB of recordings)"));
  }
  std::uint64_t removed_bytes = 0;
  for (std::size_t i = 0; i < recordings.size() && removed_bytes < to_remove; ++i) {
    if (fs::remove(recordings[i].path, ec)) {
      removed_bytes += recordings[i].bytes;
      ++removed_;
    }
  }
  const std::time_t seconds = static_cast<std::time_t>(system_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  for (int n = 0;; ++n) {
    const fs::path file = directory_ / (n == 0 ? cat("epipole-", stamp, ".mcap")
                                               : cat("epipole-", stamp, "-", n, ".mcap"));
    if (!fs::exists(file, ec)) return file;
  }
}

}  // namespace epipole::firmware::record

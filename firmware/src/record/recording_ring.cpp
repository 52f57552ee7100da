#include "record/recording_ring.hpp"

#include <sys/statvfs.h>

#include <algorithm>
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
  if (::statvfs(directory.c_str(), &s) != 0) return 0;
  return static_cast<std::uint64_t>(s.f_bavail) * s.f_frsize;
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
    return a.path < b.path;
  });  // oldest first
  std::size_t oldest = 0;
  const auto fits = [&] {
    return total + limits_.file_bytes <= limits_.total_bytes &&
           free_bytes(directory_) >= limits_.min_free_bytes + limits_.file_bytes;
  };
  while (!fits() && oldest < recordings.size()) {
    fs::remove(recordings[oldest].path, ec);
    if (!ec) {
      total -= recordings[oldest].bytes;
      ++removed_;
    }
    ++oldest;
  }
  if (!fits()) {
    throw Error(cat(directory_.string(), ": no room for another recording of ",
                    limits_.file_bytes >> 20, " MiB (recordings may take ",
                    limits_.total_bytes >> 20, " MiB and leave ", limits_.min_free_bytes >> 20,
                    " MiB free)"));
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

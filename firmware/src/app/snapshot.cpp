#include "epipole/firmware/snapshot.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <exception>
#include <functional>
#include <mutex>

#include "epipole/core/error.hpp"
#include "epipole/core/image.hpp"
#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/thread_roles.hpp"

namespace epipole::firmware {

struct SnapshotWriter::Shared {
  std::string directory;
  GrayImage left_raw, right_raw, left, right;
  Image<std::uint16_t> disparity;
  bool has_disparity = false;
  std::uint32_t frame = 0;
  std::uint32_t next_index = 0;  // the writer thread's
  std::mutex mutex;
  std::condition_variable wake;
  bool pending = false;  // guarded by mutex, as the rest below
  bool stopping = false;
  std::uint16_t sequence = 0;
  std::optional<SnapshotDone> done;
  std::atomic<std::uint64_t> written{0};
  std::atomic<std::uint64_t> failures{0};
  std::function<void()> before_write;  // set before the first snapshot (tests)
};

namespace {

constexpr std::string_view kPrefix = "snapshot-";
constexpr std::string_view kLeftRaw = "-left-raw.pgm";

// The number of a snapshot file's name (snapshot-N-...), if it is one.
std::optional<std::uint32_t> snapshot_index(std::string_view name) {
  if (!name.starts_with(kPrefix)) return std::nullopt;
  std::uint32_t n = 0;
  const char* begin = name.data() + kPrefix.size();
  const auto [end, ec] = std::from_chars(begin, name.data() + name.size(), n);
  if (ec != std::errc() || end == begin || *end != '-') return std::nullopt;
  return n;
}

struct FolderScan {
  int snapshots = 0;       // left raw files
  std::uint32_t next = 0;  // after the highest number
};

// With readdir, not std::filesystem: no operator new once running (the soak counts them).
// Nothing when the folder cannot be read to its end; a missing folder holds none.
std::optional<FolderScan> scan(const std::string& directory) {
  FolderScan s;
  DIR* dir = ::opendir(directory.c_str());
  if (dir == nullptr) return errno == ENOENT ? std::optional(s) : std::nullopt;
  for (;;) {
    errno = 0;
    const dirent* entry = ::readdir(dir);
    if (entry == nullptr) break;
    const std::string_view name(entry->d_name);
    const std::optional<std::uint32_t> n = snapshot_index(name);
    if (!n) continue;
    s.next = std::max(s.next, *n + 1);
    if (name.ends_with(kLeftRaw)) ++s.snapshots;
  }
  const bool read_to_end = errno == 0;
  ::closedir(dir);
  return read_to_end ? std::optional(s) : std::nullopt;
}

bool write_bytes(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

enum class Written { ok, exists, failed };

// A binary PGM (P5), created exclusively and synced; 16-bit samples are big-endian, as the format
// says. The header's comment names the frame.
template <typename T>
Written write_pgm(const char* path, ImageView<const T> image, std::uint32_t frame) {
  const int fd = ::open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return errno == EEXIST ? Written::exists : Written::failed;
  char header[96];
  const int n = std::snprintf(header, sizeof header, "P5\n# epipole frame %u\n%d %d\n%d\n", frame,
                              image.width(), image.height(), sizeof(T) == 1 ? 255 : 65535);
  bool ok = write_bytes(fd, header, static_cast<std::size_t>(n));
  unsigned char row[2 * 4096];
  for (int y = 0; ok && y < image.height(); ++y) {
    for (int x0 = 0; ok && x0 < image.width(); x0 += 4096) {
      const int count = std::min(4096, image.width() - x0);
      for (int i = 0; i < count; ++i) {
        const auto v = static_cast<unsigned>(image(x0 + i, y));
        if constexpr (sizeof(T) == 1) {
          row[i] = static_cast<unsigned char>(v);
        } else {
          row[2 * i] = static_cast<unsigned char>(v >> 8);
          row[2 * i + 1] = static_cast<unsigned char>(v & 0xFF);
        }
      }
      ok = write_bytes(fd, row, static_cast<std::size_t>(count) * sizeof(T));
    }
  }
  ok = ::fsync(fd) == 0 && ok;
  return ::close(fd) == 0 && ok ? Written::ok : Written::failed;
}

bool sync_folder(const std::string& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  return ::close(fd) == 0 && ok;
}

void copy(GrayView from, GrayImage& to) {
  for (int y = 0; y < from.height(); ++y) std::copy_n(from.row(y), from.width(), to.view().row(y));
}

// Writes the snapshot's files under the next free number; false when any could not be written.
bool write_all(SnapshotWriter::Shared& s) {
  // Removed while running: made again (its parent is there: it was made at start-up).
  if (::mkdir(s.directory.c_str(), 0755) != 0 && errno != EEXIST) return false;
  const std::optional<FolderScan> folder = scan(s.directory);
  if (!folder) return false;  // a number in it may be unseen
  s.next_index = std::max(s.next_index, folder->next);
  char path[4096];
  // A number someone else took meanwhile (its first file exists) is skipped.
  for (int attempt = 0; attempt < 8; ++attempt, ++s.next_index) {
    const std::uint32_t index = s.next_index;
    const auto name = [&](const char* what) {
      std::snprintf(path, sizeof path, "%s/snapshot-%06u-%s.pgm", s.directory.c_str(), index, what);
      return path;
    };
    const Written first =
        write_pgm(name("left-raw"), ImageView<const std::uint8_t>(s.left_raw.view()), s.frame);
    if (first == Written::exists) continue;
    ++s.next_index;
    bool ok = first == Written::ok;
    ok = write_pgm(name("right-raw"), ImageView<const std::uint8_t>(s.right_raw.view()), s.frame) ==
             Written::ok &&
         ok;
    ok = write_pgm(name("left"), ImageView<const std::uint8_t>(s.left.view()), s.frame) ==
             Written::ok &&
         ok;
    ok = write_pgm(name("right"), ImageView<const std::uint8_t>(s.right.view()), s.frame) ==
             Written::ok &&
         ok;
    if (s.has_disparity) {
      ok = write_pgm(name("disparity"), ImageView<const std::uint16_t>(s.disparity.view()),
                     s.frame) == Written::ok &&
           ok;
    }
    return sync_folder(s.directory) && ok;
  }
  return false;
}

void run(const std::shared_ptr<SnapshotWriter::Shared>& shared) {
  enter_thread_role_or_say(ThreadRole::snapshot);
  SnapshotWriter::Shared& s = *shared;
  std::unique_lock lock(s.mutex);
  for (;;) {
    s.wake.wait(lock, [&] { return s.pending || s.stopping; });
    if (!s.pending) return;
    lock.unlock();
    bool ok = false;
    try {
      if (s.before_write) s.before_write();
      ok = write_all(s);
    } catch (const std::exception& e) {  // nothing leaves the thread: it is a failed snapshot
      journal(Priority::error, "snapshot: %s", e.what());
    }
    (ok ? s.written : s.failures)++;
    lock.lock();
    s.done = SnapshotDone{s.sequence, ok};
    s.pending = false;
    s.wake.notify_all();
  }
}

}  // namespace

SnapshotWriter::SnapshotWriter(std::filesystem::path directory, int width, int height,
                               SnapshotLimits limits)
    : limits_(limits) {
  if (directory.empty()) return;
  shared_ = std::make_shared<Shared>();
  Shared& s = *shared_;
  s.directory = directory.string();
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  require(!ec, "snapshot directory ", s.directory, ": ", ec.message());
  // Four 8-bit images, one 16-bit, and their headers.
  bytes_each_ = 6 * static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) + 5 * 96;
  const std::optional<FolderScan> folder = scan(s.directory);
  require(folder.has_value(), "snapshot directory ", s.directory,
          ": cannot be read: ", std::strerror(errno));
  s.next_index = folder->next;
  for (GrayImage* image : {&s.left_raw, &s.right_raw, &s.left, &s.right}) {
    *image = GrayImage(width, height);
  }
  s.disparity = Image<std::uint16_t>(width, height);
  thread_ = std::thread([shared = shared_] { run(shared); });
}

SnapshotWriter::~SnapshotWriter() {
  if (!shared_) return;
  std::unique_lock lock(shared_->mutex);
  shared_->stopping = true;
  shared_->wake.notify_all();
  const bool idle = shared_->wake.wait_for(lock, kStopWait, [this] { return !shared_->pending; });
  lock.unlock();
  if (idle) {
    thread_.join();
  } else {
    thread_.detach();  // it owns what it writes from; the process is stopping
  }
}

bool SnapshotWriter::enabled() const {
  return shared_ != nullptr;
}

std::optional<int> SnapshotWriter::count() const {
  if (!enabled()) return 0;
  const std::optional<FolderScan> folder = scan(shared_->directory);
  if (!folder) return std::nullopt;
  return folder->snapshots;
}

std::uint64_t SnapshotWriter::written() const {
  return enabled() ? shared_->written.load() : 0;
}

std::uint64_t SnapshotWriter::failures() const {
  return enabled() ? shared_->failures.load() : 0;
}

std::size_t SnapshotWriter::working_set_bytes() const {
  if (!enabled()) return 0;
  const Shared& s = *shared_;
  return s.left_raw.size_bytes() + s.right_raw.size_bytes() + s.left.size_bytes() +
         s.right.size_bytes() + s.disparity.size_bytes();
}

SnapshotRefusal SnapshotWriter::can_take() const {
  if (!enabled()) return SnapshotRefusal::disabled;
  {
    const std::lock_guard lock(shared_->mutex);
    if (shared_->pending) return SnapshotRefusal::busy;
  }
  const std::optional<int> stored = count();
  if (!stored) return SnapshotRefusal::unreadable;
  if (*stored >= limits_.max_count) return SnapshotRefusal::limit;
  struct statvfs fs {};
  if (::statvfs(shared_->directory.c_str(), &fs) == 0) {
    const std::uint64_t free = static_cast<std::uint64_t>(fs.f_bavail) * fs.f_frsize;
    if (free < bytes_each_ + limits_.min_free_bytes) return SnapshotRefusal::no_space;
  }
  return SnapshotRefusal::none;
}

bool SnapshotWriter::take(const FrameResult& r, std::uint16_t sequence) {
  if (can_take() != SnapshotRefusal::none) return false;
  Shared& s = *shared_;
  copy(r.left_raw, s.left_raw);
  copy(r.right_raw, s.right_raw);
  copy(r.left, s.left);
  copy(r.right, s.right);
  s.has_disparity = !r.disparity.empty();
  if (s.has_disparity) {
    for (int y = 0; y < r.disparity.height(); ++y) {
      const std::int16_t* in = r.disparity.row(y);
      std::uint16_t* out = s.disparity.view().row(y);
      for (int x = 0; x < r.disparity.width(); ++x) {
        out[x] = static_cast<std::uint16_t>(std::max<int>(in[x], 0));
      }
    }
  }
  s.frame = r.frame;
  {
    const std::lock_guard lock(s.mutex);
    s.pending = true;
    s.sequence = sequence;
  }
  s.wake.notify_all();
  return true;
}

std::optional<SnapshotDone> SnapshotWriter::finished() {
  if (!enabled()) return std::nullopt;
  const std::lock_guard lock(shared_->mutex);
  std::optional<SnapshotDone> done = shared_->done;
  shared_->done.reset();
  return done;
}

void SnapshotWriter::before_each_write(std::function<void()> hook) {
  if (enabled()) shared_->before_write = std::move(hook);
}

bool SnapshotWriter::flush(std::chrono::milliseconds timeout) {
  if (!enabled()) return true;
  std::unique_lock lock(shared_->mutex);
  return shared_->wake.wait_for(lock, timeout, [this] {
    return !shared_->pending || shared_->stopping;
  }) && !shared_->pending;
}

}  // namespace epipole::firmware

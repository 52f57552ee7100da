#include "epipole/firmware/snapshot.hpp"

#include <fcntl.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "epipole/core/error.hpp"

namespace epipole::firmware {

namespace {

bool write_bytes(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// A binary PGM (P5); 16-bit samples are big-endian, as the format says.
template <typename T>
bool write_pgm(const char* path, ImageView<const T> image) {
  const int fd = ::open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return false;
  char header[64];
  const int n = std::snprintf(header, sizeof header, "P5\n%d %d\n%d\n", image.width(),
                              image.height(), sizeof(T) == 1 ? 255 : 65535);
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
  return ::close(fd) == 0 && ok;
}

void copy(GrayView from, GrayImage& to) {
  for (int y = 0; y < from.height(); ++y) std::copy_n(from.row(y), from.width(), to.view().row(y));
}

}  // namespace

SnapshotWriter::SnapshotWriter(std::filesystem::path directory, int width, int height,
                               SnapshotLimits limits)
    : directory_(directory.string()), limits_(limits) {
  if (directory_.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  require(!ec, "snapshot directory ", directory_, ": ", ec.message());
  // Four 8-bit images, one 16-bit, and their headers.
  bytes_each_ = 6 * static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) + 5 * 64;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("snapshot-") && name.ends_with("-left-raw.pgm")) ++existing_;
  }
  for (GrayImage* image : {&left_raw_, &right_raw_, &left_, &right_}) {
    *image = GrayImage(width, height);
  }
  disparity_ = Image<std::uint16_t>(width, height);
  thread_ = std::thread([this] { run(); });
}

SnapshotWriter::~SnapshotWriter() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

SnapshotRefusal SnapshotWriter::can_take() const {
  if (!enabled()) return SnapshotRefusal::disabled;
  {
    const std::lock_guard lock(mutex_);
    if (pending_) return SnapshotRefusal::busy;
  }
  if (count() >= limits_.max_count) return SnapshotRefusal::limit;
  struct statvfs fs {};
  if (::statvfs(directory_.c_str(), &fs) == 0) {
    const std::uint64_t free = static_cast<std::uint64_t>(fs.f_bavail) * fs.f_frsize;
    if (free < bytes_each_ + limits_.min_free_bytes) return SnapshotRefusal::no_space;
  }
  return SnapshotRefusal::none;
}

bool SnapshotWriter::take(const FrameResult& r, std::uint16_t sequence) {
  if (can_take() != SnapshotRefusal::none) return false;
  copy(r.left_raw, left_raw_);
  copy(r.right_raw, right_raw_);
  copy(r.left, left_);
  copy(r.right, right_);
  has_disparity_ = !r.disparity.empty();
  if (has_disparity_) {
    for (int y = 0; y < r.disparity.height(); ++y) {
      const std::int16_t* in = r.disparity.row(y);
      std::uint16_t* out = disparity_.view().row(y);
      for (int x = 0; x < r.disparity.width(); ++x) {
        out[x] = static_cast<std::uint16_t>(std::max<int>(in[x], 0));
      }
    }
  }
  frame_ = r.frame;
  {
    const std::lock_guard lock(mutex_);
    pending_ = true;
    sequence_ = sequence;
  }
  wake_.notify_all();
  return true;
}

std::optional<SnapshotDone> SnapshotWriter::finished() {
  const std::lock_guard lock(mutex_);
  std::optional<SnapshotDone> done = done_;
  done_.reset();
  return done;
}

void SnapshotWriter::flush() {
  std::unique_lock lock(mutex_);
  wake_.wait(lock, [this] { return !pending_ || stopping_; });
}

bool SnapshotWriter::write_all() {
  char path[4096];
  bool ok = true;
  const auto name = [&](const char* what) {
    std::snprintf(path, sizeof path, "%s/snapshot-%06u-%s.pgm", directory_.c_str(), frame_, what);
    return path;
  };
  ok = write_pgm(name("left-raw"), ImageView<const std::uint8_t>(left_raw_.view())) && ok;
  ok = write_pgm(name("right-raw"), ImageView<const std::uint8_t>(right_raw_.view())) && ok;
  ok = write_pgm(name("left"), ImageView<const std::uint8_t>(left_.view())) && ok;
  ok = write_pgm(name("right"), ImageView<const std::uint8_t>(right_.view())) && ok;
  if (has_disparity_) {
    ok = write_pgm(name("disparity"), ImageView<const std::uint16_t>(disparity_.view())) && ok;
  }
  return ok;
}

void SnapshotWriter::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return pending_ || stopping_; });
    if (!pending_) return;
    lock.unlock();
    const bool ok = write_all();
    (ok ? written_ : failures_)++;
    lock.lock();
    done_ = SnapshotDone{sequence_, ok};
    pending_ = false;
    wake_.notify_all();
  }
}

}  // namespace epipole::firmware

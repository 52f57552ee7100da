#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "epipole/core/image.hpp"
#include "epipole/firmware/pipeline.hpp"

namespace epipole::firmware {

// How much the snapshot command may write (the board file's snapshot_limit and
// snapshot_min_free_mb): at most `max_count` snapshots in the folder (those already there
// count), and never so much that less than `min_free_bytes` stays free on its file system.
struct SnapshotLimits {
  int max_count = 200;
  std::uint64_t min_free_bytes = 64ull << 20;
};

enum class SnapshotRefusal {
  none,      // one can be taken
  disabled,  // no snapshot directory
  busy,      // the one before is still being written
  limit,     // max_count reached
  no_space,  // it would leave less than min_free_bytes free
};

// A snapshot written (ok) or not, with the sequence number of the command that asked for it.
struct SnapshotDone {
  std::uint16_t sequence = 0;
  bool ok = false;
};

// The snapshot command: the frame pair as captured and rectified, and its disparity, written as
// PGM files (disparity x16 as 16-bit PGM, 0 = invalid) by a thread of its own, so the frame loop
// only copies pixels into buffers allocated at start-up. Files:
//   DIR/snapshot-FRAME-{left,right}-raw.pgm, -{left,right}.pgm, -disparity.pgm
class SnapshotWriter {
 public:
  // An empty directory disables snapshots (take() refuses).
  SnapshotWriter(std::filesystem::path directory, int width, int height,
                 SnapshotLimits limits = {});
  ~SnapshotWriter();
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;

  bool enabled() const { return !directory_.empty(); }
  // Whether one could be taken now (the limits checked against the folder's file system).
  SnapshotRefusal can_take() const;
  // Copies the pair for the writer thread; false when can_take() would refuse. Its result comes
  // from finished(), with `sequence`.
  bool take(const FrameResult& result, std::uint16_t sequence);
  // The snapshot written since the last call, if any (never blocks).
  std::optional<SnapshotDone> finished();
  // Waits until the snapshot being written (if any) is on disk.
  void flush();
  std::uint64_t written() const { return written_.load(); }
  std::uint64_t failures() const { return failures_.load(); }
  // Snapshots in the folder: those there at start-up and those written since.
  int count() const { return existing_ + static_cast<int>(written_.load()); }
  // The copies of a pair it keeps for the writer thread (none when disabled).
  std::size_t working_set_bytes() const {
    return left_raw_.size_bytes() + right_raw_.size_bytes() + left_.size_bytes() +
           right_.size_bytes() + disparity_.size_bytes();
  }

 private:
  void run();
  bool write_all();

  std::string directory_;
  SnapshotLimits limits_;
  std::uint64_t bytes_each_ = 0;  // what one snapshot writes, at most
  int existing_ = 0;
  std::uint16_t sequence_ = 0;
  std::optional<SnapshotDone> done_;  // guarded by mutex_
  GrayImage left_raw_, right_raw_, left_, right_;
  Image<std::uint16_t> disparity_;
  bool has_disparity_ = false;
  std::uint32_t frame_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool pending_ = false;
  bool stopping_ = false;
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> failures_{0};
  std::thread thread_;
};

}  // namespace epipole::firmware

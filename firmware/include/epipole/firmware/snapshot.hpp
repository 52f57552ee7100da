#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "epipole/firmware/pipeline.hpp"

namespace epipole::firmware {

// How much the snapshot command may write (the board file's snapshot_limit and
// snapshot_min_free_mb): at most `max_count` snapshots in the folder (counted in the folder each
// time, so files removed by hand make room again), and never so much that less than
// `min_free_bytes` stays free on its file system.
struct SnapshotLimits {
  int max_count = 200;
  std::uint64_t min_free_bytes = 64ull << 20;
};

enum class SnapshotRefusal {
  none,        // one can be taken
  disabled,    // no snapshot directory
  busy,        // the one before is still being written
  limit,       // max_count reached
  no_space,    // it would leave less than min_free_bytes free
  unreadable,  // the folder cannot be listed, so neither counted nor numbered
};

// A snapshot written (ok) or not, with the sequence number of the command that asked for it.
struct SnapshotDone {
  std::uint16_t sequence = 0;
  bool ok = false;
};

// The snapshot command: the frame pair as captured and rectified, and its disparity, written as
// PGM files (disparity x16 as 16-bit PGM, 0 = invalid; a comment in each header names the frame)
// by a thread of its own, so the frame loop only copies pixels into buffers allocated at
// start-up. Files:
//   DIR/snapshot-N-{left,right}-raw.pgm, -{left,right}.pgm, -disparity.pgm
// N counts on from the highest number in the folder: never reused, across restarts too, and a
// file is never overwritten (created exclusively). The folder is made again when it was removed;
// each file and then the folder are synced before the snapshot counts as written.
class SnapshotWriter {
 public:
  // An empty directory disables snapshots (take() refuses).
  SnapshotWriter(std::filesystem::path directory, int width, int height,
                 SnapshotLimits limits = {});
  // Waits up to kStopWait for a snapshot being written; a file system that stalls longer is left
  // to the writer thread, which outlives the writer (the process is stopping).
  ~SnapshotWriter();
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;

  static constexpr std::chrono::milliseconds kStopWait{2000};

  bool enabled() const;
  // Whether one could be taken now (the limits checked against the folder and its file system).
  SnapshotRefusal can_take() const;
  // Copies the pair for the writer thread; false when can_take() would refuse. Its result comes
  // from finished(), with `sequence`.
  bool take(const FrameResult& result, std::uint16_t sequence);
  // The snapshot written since the last call, if any (never blocks).
  std::optional<SnapshotDone> finished();
  // Waits until the snapshot being written (if any) is on disk, at most `timeout`: false when it
  // is still being written then (a stalled file system).
  bool flush(std::chrono::milliseconds timeout);
  // Runs on the writer thread before each snapshot is written, before the first take() (tests:
  // a file system that stalls, or throws).
  void before_each_write(std::function<void()> hook);
  std::uint64_t written() const;
  std::uint64_t failures() const;
  // Snapshots in the folder now (their left raw files); nothing when it cannot be listed.
  std::optional<int> count() const;
  // The copies of a pair it keeps for the writer thread (none when disabled).
  std::size_t working_set_bytes() const;

  // What the writer thread uses (snapshot.cpp): owned with it, so it may outlive the writer.
  struct Shared;

 private:
  SnapshotLimits limits_;
  std::uint64_t bytes_each_ = 0;  // what one snapshot writes, at most
  std::shared_ptr<Shared> shared_;
  std::thread thread_;
};

}  // namespace epipole::firmware

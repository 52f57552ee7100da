#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include "epipole/core/image.hpp"
#include "epipole/firmware/pipeline.hpp"

namespace epipole::firmware {

// The snapshot command: the frame pair as captured and rectified, and its disparity, written as
// PGM files (disparity x16 as 16-bit PGM, 0 = invalid) by a thread of its own, so the frame loop
// only copies pixels into buffers allocated at start-up. Files:
//   DIR/snapshot-FRAME-{left,right}-raw.pgm, -{left,right}.pgm, -disparity.pgm
class SnapshotWriter {
 public:
  // An empty directory disables snapshots (take() refuses).
  SnapshotWriter(std::filesystem::path directory, int width, int height);
  ~SnapshotWriter();
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;

  bool enabled() const { return !directory_.empty(); }
  // False when disabled or the previous snapshot is still being written.
  bool take(const FrameResult& result);
  // Waits until the snapshot being written (if any) is on disk.
  void flush();
  std::uint64_t written() const { return written_.load(); }
  std::uint64_t failures() const { return failures_.load(); }

 private:
  void run();
  bool write_all();

  std::string directory_;
  GrayImage left_raw_, right_raw_, left_, right_;
  Image<std::uint16_t> disparity_;
  bool has_disparity_ = false;
  std::uint32_t frame_ = 0;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool pending_ = false;
  bool stopping_ = false;
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> failures_{0};
  std::thread thread_;
};

}  // namespace epipole::firmware

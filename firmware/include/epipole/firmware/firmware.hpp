#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/firmware/board.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/frame_loop.hpp"
#include "epipole/firmware/link.hpp"
#include "epipole/firmware/memory_report.hpp"
#include "epipole/firmware/pipeline.hpp"

namespace epipole::firmware {

// The calibration a board runs with: the one the section of its cameras' backend names
// (hal::BackendSettings::calibration: a scene's own), else its own; none when it names none, or
// when its own file does not exist yet (a board fresh from its package, before `epipole
// calibrate`): the firmware then runs uncalibrated: the images are taken as rectified, nothing gets
// a depth, and every health message says so (protocol::kHealthNotCalibrated). A file that is there
// but does not read, or a backend section's that is missing, is an Error.
std::optional<calib::StereoCalibration> load_board_calibration(const BoardConfig& config);
// The file that calibration comes from: the one the cameras' backend names (a simulated scene's,
// a recording), else the board's `calibration` (empty when it names none).
std::filesystem::path board_calibration_file(const BoardConfig& config);

// Scheduling the board asks for (threads: affinity, SCHED_FIFO), before any thread of the
// firmware starts: the affinity for the calling thread, which every thread created after it
// inherits; the real-time priority each thread then takes for its role when it starts
// (thread_roles.hpp). Returns what could not be done, one line each; the firmware runs on.
std::vector<std::string> apply_scheduling(const BoardConfig::Threads& threads);

// What `epipole-fw --check` prints: the memory report of the firmware made for `config` with its
// cameras and trigger replaced by stand-ins of the same size (hal::stand_in_for_devices) and its
// link by its queue alone, so that every buffer of the frame loop is allocated as on the board
// but no device is opened (the snapshots' copies are sized in a temporary folder; the board's own
// snapshot folder is not made). Throws Error as the firmware would: a calibration that does not
// fit, a compiled cascade that does not read, a total over the board's memory budget.
MemoryReport check_memory(BoardConfig config);

// The whole firmware for one board: its hardware, the vision pipeline, the serial link and the
// frame loop, all made (and every buffer allocated) by the constructor, which throws Error
// naming the file and the setting when something in the configuration cannot work.
class Firmware {
 public:
  explicit Firmware(BoardConfig config);
  // On this board instead of the one the configuration makes (stand-ins); `offline`: its
  // outputs made to be measured only (check_memory()).
  Firmware(BoardConfig config, std::unique_ptr<Board> board, bool offline = false);
  ~Firmware();

  RunSummary run(std::uint64_t max_frames, const std::atomic<bool>& stop);
  // The memory report's part of the cameras' own frame buffers (and what their backend holds
  // for them: hal::BackendBoard::memory_bytes).
  static constexpr const char* kCameras = "cameras";

  const BoardConfig& config() const { return config_; }
  Board& board() { return *board_; }
  Pipeline& pipeline() { return *pipeline_; }
  Link& link() { return *link_; }
  Outputs& outputs() { return *outputs_; }
  FrameLoop& frame_loop() { return *loop_; }
  const std::optional<calib::StereoCalibration>& calibration() const { return calibration_; }
  // The calibration file the board names that is not there yet; empty when it names none or
  // the calibration was loaded (a backend section's calibration or a file that does not read
  // would have stopped the constructor).
  std::filesystem::path missing_calibration() const {
    return calibration_ ? std::filesystem::path() : config_.calibration;
  }
  // The frame loop's buffers, part by part: every stage's, the link's queue, the loop's own,
  // the snapshots' copies, each output's, the cameras' frame buffers on the heap (a driver's
  // mmap'ed ones are the kernel's) and what their backend holds for them (hal::BackendBoard). The
  // board's memory_budget_mb bounds the total.
  MemoryReport memory_report() const;
  std::size_t working_set_bytes() const { return memory_report().total(); }

 private:
  void build(std::unique_ptr<Board> board, bool offline = false);

  BoardConfig config_;
  std::optional<calib::StereoCalibration> calibration_;
  std::unique_ptr<Board> board_;
  std::unique_ptr<Pipeline> pipeline_;
  std::unique_ptr<Link> link_;
  std::unique_ptr<Outputs> outputs_;
  std::unique_ptr<FrameLoop> loop_;
};

}  // namespace epipole::firmware

#pragma once

// The rig corrected in place while the firmware runs (docs/calibration.md, "Correcting the
// drift"): the right camera's turn, estimated by the sparse stage over a window of pairs, undone
// by rebuilding the right camera's rectification map on a thread of its own, the new map taking
// the old one's place between two pairs.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/camera_turn.hpp"
#include "epipole/calib/drift_estimator.hpp"
#include "epipole/vision/remap.hpp"

namespace epipole::firmware {

struct BoardConfig;

class RigCorrection {
 public:
  enum class Outcome {
    none,                // online correction is off, or nothing new to decide
    started,             // the map is being rebuilt; install() puts it in place
    busy,                // a map is being rebuilt already
    no_estimate,         // the window has no estimate yet (too few pairs with matches)
    nothing_to_correct,  // the rows are already within calibration_health.min_offset_px
    would_not_lower,     // undoing the turn would not lower the rows' offsets by a fifth
    out_of_range,        // the rig would be turned beyond calibration_health.max_correction_deg
  };

  // `rig`: the calibration file's. Starts the thread that rebuilds maps (start-up: it allocates
  // the spare map; nothing after).
  RigCorrection(const calib::StereoCalibration& rig, const BoardConfig& board);
  ~RigCorrection();
  RigCorrection(const RigCorrection&) = delete;
  RigCorrection& operator=(const RigCorrection&) = delete;

  // The frame loop's thread, after a pair. consider(): with calibration_health.online_correction
  // on and two thirds of the window's pairs with matches, a correction when the estimate says
  // the rig turned (else none).
  // correct(): the same now, whatever online_correction says (the recalibrate command), from a
  // window of at least 3 pairs. Neither waits.
  Outcome consider(const calib::DriftEstimate& estimate);
  Outcome correct(const calib::DriftEstimate& estimate);

  // The rectify stage, before a pair (no task running): when a rebuilt map is ready, it takes the
  // place of `right`'s and the rig in use follows. True then.
  bool install(vision::Rectifier& right);

  // The save_calibration command (the frame loop's thread): the rig in use written to
  // corrected_file() by the thread, through a temporary file and a rename; the board's own file
  // is kept. False when a map is being rebuilt or a file written (busy); the result comes from
  // saved() once written: true, or false with save_error() saying why.
  bool request_save();
  std::optional<bool> saved();
  const std::string& save_error() const { return save_error_; }
  // `<stem>-corrected.yaml` beside the file the calibration came from (firmware.hpp's
  // board_calibration_file: a simulated scene's, a recording, the board's).
  const std::filesystem::path& corrected_file() const { return corrected_file_; }

  // The calibration in use: the file's, its right camera turned by every correction installed.
  // Changes only in install(); generation() counts the changes.
  const calib::StereoCalibration& rig() const { return rig_; }
  std::uint32_t generation() const { return generation_; }
  // The correction installed, relative to the file (pitch and roll; yaw 0), and how many.
  calib::CameraTurn total() const { return calib::turn_angles(total_); }
  int corrections() const { return static_cast<int>(generation_); }
  bool rebuilding() const {
    const int state = state_.load(std::memory_order_acquire);
    return state == kRequested || state == kReady;
  }
  // A rebuilt map waits for install() (the next pair's rectification).
  bool map_ready() const { return state_.load(std::memory_order_acquire) == kReady; }
  // The maps thread has a map to rebuild or a file to write, not done yet.
  bool busy() const {
    const int state = state_.load(std::memory_order_acquire);
    return state == kRequested || state == kSaveRequested;
  }
  // The rows' median offset before and (predicted) after the correction last started.
  double offset_before_px() const { return before_px_; }
  double offset_after_px() const { return after_px_; }
  std::size_t working_set_bytes() const { return spare_.size_bytes(); }

 private:
  enum State : int { kIdle, kRequested, kReady, kSaveRequested, kSaved, kSaveFailed, kStopping };
  Outcome decide(const calib::DriftEstimate& estimate, int min_pairs);
  void rebuild_maps();

  calib::StereoCalibration rig_;
  bool online_;
  double max_correction_;  // radians
  double min_offset_px_;
  int window_pairs_;
  Eigen::Matrix3d total_ = Eigen::Matrix3d::Identity();    // installed, relative to the file
  Eigen::Matrix3d pending_ = Eigen::Matrix3d::Identity();  // the turn being undone
  calib::CameraCalibration pending_right_;  // the right camera with its new rectification
  vision::RemapMap spare_;                  // the map being rebuilt, or the one replaced
  double before_px_ = 0, after_px_ = 0;
  std::uint32_t generation_ = 0;
  std::filesystem::path corrected_file_;
  std::string save_error_;  // the thread's, read once saved() said false
  bool idle_priority_;      // threads.maps: SCHED_IDLE, or the scheduling it starts with
  // The frame loop and the maps thread hand work over by this alone (C++20 wait and notify).
  std::atomic<int> state_{kIdle};
  std::thread builder_;
};

}  // namespace epipole::firmware

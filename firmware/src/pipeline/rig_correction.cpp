#include "epipole/firmware/rig_correction.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

#include "epipole/calib/rectification_map.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/firmware/thread_roles.hpp"

namespace epipole::firmware {

namespace {

// A share of the offsets a correction must take away (its prediction, from the window).
constexpr double kMustLower = 0.2;

// Where save_calibration writes: beside the file the calibration came from (a recording's too),
// `<its stem>-corrected.yaml`; none without one.
std::filesystem::path corrected_file_of(const std::filesystem::path& file) {
  if (file.empty()) return {};
  return file.parent_path() / (file.stem().string() + "-corrected.yaml");
}

}  // namespace

RigCorrection::RigCorrection(const calib::StereoCalibration& rig, const BoardConfig& board)
    : rig_(rig),
      online_(board.calibration_health.online_correction),
      max_correction_(radians(board.calibration_health.max_correction_deg)),
      min_offset_px_(board.calibration_health.min_offset_px),
      window_pairs_(board.calibration_health.window_pairs),
      pending_right_(rig.right),
      spare_(rig.width, rig.height),
      corrected_file_(corrected_file_of(board_calibration_file(board))),
      idle_priority_(board.threads.maps_idle),
      builder_([this] { rebuild_maps(); }) {}

RigCorrection::~RigCorrection() {
  // A rebuild or a write under way finishes (the thread cannot be stopped inside one), then the
  // thread sees the stop instead of storing its result.
  state_.store(kStopping, std::memory_order_release);
  state_.notify_all();
  builder_.join();
}

RigCorrection::Outcome RigCorrection::consider(const calib::DriftEstimate& estimate) {
  // Two thirds of the window's pairs with matches: a dark or blurred pair does not hold it off.
  return online_ ? decide(estimate, std::max(3, (2 * window_pairs_ + 2) / 3)) : Outcome::none;
}

RigCorrection::Outcome RigCorrection::correct(const calib::DriftEstimate& estimate) {
  return decide(estimate, 3);
}

RigCorrection::Outcome RigCorrection::decide(const calib::DriftEstimate& e, int min_pairs) {
  if (state_.load(std::memory_order_acquire) != kIdle) return Outcome::busy;
  if (!e.valid || e.pairs < min_pairs) return Outcome::no_estimate;
  if (e.median_offset_px < min_offset_px_) return Outcome::nothing_to_correct;
  // Undoing the turn must take away a fifth of the offsets, and the turn must stand out of the
  // pairs' spread (a static scene's spread is 0: then the first test decides).
  const bool stands_out =
      std::abs(e.pitch) > 3 * e.pitch_sigma || std::abs(e.roll) > 3 * e.roll_sigma;
  if (e.median_corrected_px > (1 - kMustLower) * e.median_offset_px || !stands_out) {
    return Outcome::would_not_lower;
  }
  const Eigen::Matrix3d turn = calib::turn_rotation({e.pitch, e.roll, 0});
  const calib::CameraTurn total = calib::turn_angles(total_ * turn);
  if (std::abs(total.pitch) > max_correction_ || std::abs(total.roll) > max_correction_) {
    return Outcome::out_of_range;
  }
  pending_ = turn;
  pending_right_.rectification = rig_.right.rectification * turn;
  before_px_ = e.median_offset_px;
  after_px_ = e.median_corrected_px;
  // No lock is shared with the maps thread: at its low priority it could hold one while the
  // frame loop waits for it (an inversion of their priorities).
  state_.store(kRequested, std::memory_order_release);
  state_.notify_one();
  return Outcome::started;
}

bool RigCorrection::install(vision::Rectifier& right) {
  if (state_.load(std::memory_order_acquire) != kReady) return false;
  right.swap_map(spare_);
  calib::turn_right_camera(rig_, pending_);
  total_ = total_ * pending_;
  ++generation_;
  state_.store(kIdle, std::memory_order_release);
  return true;
}

bool RigCorrection::request_save() {
  if (corrected_file_.empty()) {
    save_error_ = "the board names no calibration file to write beside";
    return false;
  }
  int idle = kIdle;
  if (!state_.compare_exchange_strong(idle, kSaveRequested, std::memory_order_acq_rel)) {
    return false;
  }
  state_.notify_one();
  return true;
}

std::optional<bool> RigCorrection::saved() {
  const int state = state_.load(std::memory_order_acquire);
  if (state != kSaved && state != kSaveFailed) return std::nullopt;
  state_.store(kIdle, std::memory_order_release);
  return state == kSaved;
}

// The thread: each request's map into the spare, then ready for install(); or the rig in use
// written (no install can change it meanwhile: the state is not idle).
void RigCorrection::rebuild_maps() {
  if (idle_priority_) {
    enter_thread_role_or_say(ThreadRole::maps);
  } else {
    name_thread(ThreadRole::maps);
  }
  for (;;) {
    int state = state_.load(std::memory_order_acquire);
    while (state != kRequested && state != kSaveRequested && state != kStopping) {
      state_.wait(state, std::memory_order_acquire);
      state = state_.load(std::memory_order_acquire);
    }
    if (state == kStopping) return;
    int done = kReady;
    if (state == kSaveRequested) {
      try {
        calib::StereoCalibration corrected = rig_;
        corrected.date = calib::utc_now();
        corrected.source = "epipole-fw: corrected while running (" + rig_.source + ")";
        calib::save_calibration(corrected_file_, corrected);
        done = kSaved;
      } catch (const std::exception& e) {
        save_error_ = e.what();
        done = kSaveFailed;
      }
    } else {
      calib::fill_fixed_point_map(pending_right_, spare_.xy(), spare_.fractions());
    }
    // Unless the destructor asked for the stop meanwhile.
    if (!state_.compare_exchange_strong(state, done, std::memory_order_acq_rel)) return;
  }
}

}  // namespace epipole::firmware

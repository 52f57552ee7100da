#pragma once

// How far the right camera has turned since the calibration, from the rows of its matches: the
// epipolar constraint of a calibrated pair, RANSAC on each pair's matches, then least squares
// over a window of pairs (docs/calibration.md, "The drift").
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/health.hpp"
#include "epipole/core/splitmix.hpp"

namespace epipole::calib {

struct DriftEstimatorConfig {
  int max_matches = 2000;  // a pair's matches add_pair() takes at most
  int window_pairs = 30;   // the pairs the estimate is made of, 3..1000
  int pair_matches = 256;  // a pair's inliers kept (evenly over its matches), 8..4096
  int min_matches = 12;    // a pair with fewer inliers adds nothing
  int iterations = 64;     // RANSAC's samples per pair
  double inlier_px = 0.5;  // a match's row residual under the model, pixels
  std::uint64_t seed = 0x5EEDu;
};

// The right camera's turn since the calibration, pitch and roll (calib::CameraTurn's axes and
// signs, radians), with one standard deviation each: the spread of the window's pairs' own
// estimates over the square root of their count. Yaw is not seen by rows (docs).
struct DriftEstimate {
  bool valid = false;  // pairs >= 3
  double pitch = 0, roll = 0;
  double pitch_sigma = 0, roll_sigma = 0;
  int pairs = 0;    // of the window, with matches
  int matches = 0;  // the window's inliers
  // The window's inliers' median |row offset| (pixels), as they are and once the turn is undone.
  double median_offset_px = 0;
  double median_corrected_px = 0;
};

// Fixed memory: the constructor allocates the window (window_pairs x pair_matches matches);
// add_pair() and estimate() never allocate.
class DriftEstimator {
 public:
  // The rig's rectified cameras (P1, P2: f, cx, cy) and R2, which turns the estimate from the
  // rectified frame into the right camera's. Throws Error for a configuration out of range.
  DriftEstimator(const StereoCalibration& rig, const DriftEstimatorConfig& config);

  // A pair's matches between the rectified images, sub-pixel in both coordinates (right_x with
  // the disparity, right_y measured), at most max_matches (Error). Returns the pair's inliers.
  int add_pair(std::span<const RectifiedMatch> matches);
  DriftEstimate estimate() const;
  // Forgets the window (after the maps changed: its matches were measured through the old ones).
  void clear();
  // A new rig (a correction applied): its R2, and the window forgotten.
  void set_rig(const StereoCalibration& rig);
  std::size_t working_set_bytes() const;

 private:
  // A match in normalised rectified coordinates: the left row, the right column and row.
  struct Observation {
    double yl, xr, yr;
  };
  struct PairFit {
    double wx = 0, wz = 0;
    bool valid = false;
  };
  // The exact constraint's residual (normalised rows) of a match under the turn M (mt = M^T).
  static double residual(const Eigen::Matrix3d& mt, const Observation& o);
  PairFit fit_pair(std::span<const Observation> pair);
  // Gauss-Newton on the exact constraint from (wx, wz); the observations with inlier set.
  PairFit least_squares(std::span<const Observation> observations,
                        std::span<const std::uint8_t> use, double wx, double wz) const;

  DriftEstimatorConfig config_;
  double fx_ = 1, fy_ = 1, left_cy_ = 0, right_cx_ = 0, right_cy_ = 0;
  Eigen::Matrix3d r2_ = Eigen::Matrix3d::Identity();
  SplitMix64 random_;
  std::vector<Observation> scratch_;      // the pair's matches, normalised
  std::vector<std::uint8_t> inlier_;      // per scratch entry
  std::vector<Observation> window_;       // window_pairs slots of pair_matches
  std::vector<std::uint8_t> window_use_;  // per window_ entry: holds a match
  mutable std::vector<double> offsets_;   // estimate()'s medians
  std::vector<int> slot_count_;           // inliers in each slot
  std::vector<PairFit> slot_fit_;         // each slot's own estimate
  int next_slot_ = 0;
};

}  // namespace epipole::calib

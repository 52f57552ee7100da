#pragma once

#include <cstddef>
#include <memory>
#include <span>

namespace epipole::calib {

// A match between the rectified left and right images (pixels).
struct RectifiedMatch {
  float left_x = 0, left_y = 0;
  float right_x = 0, right_y = 0;
};

// How well the rectification still holds: in a rectified pair a point lies on the same row in
// both images, so the vertical offset of matches measures how far the rig has drifted from its
// calibration (a rotation of the right camera by a small angle a about the baseline moves its
// rectified image by about f * a pixels vertically).
struct HealthFigure {
  int matches = 0;              // matches measured (the non-finite ones are skipped)
  double median_px = 0;         // median of |right_y - left_y|
  double p90_px = 0;            // 90th percentile of |right_y - left_y|
  double median_signed_px = 0;  // median of right_y - left_y: the direction of the drift
};

// The calibration health figure of sparse matches. Percentiles interpolate linearly between
// order statistics (position p * (n - 1)). With no finite match every figure is NaN.
//
// Fixed memory: the constructor allocates room for max_matches offsets (8 bytes each);
// measure() never allocates.
class CalibrationHealth {
 public:
  // Throws Error if max_matches < 1.
  explicit CalibrationHealth(int max_matches);

  // Throws Error if there are more than max_matches matches.
  HealthFigure measure(std::span<const RectifiedMatch> matches);

  int max_matches() const { return capacity_; }
  std::size_t working_set_bytes() const { return 2 * static_cast<std::size_t>(capacity_) * 4; }

 private:
  int capacity_;
  std::unique_ptr<float[]> absolute_;
  std::unique_ptr<float[]> signed_;
};

}  // namespace epipole::calib

#pragma once

// The depth of a Viola-Jones detection when a disparity map of the same (rectified left) image
// is available: the median valid disparity inside the box (vision::BoxDisparity), converted to
// metres with the calibration's Q (calib::Triangulator::depth). The frame loop calls this per
// detection; nothing here allocates after construction.

#include <span>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/image.hpp"
#include "epipole/vision/box_disparity.hpp"
#include "epipole/vision/cascade.hpp"

namespace epipole::firmware {

struct DetectionDepth {
  bool valid = false;      // the box holds valid disparities and they give a point in front
  float disparity = 0.0f;  // the median valid disparity in the box, pixels
  double depth = 0.0;      // Z in the rectified left camera frame, units of the calibration's T
};

class DetectionDepthEstimator {
 public:
  // `triangulator` must outlive the estimator; max_disparity is the matcher's range.
  DetectionDepthEstimator(const calib::Triangulator& triangulator, int max_disparity);

  // The depth of one box of `disparity` (int16 x16, vision::kInvalidDisparity where unknown).
  DetectionDepth estimate(const vision::Detection& detection,
                          ImageView<const std::int16_t> disparity);
  // Every detection, into out[i] (out must be at least as long).
  void estimate(std::span<const vision::Detection> detections,
                ImageView<const std::int16_t> disparity, std::span<DetectionDepth> out);

 private:
  const calib::Triangulator& triangulator_;
  vision::BoxDisparity median_;
};

}  // namespace epipole::firmware

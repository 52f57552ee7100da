#include "epipole/firmware/detection_depth.hpp"

#include <cmath>

#include "epipole/core/error.hpp"

namespace epipole::firmware {

DetectionDepthEstimator::DetectionDepthEstimator(const calib::Triangulator& triangulator,
                                                 int max_disparity)
    : triangulator_(triangulator), median_(max_disparity) {}

DetectionDepth DetectionDepthEstimator::estimate(const vision::Detection& detection,
                                                 ImageView<const std::int16_t> disparity) {
  DetectionDepth out;
  const auto median =
      median_.median(disparity, detection.x, detection.y, detection.width, detection.height);
  if (!median) return out;
  out.disparity = static_cast<float>(*median) / 16.0f;
  const double z = triangulator_.depth(*median / 16.0);
  if (!std::isfinite(z)) return out;
  out.depth = z;
  out.valid = true;
  return out;
}

void DetectionDepthEstimator::estimate(std::span<const vision::Detection> detections,
                                       ImageView<const std::int16_t> disparity,
                                       std::span<DetectionDepth> out) {
  require(out.size() >= detections.size(), "detection depths: ", out.size(), " slots for ",
          detections.size(), " detections");
  for (std::size_t i = 0; i < detections.size(); ++i) out[i] = estimate(detections[i], disparity);
}

}  // namespace epipole::firmware

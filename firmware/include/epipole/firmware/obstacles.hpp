#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/image.hpp"
#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::firmware {

struct ObstacleConfig {
  int width = 0;  // the disparity image
  int height = 0;
  int max_disparity = 64;
  int sectors = 72;        // 1..protocol::kMaxSectors, evenly split over the horizontal view
  double band_top = 0.25;  // rows searched, fractions of the height
  double band_bottom = 0.75;
  double min_depth_m = 0.2;   // nearer is reported as this
  double max_depth_m = 20.0;  // farther counts as nothing seen
  // A sector's nearest obstacle must cover at least this share of the sector's band pixels (and
  // at least min_pixels), so that a few wrong disparities do not make phantom obstacles.
  double min_share = 0.002;
  int min_pixels = 12;
  // 1..255: only pixels whose disparity confidence (vision::StereoMatcher::confidence()) is at
  // least this count; 0: every valid pixel.
  int min_confidence = 0;
};

// The nearest depth per angular sector of the rectified left view, from a disparity image
// (x16, vision::kInvalidDisparity where unknown): per sector, the largest integer disparity
// that enough pixels of the sector's band reach, refined to the mean disparity of the pixels of
// that integer bin and converted to depth (Z, metres) with Q. Sectors go left to
// right and split the view's horizontal field of view evenly by angle (pinhole, from the
// rectified camera's fx and cx).
//
// Fixed memory: the constructor allocates the column-to-sector table and a histogram of
// integer disparities per sector; measure() never allocates.
class ObstacleSectors {
 public:
  // fx, cx: the rectified left camera (P1). Throws Error for a bad configuration.
  ObstacleSectors(const ObstacleConfig& config, const calib::Triangulator& triangulator, double fx,
                  double cx);

  // `confidence`: the disparity's, required with config.min_confidence (ignored without).
  const protocol::Obstacles& measure(ImageView<const std::int16_t> disparity, std::uint32_t frame,
                                     ImageView<const std::uint8_t> confidence = {});
  // The view's horizontal field of view, degrees.
  double field_of_view_deg() const { return fov_deg_; }
  // Horizontal angle of a sector's centre from the optical axis, degrees (positive to the right).
  double sector_centre_deg(int sector) const;
  const ObstacleConfig& config() const { return config_; }
  std::size_t working_set_bytes() const;

 private:
  ObstacleConfig config_;
  const calib::Triangulator& triangulator_;
  double fov_deg_ = 0;
  double first_edge_deg_ = 0;
  std::vector<std::uint8_t> sector_of_column_;
  std::vector<std::uint32_t> histogram_;  // sectors x max_disparity: pixel counts
  std::vector<std::uint32_t> sums_;       // and the sums of their disparities x16
  std::vector<std::uint32_t> band_pixels_;
  protocol::Obstacles result_;
};

}  // namespace epipole::firmware

#pragma once

#include <cstdint>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/image.hpp"
#include "epipole/firmware/depth_cells.hpp"
#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::firmware {

// The obstacle sectors: one row of cells (rows stays 1; the columns are the sectors, at most
// protocol::kMaxSectors) within a band of rows.
struct ObstacleConfig : DepthCellsConfig {
  ObstacleConfig() {
    columns = 72;
    band_top = 0.25;
    band_bottom = 0.75;
  }
};

// The nearest depth per angular sector of the rectified left view within a band of rows: one
// row of DepthCells (depth_cells.hpp), sectors left to right, splitting the view's horizontal
// field of view evenly by angle (pinhole, from the rectified camera's fx and cx).
//
// Fixed memory: the constructor allocates everything; measure() never allocates.
class ObstacleSectors {
 public:
  // fx, cx: the rectified left camera (P1). Throws Error for a bad configuration.
  ObstacleSectors(const ObstacleConfig& config, const calib::Triangulator& triangulator, double fx,
                  double cx);

  // `confidence`: the disparity's, required with config.min_confidence (ignored without).
  // `counted`: only the pixels in this half-space count (those above the ground); null: all.
  const protocol::Obstacles& measure(ImageView<const std::int16_t> disparity, std::uint32_t frame,
                                     ImageView<const std::uint8_t> confidence = {},
                                     const PixelHalfSpace* counted = nullptr);
  // The view's horizontal field of view, degrees.
  double field_of_view_deg() const { return cells_.horizontal_fov_deg(); }
  // Horizontal angle of a sector's centre from the optical axis, degrees (positive to the right).
  double sector_centre_deg(int sector) const { return cells_.column_centre_deg(sector); }
  const ObstacleConfig& config() const { return config_; }
  std::size_t working_set_bytes() const { return cells_.working_set_bytes(); }

 private:
  ObstacleConfig config_;
  DepthCells cells_;
  protocol::Obstacles result_;
};

}  // namespace epipole::firmware

#include "epipole/firmware/depth_grid.hpp"

#include <cmath>

#include "epipole/core/error.hpp"

namespace epipole::firmware {

namespace {

DepthCellsConfig whole_view(DepthCellsConfig c) {
  // Each way first: their product must not overflow.
  require(c.columns >= 1 && c.rows >= 1 && c.columns <= protocol::kMaxGridCells &&
              c.rows <= protocol::kMaxGridCells && c.columns * c.rows <= protocol::kMaxGridCells,
          "depth_grid: ", c.columns, "x", c.rows, " cells is not within 1..",
          protocol::kMaxGridCells, " cells");
  c.band_top = 0;
  c.band_bottom = 1;
  return c;
}

std::uint16_t centidegrees(double degrees) {
  return static_cast<std::uint16_t>(std::lround(degrees * 100));
}

}  // namespace

DepthGrid::DepthGrid(const DepthCellsConfig& config, const calib::Triangulator& triangulator,
                     RectifiedPinhole camera)
    : cells_(whole_view(config), triangulator, camera, "depth_grid") {
  result_.columns = static_cast<std::uint8_t>(config.columns);
  result_.count = static_cast<std::uint8_t>(config.columns * config.rows);
  result_.field_of_view_centideg = centidegrees(cells_.horizontal_fov_deg());
  result_.vertical_field_of_view_centideg = centidegrees(cells_.vertical_fov_deg());
}

const protocol::DepthGrid& DepthGrid::measure(ImageView<const std::int16_t> disparity,
                                              std::uint32_t frame,
                                              ImageView<const std::uint8_t> confidence) {
  cells_.measure(disparity, confidence, result_.nearest_mm);
  result_.frame = frame;
  return result_;
}

}  // namespace epipole::firmware

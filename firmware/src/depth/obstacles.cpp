#include "epipole/firmware/obstacles.hpp"

#include <cmath>

#include "epipole/core/error.hpp"

namespace epipole::firmware {

namespace {

const ObstacleConfig& checked(const ObstacleConfig& o) {
  require(o.columns >= 1 && o.columns <= protocol::kMaxSectors, "obstacles: ", o.columns,
          " sectors is outside 1..", protocol::kMaxSectors);
  require(o.rows == 1, "obstacles: the sectors are one row of cells, not ", o.rows);
  return o;
}

}  // namespace

ObstacleSectors::ObstacleSectors(const ObstacleConfig& config,
                                 const calib::Triangulator& triangulator, double fx, double cx)
    : config_(config),
      cells_(checked(config), triangulator, RectifiedPinhole{fx, cx, 0, 0}, "obstacles") {}

const protocol::Obstacles& ObstacleSectors::measure(ImageView<const std::int16_t> disparity,
                                                    std::uint32_t frame,
                                                    ImageView<const std::uint8_t> confidence,
                                                    const PixelHalfSpace* counted) {
  cells_.measure(disparity, confidence, result_.nearest_mm, counted);
  result_.frame = frame;
  result_.count = static_cast<std::uint8_t>(config_.columns);
  result_.field_of_view_centideg =
      static_cast<std::uint16_t>(std::lround(cells_.horizontal_fov_deg() * 100));
  return result_;
}

}  // namespace epipole::firmware

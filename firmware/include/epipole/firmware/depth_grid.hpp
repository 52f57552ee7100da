#pragma once

#include <cstdint>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/image.hpp"
#include "epipole/firmware/depth_cells.hpp"
#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::firmware {

// The depth grid sent to the robot (protocol::DepthGrid): the nearest depth in each of
// columns x rows cells over the whole rectified left view (DepthCells with the band the whole
// image), for a coarse map of what is in front of it.
//
// Fixed memory: the constructor allocates everything; measure() never allocates.
class DepthGrid {
 public:
  // config.columns x config.rows at most protocol::kMaxGridCells; the band is the whole image.
  // Throws Error for a bad configuration.
  DepthGrid(const DepthCellsConfig& config, const calib::Triangulator& triangulator,
            RectifiedPinhole camera);

  // `confidence`: the disparity's, required with config.min_confidence (ignored without).
  const protocol::DepthGrid& measure(ImageView<const std::int16_t> disparity, std::uint32_t frame,
                                     ImageView<const std::uint8_t> confidence = {});
  const DepthCellsConfig& config() const { return cells_.config(); }
  std::size_t working_set_bytes() const { return cells_.working_set_bytes(); }

 private:
  DepthCells cells_;
  protocol::DepthGrid result_;
};

}  // namespace epipole::firmware

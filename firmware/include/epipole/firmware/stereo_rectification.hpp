#pragma once

#include <cstdint>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/rectification_map.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/vision/remap.hpp"

namespace epipole::firmware {

// The calibration's fixed-point map as the remap kernel's map (a copy of the two planes; the
// layouts are the same, calib/rectification_map.hpp).
vision::RemapMap to_remap_map(const calib::FixedPointMap& map);

// The two rectifiers of a calibrated pair: source and rectified images of the calibration's
// image size. Start-up code (builds the maps); the rectifiers never allocate per frame.
// own_output false: they rectify only into their caller's images (vision::RectifierConfig).
struct StereoRectifiers {
  vision::Rectifier left;
  vision::Rectifier right;
};
StereoRectifiers make_stereo_rectifiers(const calib::StereoCalibration& calibration,
                                        SimdPath path = best_simd_path(), std::uint8_t border = 0,
                                        bool own_output = true);

}  // namespace epipole::firmware

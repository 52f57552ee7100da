#pragma once

#include <optional>
#include <string>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/firmware/stereo_rectification.hpp"

namespace epipole::tools {

// A stereo pair read from two files, checked to have one size, and rectified as the firmware
// does when a calibration file is given (its size must be the images'). left and right are
// the (rectified) views to match.
struct StereoInput {
  GrayImage left_image;
  GrayImage right_image;
  std::optional<calib::StereoCalibration> calibration;
  std::optional<firmware::StereoRectifiers> rectifiers;
  GrayView left;
  GrayView right;
};

StereoInput load_stereo_input(const std::string& left, const std::string& right,
                              const std::string& calib, SimdPath path);

}  // namespace epipole::tools

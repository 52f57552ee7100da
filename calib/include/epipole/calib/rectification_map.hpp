#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/image.hpp"

namespace epipole::calib {

enum class Side { left, right };

inline const CameraCalibration& camera_of(const StereoCalibration& c, Side side) {
  return side == Side::left ? c.left : c.right;
}

// A rectification map in fixed point, in the layout of vision::RemapMap (OpenCV's CV_16SC2 +
// CV_16UC1 pair): for destination pixel (u, v),
//   xy(2u, v), xy(2u + 1, v): floor of the source x and y (int16, saturated),
//   fractions(u, v): fy * 32 + fx, the sub-pixel parts in 1/32 pixel.
// calib does not depend on vision; the firmware builds a vision::RemapMap from these two planes
// (RemapMap(xy.view(), fractions.view()), see firmware/stereo_rectification.hpp).
struct FixedPointMap {
  static constexpr int kFractionBits = 5;
  static constexpr int kFractionSteps = 1 << kFractionBits;  // 32

  Image<std::int16_t> xy;          // 2 * width elements per row
  Image<std::uint16_t> fractions;  // width elements per row

  int width() const { return fractions.width(); }
  int height() const { return fractions.height(); }
};

// Where the rectified pixel (u, v) of a camera comes from in its raw image: the ray
// (P[:, 0:3] R)^-1 (u, v, 1), distorted and projected with K, computed in double as
// cv::initUndistortRectifyMap does (P is the camera's P1/P2, R its R1/R2).
Eigen::Vector2d source_of_rectified(const CameraCalibration& camera, double u, double v);

// The inverse: a raw (distorted) pixel to its rectified position (cv::undistortPoints with R
// and P, iterated to convergence). NaN when the distortion cannot be inverted there.
Eigen::Vector2d rectify_point(const CameraCalibration& camera, const Eigen::Vector2d& pixel);

// Float maps (the source x and y of every rectified pixel, as cv::initUndistortRectifyMap's
// CV_32FC1 maps): source_of_rectified() rounded to float. Both views must be the same size.
void build_float_map(const CameraCalibration& camera, ImageView<float> map_x,
                     ImageView<float> map_y);

// The fixed-point map of one camera, width x height (the calibration's image size): each
// coordinate of build_float_map() converted by epipole::to_fixed_point() (core/fixed_point.hpp).
// The result is therefore identical, bit for bit, to vision::RemapMap::from_float() of the float
// maps; it is within one fixed-point step (1/32 pixel) of cv::initUndistortRectifyMap(...,
// CV_16SC2, ...), which rounds the double coordinates directly
// (tests/reference/calibration_opencv_test.cpp). Start-up code: allocates the map, about 6 * width
// * height bytes.
FixedPointMap build_fixed_point_map(const CameraCalibration& camera, int width, int height);
FixedPointMap build_fixed_point_map(const StereoCalibration& calibration, Side side);
// The same into existing planes (xy twice the fractions' width, one height): no allocation, for
// a map rebuilt while the firmware runs (a corrected rig, firmware/rig_correction.hpp).
void fill_fixed_point_map(const CameraCalibration& camera, ImageView<std::int16_t> xy,
                          ImageView<std::uint16_t> fractions);

}  // namespace epipole::calib

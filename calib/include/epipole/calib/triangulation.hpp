#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/image.hpp"

namespace epipole::calib {

struct Point3f {
  float x = 0, y = 0, z = 0;
};

// Disparity to depth and 3-D points with Q (rectified left frame, units of T — metres for a
// calibration made with the square size in metres):
//   (X, Y, Z, W) = Q (u, v, d, 1),  point = (X/W, Y/W, Z/W),
// the same as cv::reprojectImageTo3D (which also computes in double and stores float).
// A disparity that is not finite, or gives W <= 0 (d <= 0 on a rig whose rectified principal
// points agree), has no point: all three coordinates are NaN (OpenCV would return infinities
// or, with handleMissingValues, Z = 10000).
//
// Fixed memory: the constructor allocates the point image; reproject() never allocates.
// Working set: 12 * height * round_up(width, 16) bytes (3 686 400 B for 640x480).
class Triangulator {
 public:
  // Throws Error if Q is not finite or Q(3,2) is 0, or the size is outside [1, 32767].
  Triangulator(const Eigen::Matrix4d& Q, int width, int height);
  explicit Triangulator(const StereoCalibration& calibration);

  // Depth Z of a disparity (in pixels) anywhere in the image when Q(3,3) == 0, otherwise the
  // depth of pixels with that disparity; NaN when there is no point.
  double depth(double disparity) const;
  // The 3-D point of pixel (u, v) with disparity d; NaN coordinates when there is no point.
  Eigen::Vector3d point(double u, double v, double disparity) const;

  // Every pixel of a disparity image (pixels) into the triangulator's own point image; the view
  // stays valid until the next call. Throws Error if the size differs from the configuration.
  ImageView<const Point3f> reproject(ImageView<const float> disparity);
  // Fixed-point disparities (disparity * 16, as StereoBM/SGBM and disparity PNGs hold them);
  // 0 means no disparity.
  ImageView<const Point3f> reproject(ImageView<const std::uint16_t> disparity16);
  // Into a caller's image of the configured size.
  void reproject(ImageView<const float> disparity, ImageView<Point3f> points) const;

  int width() const { return points_.width(); }
  int height() const { return points_.height(); }
  const Eigen::Matrix4d& Q() const { return q_; }
  std::size_t working_set_bytes() const { return points_.size_bytes(); }

 private:
  template <typename T>
  void reproject_rows(ImageView<const T> disparity, double scale, bool zero_is_missing,
                      ImageView<Point3f> points) const;

  Eigen::Matrix4d q_;
  Image<Point3f> points_;
};

}  // namespace epipole::calib

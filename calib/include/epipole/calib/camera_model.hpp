#pragma once

#include <Eigen/Core>

namespace epipole::calib {

// Pinhole intrinsics K = [fx 0 cx; 0 fy cy; 0 0 1], in pixels.
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

// OpenCV's radial-tangential ("plumb bob") model, coefficients in OpenCV's order.
struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
};

struct PinholeCamera {
  Intrinsics intrinsics;
  Distortion distortion;

  // Ideal normalised image coordinates (x/z, y/z) to distorted ones.
  Eigen::Vector2d distort(const Eigen::Vector2d& normalized) const;

  // The inverse of distort(): the ideal normalised coordinates whose distortion is `distorted`,
  // by Newton's method from `distorted` (a few steps to full double precision for the
  // distortion of real lenses over their image). Returns NaN coordinates when it does not
  // converge or converges beyond the fold of the model (where distort() stops being
  // one-to-one: a non-positive radial factor or Jacobian), i.e. outside the lens's domain.
  Eigen::Vector2d undistort(const Eigen::Vector2d& distorted) const;

  // A point in the camera frame to pixel coordinates, distortion included. Throws Error for a
  // point on or behind the image plane.
  Eigen::Vector2d project(const Eigen::Vector3d& point) const;

  // Pixel coordinates (distorted) to ideal normalised coordinates: K^-1, then undistort().
  Eigen::Vector2d normalize(const Eigen::Vector2d& pixel) const;
};

}  // namespace epipole::calib

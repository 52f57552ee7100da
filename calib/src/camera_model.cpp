#include "epipole/calib/camera_model.hpp"

#include "epipole/core/error.hpp"

namespace epipole::calib {

Eigen::Vector2d PinholeCamera::distort(const Eigen::Vector2d& normalized) const {
  const double x = normalized.x();
  const double y = normalized.y();
  const double r2 = x * x + y * y;
  const Distortion& d = distortion;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  return {x * radial + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x),
          y * radial + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y};
}

Eigen::Vector2d PinholeCamera::project(const Eigen::Vector3d& point) const {
  require(point.z() > 0, "cannot project a point at depth ", point.z(), " (must be > 0)");
  const Eigen::Vector2d distorted = distort(point.head<2>() / point.z());
  return {intrinsics.fx * distorted.x() + intrinsics.cx,
          intrinsics.fy * distorted.y() + intrinsics.cy};
}

}  // namespace epipole::calib

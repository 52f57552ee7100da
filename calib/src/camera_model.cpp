#include "epipole/calib/camera_model.hpp"

#include <Eigen/LU>
#include <cmath>
#include <limits>

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

Eigen::Vector2d PinholeCamera::undistort(const Eigen::Vector2d& distorted) const {
  constexpr int kMaxSteps = 50;
  const Distortion& d = distortion;
  Eigen::Vector2d p = distorted;
  for (int step = 0; step <= kMaxSteps; ++step) {
    const double x = p.x();
    const double y = p.y();
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
    const double dradial = d.k1 + r2 * (2 * d.k2 + 3 * r2 * d.k3);  // d radial / d r2
    Eigen::Matrix2d jacobian;
    jacobian << radial + 2 * x * x * dradial + 2 * d.p1 * y + 6 * d.p2 * x,
        2 * x * y * dradial + 2 * d.p1 * x + 2 * d.p2 * y,
        2 * x * y * dradial + 2 * d.p1 * x + 2 * d.p2 * y,
        radial + 2 * y * y * dradial + 6 * d.p1 * y + 2 * d.p2 * x;
    const Eigen::Vector2d residual = distort(p) - distorted;
    if (residual.norm() <= 1e-14 * (1 + distorted.norm())) {
      // Converged. Only inside the fold of the model (where it still maps outwards, with a
      // positive Jacobian) is the answer the lens's; beyond, distort() is not one-to-one.
      if (radial > 0 && jacobian.determinant() > 0) return p;
      break;
    }
    const Eigen::Vector2d delta = jacobian.partialPivLu().solve(residual);
    if (!delta.allFinite()) break;
    p -= delta;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan};
}

Eigen::Vector2d PinholeCamera::normalize(const Eigen::Vector2d& pixel) const {
  return undistort(
      {(pixel.x() - intrinsics.cx) / intrinsics.fx, (pixel.y() - intrinsics.cy) / intrinsics.fy});
}

Eigen::Vector2d PinholeCamera::project(const Eigen::Vector3d& point) const {
  require(point.z() > 0, "cannot project a point at depth ", point.z(), " (must be > 0)");
  const Eigen::Vector2d distorted = distort(point.head<2>() / point.z());
  return {intrinsics.fx * distorted.x() + intrinsics.cx,
          intrinsics.fy * distorted.y() + intrinsics.cy};
}

}  // namespace epipole::calib

#include "epipole/calib/disparity_plane.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include "epipole/core/angles.hpp"

namespace epipole::calib {

// On the plane, p . (u, v, d, 1) = 0 with p = (a, b, -1, c); a point X (homogeneous) is Q times
// its pixel, so the plane of X is pi = Q^-T p.
std::optional<MetricPlane> metric_plane(const Eigen::Matrix4d& Q, double a, double b, double c) {
  Eigen::Matrix4d inverse;
  bool invertible = false;
  Q.computeInverseWithCheck(inverse, invertible);
  if (!invertible) return std::nullopt;
  const Eigen::Vector4d pi = inverse.transpose() * Eigen::Vector4d(a, b, -1, c);
  const double norm = pi.head<3>().norm();
  if (!std::isfinite(norm) || !(norm > 0) || !std::isfinite(pi(3))) return std::nullopt;
  // pi . (X, 1) = 0: n . X = -pi_w / |pi_xyz|.
  MetricPlane plane{pi.head<3>() / norm, -pi(3) / norm};
  if (plane.distance < 0) {
    plane.normal = -plane.normal;
    plane.distance = -plane.distance;
  }
  if (!(plane.distance > 0)) return std::nullopt;
  return plane;
}

double pitch_deg(const MetricPlane& ground) {
  return degrees(std::asin(std::clamp(ground.normal.z(), -1.0, 1.0)));
}

double roll_deg(const MetricPlane& ground) {
  return degrees(std::atan2(ground.normal.x(), ground.normal.y()));
}

// Q (u, v, d, 1) = (W X, W), so height >= clearance is (distance - clearance) W - n . (W X) >= 0.
Eigen::Vector4d clearance_form(const Eigen::Matrix4d& Q, const MetricPlane& plane,
                               double clearance) {
  return (plane.distance - clearance) * Q.row(3).transpose() -
         Q.topRows<3>().transpose() * plane.normal;
}

}  // namespace epipole::calib

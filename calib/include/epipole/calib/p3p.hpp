#pragma once

// The pose of a calibrated camera from three points it sees (perspective-three-point), and the
// rigid motion between two sets of corresponding points: the minimal solvers of the stereo
// odometry's RANSAC (stereo_motion.hpp). Fixed-size Eigen only: nothing here allocates.
#include <Eigen/Core>
#include <array>

namespace epipole::calib {

// A rigid motion x' = rotation x + translation (the camera's frame from the points' frame).
struct RigidMotion {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return rotation * x + translation; }
  // This motion after `first`: x -> this(first(x)).
  RigidMotion after(const RigidMotion& first) const {
    return {rotation * first.rotation, rotation * first.translation + translation};
  }
  RigidMotion inverse() const {
    return {rotation.transpose(), -(rotation.transpose() * translation)};
  }
};

// The poses of a camera that sees points[i] (any frame) along bearings[i] (unit vectors in the
// camera's frame, z forward), i = 0..2: Grunert's direct solution (1841) as reviewed by
// Haralick, Lee, Ottenberg and Nolle (IJCV 1994): the quartic in the ratio of two distances
// along the rays, each real positive root giving the three distances, then the motion that
// takes the points to those along their rays. Writes up to four poses into `poses` (points in
// the camera's frame = pose.apply(point)) and returns how many; 0 for collinear or coincident
// points.
int solve_p3p(const std::array<Eigen::Vector3d, 3>& points,
              const std::array<Eigen::Vector3d, 3>& bearings, std::array<RigidMotion, 4>& poses);

// The real roots of c4 x^4 + c3 x^3 + c2 x^2 + c1 x + c0 (c4 != 0), each polished by Newton's
// method; writes them into `roots` and returns how many.
int real_quartic_roots(const std::array<double, 5>& coefficients, std::array<double, 4>& roots);

// The rigid motion taking from[i] to to[i] best in least squares, i = 0..n-1, n >= 3
// (Kabsch/Horn: the SVD of the centred points' cross-covariance, a reflection refused).
// `from` and `to` point at n vectors each.
RigidMotion align_points(const Eigen::Vector3d* from, const Eigen::Vector3d* to, int n);

}  // namespace epipole::calib

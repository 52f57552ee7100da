#pragma once

// Synthetic stereo motion for the odometry's solvers: points before a rectified rig, a known
// motion, their reprojections in the later pair's images with noise, some matches wrong.
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "epipole/calib/p3p.hpp"
#include "epipole/calib/stereo_motion.hpp"
#include "epipole/core/splitmix.hpp"

namespace epipole::test {

// Normally distributed (Box-Muller), mean 0, deviation 1.
inline double gaussian(SplitMix64& random) {
  const double u = std::max(random.uniform(), 1e-300);
  return std::sqrt(-2 * std::log(u)) * std::cos(2 * std::numbers::pi * random.uniform());
}

// A random rotation of `degrees` about a random axis.
inline Eigen::Matrix3d random_turn(SplitMix64& random, double degrees) {
  const Eigen::Vector3d axis(gaussian(random), gaussian(random), gaussian(random));
  return Eigen::AngleAxisd(degrees * std::numbers::pi / 180, axis.normalized()).toRotationMatrix();
}

// 640x480, f = 700 px, a 12 cm baseline: the simulated board's faces rig.
inline calib::RectifiedStereoCameras motion_rig() {
  return {700, 320, 320, 240, 0.12};
}

struct MotionScene {
  calib::RigidMotion truth;
  std::vector<calib::MotionMatch> matches;
  std::vector<bool> wrong;  // per match: an outlier
};

// `count` points 1.5..15 m before the earlier camera; `truth` takes them into the later
// camera's frame; reprojected there with `noise_px` of noise, `outliers` of them anywhere in the
// image instead, `no_right` of them not seen by the right camera. Points the later cameras
// cannot see are drawn again.
inline MotionScene motion_scene(SplitMix64& random, const calib::RigidMotion& truth, int count,
                                double noise_px, double outliers, double no_right = 0.1) {
  const calib::RectifiedStereoCameras c = motion_rig();
  MotionScene s{truth, {}, {}};
  while (static_cast<int>(s.matches.size()) < count) {
    const double z = 1.5 + 13.5 * random.uniform();
    const Eigen::Vector3d p((random.uniform() - 0.5) * z * 0.9, (random.uniform() - 0.5) * z * 0.6,
                            z);
    const Eigen::Vector3d x = truth.apply(p);
    if (x.z() < 0.5) continue;
    calib::MotionMatch m;
    m.point = p;
    m.left_x = c.f * x.x() / x.z() + c.left_cx + noise_px * gaussian(random);
    m.left_y = c.f * x.y() / x.z() + c.cy + noise_px * gaussian(random);
    m.right_x = c.f * (x.x() - c.baseline) / x.z() + c.right_cx + noise_px * gaussian(random);
    if (m.left_x < 0 || m.left_x > 639 || m.left_y < 0 || m.left_y > 479) continue;
    const bool wrong = random.uniform() < outliers;
    if (wrong) {
      m.left_x = 639 * random.uniform();
      m.left_y = 479 * random.uniform();
      m.right_x = m.left_x - 60 * random.uniform();
    }
    if (random.uniform() < no_right) m.right_x = std::numeric_limits<double>::quiet_NaN();
    s.matches.push_back(m);
    s.wrong.push_back(wrong);
  }
  return s;
}

inline double rotation_error_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180 / std::numbers::pi;
}

}  // namespace epipole::test

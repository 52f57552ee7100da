// A camera turned after the calibration: the angles' round trip and signs, and the rig it leaves
// rectifying the turned camera's view as the old rig rectified the old one's.
#include "epipole/calib/camera_turn.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "epipole/core/angles.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

TEST(CameraTurn, AnglesComeBackFromTheirRotation) {
  for (const CameraTurn t : {CameraTurn{0.3, -0.2, 0.1}, CameraTurn{-0.01, 0.004, -0.02},
                             CameraTurn{0, 0, 0}, CameraTurn{1.2, 2.5, -3.0}}) {
    const Eigen::Matrix3d d = turn_rotation(t);
    EXPECT_NEAR((d * d.transpose() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
    const CameraTurn back = turn_angles(d);
    EXPECT_NEAR(back.pitch, t.pitch, 1e-12);
    EXPECT_NEAR(back.roll, t.roll, 1e-12);
    EXPECT_NEAR(back.yaw, t.yaw, 1e-12);
  }
}

TEST(CameraTurn, SignsAreThoseDocumented) {
  const double a = radians(2);
  // Pitch raises the view: the forward axis leans to -y (up).
  const Eigen::Vector3d forward = turn_rotation({a, 0, 0}) * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(forward.y(), -std::sin(a), 1e-12);
  // Yaw turns it right (+x).
  EXPECT_NEAR((turn_rotation({0, 0, a}) * Eigen::Vector3d::UnitZ()).x(), std::sin(a), 1e-12);
  // Roll turns x towards y.
  EXPECT_NEAR((turn_rotation({0, a, 0}) * Eigen::Vector3d::UnitX()).y(), std::sin(a), 1e-12);
}

TEST(CameraTurn, TheTurnedRigRectifiesTheTurnedViewAsBefore) {
  const StereoCalibration rig = test::sample_calibration();
  const Eigen::Matrix3d d = turn_rotation({radians(0.4), radians(-0.3), radians(0.2)});
  const StereoCalibration turned = with_right_camera_turned(rig, d);
  EXPECT_NO_THROW(validate(turned));
  EXPECT_EQ(turned.left.rectification, rig.left.rectification);
  EXPECT_EQ(turned.right.projection, rig.right.projection);
  EXPECT_EQ(turned.Q, rig.Q);
  for (const Eigen::Vector3d& x_left :
       {Eigen::Vector3d(0.2, -0.1, 1.5), Eigen::Vector3d(-1.0, 0.4, 6.0)}) {
    const Eigen::Vector3d old_view = rig.R * x_left + rig.T;        // the old right camera's
    const Eigen::Vector3d new_view = turned.R * x_left + turned.T;  // the turned one's
    EXPECT_NEAR((new_view - d.transpose() * old_view).norm(), 0, 1e-12);
    const Eigen::Vector3d old_rectified = rig.right.rectification * old_view;
    const Eigen::Vector3d new_rectified = turned.right.rectification * new_view;
    EXPECT_NEAR((new_rectified - old_rectified).norm(), 0, 1e-12);
  }
  // Turning back gives the rig back.
  const StereoCalibration back = with_right_camera_turned(turned, d.transpose());
  EXPECT_NEAR((back.R - rig.R).norm(), 0, 1e-12);
  EXPECT_NEAR((back.T - rig.T).norm(), 0, 1e-12);
  EXPECT_NEAR((back.right.rectification - rig.right.rectification).norm(), 0, 1e-12);
}

}  // namespace
}  // namespace epipole::calib

#include "epipole/calib/camera_turn.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace epipole::calib {

Eigen::Matrix3d turn_rotation(const CameraTurn& turn) {
  const Eigen::Matrix3d yaw(Eigen::AngleAxisd(turn.yaw, Eigen::Vector3d::UnitY()));
  const Eigen::Matrix3d pitch(Eigen::AngleAxisd(turn.pitch, Eigen::Vector3d::UnitX()));
  const Eigen::Matrix3d roll(Eigen::AngleAxisd(turn.roll, Eigen::Vector3d::UnitZ()));
  return yaw * pitch * roll;
}

CameraTurn turn_angles(const Eigen::Matrix3d& d) {
  // D = Ry Rx Rz: D(1,2) = -sin(pitch); D(0,2) = sin(yaw) cos(pitch); D(1,0) = cos(pitch)
  // sin(roll), D(1,1) = cos(pitch) cos(roll).
  CameraTurn turn;
  turn.pitch = std::asin(std::clamp(-d(1, 2), -1.0, 1.0));
  turn.yaw = std::atan2(d(0, 2), d(2, 2));
  turn.roll = std::atan2(d(1, 0), d(1, 1));
  return turn;
}

StereoCalibration with_right_camera_turned(const StereoCalibration& rig,
                                           const Eigen::Matrix3d& rotation) {
  StereoCalibration turned = rig;
  turn_right_camera(turned, rotation);
  return turned;
}

void turn_right_camera(StereoCalibration& rig, const Eigen::Matrix3d& rotation) {
  rig.R = rotation.transpose() * rig.R;
  rig.T = rotation.transpose() * rig.T;
  rig.right.rectification = rig.right.rectification * rotation;
}

}  // namespace epipole::calib

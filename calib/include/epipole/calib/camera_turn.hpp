#pragma once

// A camera of a calibrated rig turned about its own centre after the calibration (a knock, heat):
// the rotation, and the rig it leaves.
#include <Eigen/Core>

#include "epipole/calib/calibration.hpp"

namespace epipole::calib {

// Small turns of a camera about its own axes (OpenCV's: x right, y down, z forward), radians:
// pitch about x (positive raises the view: the picture moves down), roll about z (positive turns
// x towards y: the picture turns anticlockwise), yaw about y (positive turns the view right).
struct CameraTurn {
  double pitch = 0, roll = 0, yaw = 0;
};

// The turn as a rotation D: the turned camera's axes in the old camera frame, yaw first, then
// pitch, then roll (D = Ry(yaw) Rx(pitch) Rz(roll)). A direction the old camera saw at r, the
// turned one sees at D^T r.
Eigen::Matrix3d turn_rotation(const CameraTurn& turn);
// The inverse of turn_rotation() (angles within +-90 degrees of pitch).
CameraTurn turn_angles(const Eigen::Matrix3d& rotation);

// The rig after its right camera turned by `rotation` (turn_rotation()): R and T follow the
// camera (x_right' = D^T x_right), and its rectification follows too (R2' = R2 D), so the
// rectified frames, P1, P2 and Q stay as they were and the result validates. Rectifying the
// turned camera's images with it gives the pictures the old calibration gave the old camera's.
StereoCalibration with_right_camera_turned(const StereoCalibration& rig,
                                           const Eigen::Matrix3d& rotation);
// The same in place (no allocation).
void turn_right_camera(StereoCalibration& rig, const Eigen::Matrix3d& rotation);

}  // namespace epipole::calib

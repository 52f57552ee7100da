#pragma once

#include "epipole/calib/calibration.hpp"

namespace epipole::test {

// Two ideal cameras, already rectified, 0.1 m apart: 320x240, f = 300 pixels, the centre at
// (160, 120); `right_k1`: the right lens's radial distortion (none by default).
inline calib::StereoCalibration ideal_rig(double right_k1 = 0) {
  calib::StereoCalibration rig;
  rig.width = 320;
  rig.height = 240;
  rig.left.id = "left";
  rig.right.id = "right";
  rig.left.camera.intrinsics = {300, 300, 160, 120};
  rig.right.camera.intrinsics = {300, 300, 160, 120};
  rig.right.camera.distortion.k1 = right_k1;
  rig.left.projection << 300, 0, 160, 0, 0, 300, 120, 0, 0, 0, 1, 0;
  rig.right.projection << 300, 0, 160, -30, 0, 300, 120, 0, 0, 0, 1, 0;
  rig.T = Eigen::Vector3d(-0.1, 0.0, 0.0);
  rig.Q = calib::disparity_to_depth(rig.left.projection, rig.right.projection);
  calib::validate(rig);
  return rig;
}

}  // namespace epipole::test

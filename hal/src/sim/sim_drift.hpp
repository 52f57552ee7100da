#pragma once

#include "epipole/calib/calibration.hpp"
#include "sim/sim_files.hpp"
#include "sim/sim_settings.hpp"

namespace epipole::hal {

// The drift's rotation (calib::turn_rotation of its angles).
Eigen::Matrix3d drift_rotation(const SimDrift& drift);

// Turns the scene's right camera after its calibration `rig`: each right image becomes the one
// the turned camera sees, right'(p) = right(project(D unproject(p))) through the right camera's
// lens (for a lens without distortion, the homography K D K^-1), sampled by cubic convolution; what
// the old image did not see is black. Throws Error when the images are not rig.width x rig.height.
void drift_right_images(StereoImages& images, const calib::StereoCalibration& rig,
                        const SimDrift& drift);

}  // namespace epipole::hal

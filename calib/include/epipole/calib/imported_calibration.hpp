#pragma once

// What the importers of other tools' calibration files share (ROS here, OpenCV's FileStorage
// in the host tool): their camera and distortion conventions turned into ours, and validation
// errors in the source's names.

#include <Eigen/Core>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "epipole/calib/calibration.hpp"

namespace epipole::calib {

// OpenCV's distortion vector (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tx ty]]]]) or ROS's D:
// 0, 4, 5, 8, 12 or 14 coefficients, every one beyond k3 zero (the rational, thin-prism and
// tilted models are not supported). Error names `where`.
Distortion radial_tangential_distortion(std::span<const double> coefficients,
                                        const std::string& where);

// A camera from K = [fx 0 cx; 0 fy cy; 0 0 1] (no skew: Error naming `where`).
CameraCalibration pinhole_camera(const Eigen::Matrix3d& K, const Distortion& distortion,
                                 const std::string& where);

// validate(), with the error in the source's names: the first pair whose first string starts
// the message (a key of our schema, such as "cameras.left.K") is replaced by the second (the
// source's key, such as "M1"), and the message starts with `files`.
using KeyName = std::pair<std::string_view, std::string_view>;
void validate_imported(const StereoCalibration& calibration, const std::string& files,
                       std::initializer_list<KeyName> names);

}  // namespace epipole::calib

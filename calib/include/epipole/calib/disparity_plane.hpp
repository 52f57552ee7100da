#pragma once

// Planes of a rectified pair's disparity space in metres, through Q (cv::reprojectImageTo3D's
// matrix, calibration.hpp). A plane in front of the rig has a disparity affine in the pixel,
// d(u, v) = a u + b v + c; Q turns it into the plane n . X = distance of the rectified left
// camera frame (x right, y down, z forward, metres).
#include <Eigen/Core>
#include <optional>

namespace epipole::calib {

struct MetricPlane {
  Eigen::Vector3d normal;  // unit, pointing from the camera towards the plane
  double distance = 0;     // of the camera's centre from the plane, > 0
};

// The plane whose disparities are d = a u + b v + c; none when Q is singular or the plane
// passes through the camera's centre (or is no finite plane).
std::optional<MetricPlane> metric_plane(const Eigen::Matrix4d& Q, double a, double b, double c);

// A ground plane's pose seen from the camera, degrees: pitch, the optical axis's angle below
// the ground's horizontal (looking down positive), asin(n_z); roll, the camera's x axis's angle
// below it (the image's right side lower positive), atan2(n_x, n_y).
double pitch_deg(const MetricPlane& ground);
double roll_deg(const MetricPlane& ground);

// The pixels (u, v, d) of points at least `clearance` metres off the plane on the camera's side
// (height = distance - n . X): those where form . (u, v, d, 1) >= 0, for points in front of the
// camera (Q's w > 0). Linear in the pixel, so a per-pixel test costs three multiply-adds.
Eigen::Vector4d clearance_form(const Eigen::Matrix4d& Q, const MetricPlane& plane,
                               double clearance);

}  // namespace epipole::calib

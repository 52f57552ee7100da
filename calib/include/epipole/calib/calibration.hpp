#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "epipole/calib/camera_model.hpp"

namespace epipole::calib {

// One camera of a calibrated stereo rig.
struct CameraCalibration {
  std::string id;        // camera identifier (serial number, device name, "left")
  PinholeCamera camera;  // K and the radial-tangential distortion
  Eigen::Matrix3d rectification = Eigen::Matrix3d::Identity();  // R1 / R2: camera -> rectified
  Eigen::Matrix<double, 3, 4> projection = Eigen::Matrix<double, 3, 4>::Zero();  // P1 / P2

  // K as a matrix (no skew).
  Eigen::Matrix3d camera_matrix() const;
};

// The error of one calibration view (a left/right image pair), RMS in pixels.
struct ViewError {
  std::string left;  // image names as given to the calibration
  std::string right;
  double left_rms = 0;
  double right_rms = 0;
};

// A calibrated stereo rig: what a calibration file holds (docs/calibration.md). The names and
// conventions are OpenCV's (cv::stereoCalibrate, cv::stereoRectify):
//   x_right = R x_left + T                       (a point in each camera's frame)
//   R1, R2 rotate each camera's frame into its rectified frame; P1, P2 project rectified frames
//   to rectified pixels; Q maps (u, v, disparity, 1) to homogeneous 3-D points in the rectified
//   left frame.
struct StereoCalibration {
  static constexpr int kVersion = 1;  // schema version written by this build

  int width = 0;  // image size, pixels (the same for both cameras and the rectified images)
  int height = 0;
  CameraCalibration left;
  CameraCalibration right;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d T = Eigen::Vector3d::Zero();  // units of the calibration target (metres)
  Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
  std::optional<double> rms;     // overall RMS reprojection error, pixels, when known
  std::vector<ViewError> views;  // per-view errors, when known
  std::string date;              // when the calibration was made, ISO 8601 (UTC)
  std::string source;            // what made it ("epipole calibrate", "import: opencv", ...)
};

// Throws Error naming the first field that is not a valid calibration: sizes outside
// [1, 32767], non-finite numbers, K without positive focal lengths or with skew, R/R1/R2 not
// rotations, T zero, P1/P2 not rectified projections, R1 and R2 * R not the same rotation
// (the rectified frames must be parallel), negative errors.
void validate(const StereoCalibration& calibration);

// The calibration file (YAML, docs/calibration.md). Reading checks everything validate()
// checks plus the schema (every key known, every matrix of its size), and either returns a
// complete calibration or throws Error naming the file and the key: never a partial one.
StereoCalibration parse_calibration(const std::string& yaml, const std::string& file_name);
StereoCalibration load_calibration(const std::filesystem::path& file);
std::string format_calibration(const StereoCalibration& calibration);  // validates first
// Writes to a temporary file in the same folder and renames it over `file`, so a reader never
// sees a half-written file. Throws Error naming the file.
void save_calibration(const std::filesystem::path& file, const StereoCalibration& calibration);

// Imports a ROS camera_info YAML pair (camera_calibration_parsers' format: image_width,
// image_height, camera_name, camera_matrix, distortion_model, distortion_coefficients,
// rectification_matrix, projection_matrix). R and T are recovered from the rectification and
// projection matrices, Q from the projections. distortion_model must be plumb_bob (or
// rational_polynomial with k4 k5 k6 zero).
StereoCalibration import_ros_calibration(const std::filesystem::path& left,
                                         const std::filesystem::path& right);

// Exports for ROS programs (docs/calibration.md): left.yaml and right.yaml, as camera_calibration
// writes them (image size, camera_name: the camera's id, camera_matrix, distortion_model
// plumb_bob, distortion_coefficients, rectification_matrix, projection_matrix), written into
// `directory` (made when missing), each through a temporary file and a rename; numbers with 17
// significant digits, so that importing them gives the same doubles. Throws Error naming the
// file. (OpenCV's files: epipole/tools/opencv_calibration.hpp, on the host.)
void export_ros_calibration(const StereoCalibration& calibration,
                            const std::filesystem::path& directory);

// Q of a rectified pair from its projections, as cv::stereoRectify builds it (horizontal rigs:
// P2(0,3) != 0; vertical rigs: P2(1,3) != 0).
Eigen::Matrix4d disparity_to_depth(const Eigen::Matrix<double, 3, 4>& P1,
                                   const Eigen::Matrix<double, 3, 4>& P2);

// The current time, ISO 8601 UTC ("2024-05-01T12:34:56Z"), for StereoCalibration::date.
std::string utc_now();

}  // namespace epipole::calib

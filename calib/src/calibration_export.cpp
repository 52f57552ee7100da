// Calibration files for OpenCV and ROS programs (docs/calibration.md), the inverse of
// calibration_import.cpp: written as text here, so the calibration library needs no OpenCV.
#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include "atomic_file.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"

namespace epipole::calib {

namespace {

// Enough digits that reading the number back gives the same double.
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// The row-major entries of a matrix, ", "-separated.
std::string entries(const Eigen::MatrixXd& m) {
  std::string out;
  for (int r = 0; r < m.rows(); ++r) {
    for (int c = 0; c < m.cols(); ++c) {
      if (!out.empty()) out += ", ";
      out += number(m(r, c));
    }
  }
  return out;
}

Eigen::MatrixXd coefficients(const Distortion& d) {
  Eigen::MatrixXd row(1, 5);
  row << d.k1, d.k2, d.p1, d.p2, d.k3;
  return row;
}

// A matrix as cv::FileStorage writes one in YAML.
std::string opencv_matrix(const char* name, const Eigen::MatrixXd& m) {
  return std::string(name) + ": !!opencv-matrix\n   rows: " + std::to_string(m.rows()) +
         "\n   cols: " + std::to_string(m.cols()) + "\n   dt: d\n   data: [ " + entries(m) + " ]\n";
}

std::string opencv_size(const StereoCalibration& c) {
  return "image_width: " + std::to_string(c.width) + "\nimage_height: " + std::to_string(c.height) +
         "\n";
}

// A matrix as camera_calibration writes one.
std::string ros_matrix(const char* name, const Eigen::MatrixXd& m) {
  return std::string(name) + ":\n  rows: " + std::to_string(m.rows()) +
         "\n  cols: " + std::to_string(m.cols()) + "\n  data: [" + entries(m) + "]\n";
}

// A YAML string that stays one string whatever the id holds (": ", "#", quotes).
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string ros_camera(const StereoCalibration& c, const CameraCalibration& camera) {
  return "image_width: " + std::to_string(c.width) + "\nimage_height: " + std::to_string(c.height) +
         "\ncamera_name: " + quoted(camera.id) + "\n" +
         ros_matrix("camera_matrix", camera.camera_matrix()) + "distortion_model: plumb_bob\n" +
         ros_matrix("distortion_coefficients", coefficients(camera.camera.distortion)) +
         ros_matrix("rectification_matrix", camera.rectification) +
         ros_matrix("projection_matrix", camera.projection);
}

void make_directory(const std::filesystem::path& directory) {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  require(!error && std::filesystem::is_directory(directory), directory.string(),
          ": cannot make the folder", error ? " (" + error.message() + ")" : std::string());
}

}  // namespace

void export_opencv_calibration(const StereoCalibration& c, const std::filesystem::path& directory) {
  validate(c);
  make_directory(directory);
  const std::string header = "%YAML:1.0\n---\n";
  detail::write_atomically(directory / "intrinsics.yml",
                           header + opencv_size(c) + opencv_matrix("M1", c.left.camera_matrix()) +
                               opencv_matrix("D1", coefficients(c.left.camera.distortion)) +
                               opencv_matrix("M2", c.right.camera_matrix()) +
                               opencv_matrix("D2", coefficients(c.right.camera.distortion)));
  detail::write_atomically(directory / "extrinsics.yml",
                           header + opencv_size(c) + opencv_matrix("R", c.R) +
                               opencv_matrix("T", c.T) + opencv_matrix("R1", c.left.rectification) +
                               opencv_matrix("R2", c.right.rectification) +
                               opencv_matrix("P1", c.left.projection) +
                               opencv_matrix("P2", c.right.projection) + opencv_matrix("Q", c.Q));
}

void export_ros_calibration(const StereoCalibration& c, const std::filesystem::path& directory) {
  validate(c);
  make_directory(directory);
  detail::write_atomically(directory / "left.yaml", ros_camera(c, c.left));
  detail::write_atomically(directory / "right.yaml", ros_camera(c, c.right));
}

}  // namespace epipole::calib

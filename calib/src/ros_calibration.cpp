// ROS camera_info files (camera_calibration_parsers' YAML layout), both ways: a stereo pair's
// left.yaml and right.yaml to a calibration and back.
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/imported_calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/text_file.hpp"
#include "epipole/core/yaml_fields.hpp"

namespace epipole::calib {

namespace {

struct RosCamera {
  int width = 0;
  int height = 0;
  std::string name;
  Eigen::Matrix3d K;
  Distortion distortion;
  Eigen::Matrix3d R;
  Eigen::Matrix<double, 3, 4> P;
};

Eigen::MatrixXd read_ros_matrix(const yaml::Fields& f, const YAML::Node& root, const char* key,
                                int rows, int cols) {
  const YAML::Node node = f.child(root, "", key);
  const int r = f.integer(f.child(node, key, "rows"), std::string(key) + ".rows");
  const int c = f.integer(f.child(node, key, "cols"), std::string(key) + ".cols");
  if (r != rows || c != cols) f.fail(key, cat("expected ", rows, "x", cols, ", found ", r, "x", c));
  const std::vector<double> data =
      f.numbers(f.child(node, key, "data"), std::string(key) + ".data");
  if (data.size() != static_cast<std::size_t>(rows * cols)) {
    f.fail(std::string(key) + ".data",
           cat("expected ", rows * cols, " numbers, found ", data.size()));
  }
  Eigen::MatrixXd m(rows, cols);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) m(i, j) = data[static_cast<std::size_t>(i * cols + j)];
  }
  return m;
}

RosCamera read_ros(const std::filesystem::path& path) {
  const yaml::Fields f(path.string());
  const YAML::Node root = f.parse(read_text_file(path));
  f.require_map(root, "");
  RosCamera c;
  c.width = f.integer(f.child(root, "", "image_width"), "image_width");
  c.height = f.integer(f.child(root, "", "image_height"), "image_height");
  if (const YAML::Node name = f.optional_child(root, "", "camera_name")) {
    c.name = f.text(name, "camera_name");
  }
  c.K = read_ros_matrix(f, root, "camera_matrix", 3, 3);
  const std::string model = f.text(f.child(root, "", "distortion_model"), "distortion_model");
  const YAML::Node dnode = f.child(root, "", "distortion_coefficients");
  const std::vector<double> d =
      f.numbers(f.child(dnode, "distortion_coefficients", "data"), "distortion_coefficients.data");
  if (model == "plumb_bob" || model == "rational_polynomial") {
    c.distortion = radial_tangential_distortion(d, path.string() + ": distortion_coefficients");
  } else {
    f.fail("distortion_model", "'" + model +
                                   "' is not supported (plumb_bob, or rational_polynomial with "
                                   "k4 k5 k6 zero)");
  }
  c.R = read_ros_matrix(f, root, "rectification_matrix", 3, 3);
  c.P = read_ros_matrix(f, root, "projection_matrix", 3, 4);
  return c;
}

}  // namespace

StereoCalibration import_ros_calibration(const std::filesystem::path& left,
                                         const std::filesystem::path& right) {
  const RosCamera l = read_ros(left);
  const RosCamera r = read_ros(right);
  const std::string names = left.string() + " and " + right.string();
  require(l.width == r.width && l.height == r.height, names, ": image sizes differ (", l.width, "x",
          l.height, " and ", r.width, "x", r.height, ")");
  StereoCalibration c;
  c.width = l.width;
  c.height = l.height;
  c.left = pinhole_camera(l.K, l.distortion, left.string() + ": camera_matrix");
  c.right = pinhole_camera(r.K, r.distortion, right.string() + ": camera_matrix");
  c.left.id = l.name.empty() ? "left" : l.name;
  c.right.id = r.name.empty() ? "right" : r.name;
  c.left.rectification = l.R;
  c.right.rectification = r.R;
  c.left.projection = l.P;
  c.right.projection = r.P;
  // Rectified frames are parallel and the right one sits at t = (P2(0,3)/fx', P2(1,3)/fy', 0)
  // from the left: R2 x_right = R1 x_left + t, so R = R2^T R1 and T = R2^T t.
  require(r.P(0, 0) > 0 && r.P(1, 1) > 0, right.string(),
          ": projection_matrix: focal lengths must be > 0");
  const Eigen::Vector3d t(r.P(0, 3) / r.P(0, 0), r.P(1, 3) / r.P(1, 1), 0);
  c.R = r.R.transpose() * l.R;
  c.T = r.R.transpose() * t;
  c.Q = disparity_to_depth(c.left.projection, c.right.projection);
  c.date = utc_now();
  c.source = "import: ros " + names;
  validate_imported(c, names,
                    {{"image_size", "image_width/image_height"},
                     {"cameras.left.K", "left camera_matrix"},
                     {"cameras.right.K", "right camera_matrix"},
                     {"cameras.left.distortion.coefficients", "left distortion_coefficients"},
                     {"cameras.right.distortion.coefficients", "right distortion_coefficients"},
                     {"extrinsics.T", "right projection_matrix (baseline)"},
                     {"extrinsics.R", "rectification matrices"},
                     {"rectification.R1", "left rectification_matrix"},
                     {"rectification.R2", "right rectification_matrix"},
                     {"rectification.P1", "left projection_matrix"},
                     {"rectification.P2", "right projection_matrix"},
                     {"rectification.Q", "projection matrices"}});
  return c;
}

namespace {

// A matrix as camera_calibration writes one: rows, cols, data in a row-major flow sequence.
void emit_ros_matrix(YAML::Emitter& out, const char* key, const Eigen::MatrixXd& m) {
  out << YAML::Key << key << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "rows" << YAML::Value << m.rows();
  out << YAML::Key << "cols" << YAML::Value << m.cols();
  out << YAML::Key << "data" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) out << m(r, c);
  }
  out << YAML::EndSeq << YAML::EndMap;
}

std::string ros_camera(const StereoCalibration& c, const CameraCalibration& camera) {
  const Distortion& d = camera.camera.distortion;
  Eigen::MatrixXd coefficients(1, 5);
  coefficients << d.k1, d.k2, d.p1, d.p2, d.k3;
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // every double reads back to the same bits
  out << YAML::BeginMap;
  out << YAML::Key << "image_width" << YAML::Value << c.width;
  out << YAML::Key << "image_height" << YAML::Value << c.height;
  out << YAML::Key << "camera_name" << YAML::Value << camera.id;
  emit_ros_matrix(out, "camera_matrix", camera.camera_matrix());
  out << YAML::Key << "distortion_model" << YAML::Value << "plumb_bob";
  emit_ros_matrix(out, "distortion_coefficients", coefficients);
  emit_ros_matrix(out, "rectification_matrix", camera.rectification);
  emit_ros_matrix(out, "projection_matrix", camera.projection);
  out << YAML::EndMap;
  require(out.good(), "cannot format the ROS camera_info file: ", out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

}  // namespace

void export_ros_calibration(const StereoCalibration& c, const std::filesystem::path& directory) {
  validate(c);
  make_directories(directory);
  write_text_file_atomically(directory / "left.yaml", ros_camera(c, c.left));
  write_text_file_atomically(directory / "right.yaml", ros_camera(c, c.right));
}

}  // namespace epipole::calib

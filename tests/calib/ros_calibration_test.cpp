// Importing and exporting ROS camera_info files, from text in the exact form
// camera_calibration writes.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

#include "calibration_checks.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "error_of.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

using test::coefficients;
using test::error_of;
using test::expect_geometry;
using test::numbers;
using test::write_temp;

// A ROS camera_info file (camera_calibration_parsers' layout).
template <typename M>
std::string ros_matrix(const char* name, const Eigen::MatrixBase<M>& m) {
  return cat(name, ":\n  rows: ", m.rows(), "\n  cols: ", m.cols(), "\n  data: [", numbers(m, ", "),
             "]\n");
}

std::string ros_file(const CameraCalibration& c, const char* name,
                     const char* model = "plumb_bob") {
  return cat("image_width: 640\nimage_height: 480\ncamera_name: ", name, "\n",
             ros_matrix("camera_matrix", c.camera_matrix()), "distortion_model: ", model, "\n",
             ros_matrix("distortion_coefficients", coefficients(c)),
             ros_matrix("rectification_matrix", c.rectification),
             ros_matrix("projection_matrix", c.projection));
}

TEST(RosImport, RecoversExtrinsicsAndQ) {
  const StereoCalibration want = test::sample_calibration();
  const auto left = write_temp("ros-left.yaml", ros_file(want.left, "narrow_stereo/left"));
  const auto right = write_temp("ros-right.yaml", ros_file(want.right, "narrow_stereo/right"));
  const StereoCalibration got = import_ros_calibration(left, right);
  expect_geometry(got, want, 1e-9);
  EXPECT_EQ(got.left.id, "narrow_stereo/left");
  EXPECT_EQ(got.right.id, "narrow_stereo/right");
}

TEST(RosImport, BadInput) {
  const StereoCalibration c = test::sample_calibration();
  const auto left = write_temp("ros-left.yaml", ros_file(c.left, "l"));
  const auto fisheye = write_temp("ros-fisheye.yaml", ros_file(c.right, "r", "equidistant"));
  std::string e = error_of([&] { import_ros_calibration(left, fisheye); });
  EXPECT_NE(e.find("ros-fisheye.yaml: distortion_model: 'equidistant' is not supported"),
            std::string::npos)
      << e;
  std::string text = ros_file(c.right, "r");
  text.replace(text.find("rows: 3\n  cols: 4"), 17, "rows: 3\n  cols: 3");
  const auto wrong = write_temp("ros-wrong.yaml", text);
  e = error_of([&] { import_ros_calibration(left, wrong); });
  EXPECT_NE(e.find("ros-wrong.yaml: projection_matrix: expected 3x4"), std::string::npos) << e;
  text = ros_file(c.right, "r");
  text.replace(text.find("image_width: 640"), 16, "image_width: 320");
  const auto smaller = write_temp("ros-small.yaml", text);
  e = error_of([&] { import_ros_calibration(left, smaller); });
  EXPECT_NE(e.find("image sizes differ"), std::string::npos) << e;
  text = ros_file(c.right, "r");
  text.erase(text.find("rectification_matrix"));
  const auto missing = write_temp("ros-missing.yaml", text);
  e = error_of([&] { import_ros_calibration(left, missing); });
  EXPECT_NE(e.find("ros-missing.yaml: missing key 'rectification_matrix'"), std::string::npos) << e;
  // A monocular camera_info (identity rectification, no baseline) is not a stereo pair.
  CameraCalibration mono = c.right;
  mono.rectification.setIdentity();
  mono.projection(0, 3) = 0;
  const auto mono_file = write_temp("ros-mono.yaml", ros_file(mono, "r"));
  e = error_of([&] { import_ros_calibration(left, mono_file); });
  EXPECT_FALSE(e.empty());
}

// `epipole calibrate --export-ros`, then --from-ros: the same calibration (R and T recovered
// from the rectification, to rounding).
TEST(CalibrationExport, RosFilesImportToTheSameCalibration) {
  StereoCalibration want = test::sample_calibration();
  want.left.id = "narrow_stereo/left";
  want.right.id = "usb: \"cam\" #1 \\ right";  // one string, whatever it holds
  const std::filesystem::path folder = std::filesystem::path(::testing::TempDir()) / "export-ros";
  export_ros_calibration(want, folder);
  const StereoCalibration got = import_ros_calibration(folder / "left.yaml", folder / "right.yaml");
  expect_geometry(got, want, 1e-9);
  EXPECT_EQ(got.left.camera_matrix(), want.left.camera_matrix());
  EXPECT_EQ(got.right.projection, want.right.projection);
  EXPECT_EQ(got.left.id, "narrow_stereo/left");
  EXPECT_EQ(got.right.id, want.right.id);
  const YAML::Node left = YAML::LoadFile((folder / "left.yaml").string());
  EXPECT_EQ(left["distortion_model"].as<std::string>(), "plumb_bob");
  EXPECT_EQ(left["projection_matrix"]["cols"].as<int>(), 4);
  EXPECT_EQ(left["distortion_coefficients"]["data"].size(), 5u);
}

TEST(CalibrationExport, AFolderThatCannotBeMadeIsNamed) {
  const std::filesystem::path file = write_temp("not-a-folder", "x");
  const std::string error =
      error_of([&] { export_ros_calibration(test::sample_calibration(), file / "ros"); });
  EXPECT_NE(error.find("not-a-folder/ros"), std::string::npos) << error;
  StereoCalibration broken = test::sample_calibration();
  broken.width = 0;
  EXPECT_NE(error_of([&] {
              export_ros_calibration(broken, std::filesystem::path(::testing::TempDir()));
            }),
            "")
      << "an invalid calibration is not exported";
}

}  // namespace
}  // namespace epipole::calib

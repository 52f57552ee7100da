// Importing OpenCV FileStorage (YAML, XML) and ROS camera_info files, from text in the exact
// form those tools write (tests/reference/calibration_opencv_test.cpp checks files written by
// cv::FileStorage itself).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "error_of.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

std::filesystem::path write_temp(const std::string& name, const std::string& text) {
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / name;
  std::ofstream(file) << text;
  return file;
}

std::string number(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.16e", v);
  return text;
}

template <typename Derived>
std::string numbers(const Eigen::MatrixBase<Derived>& m, const char* separator) {
  std::string out;
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      if (!out.empty()) out += separator;
      out += number(m(r, c));
    }
  }
  return out;
}

Eigen::Matrix<double, 1, 5> coefficients(const CameraCalibration& c) {
  const Distortion& d = c.camera.distortion;
  Eigen::Matrix<double, 1, 5> v;
  v << d.k1, d.k2, d.p1, d.p2, d.k3;
  return v;
}

template <typename Derived>
std::string yaml_matrix(const char* name, const Eigen::MatrixBase<Derived>& m) {
  return cat(name, ": !!opencv-matrix\n   rows: ", m.rows(), "\n   cols: ", m.cols(),
             "\n   dt: d\n   data: [ ", numbers(m, ", "), " ]\n");
}

template <typename Derived>
std::string xml_matrix(const char* name, const Eigen::MatrixBase<Derived>& m) {
  return cat("<", name, " type_id=\"opencv-matrix\">\n  <rows>", m.rows(), "</rows>\n  <cols>",
             m.cols(), "</cols>\n  <dt>d</dt>\n  <data>\n    ", numbers(m, " "), "</data></", name,
             ">\n");
}

// OpenCV's stereo_calib sample writes intrinsics (M1 D1 M2 D2) and extrinsics (R T R1 R2 P1 P2
// Q) like this.
struct OpenCvFiles {
  std::string intrinsics;
  std::string extrinsics;
};

OpenCvFiles opencv_yaml(const StereoCalibration& c, bool with_q = true) {
  OpenCvFiles f;
  f.intrinsics = "%YAML:1.0\n---\n" + yaml_matrix("M1", c.left.camera_matrix()) +
                 yaml_matrix("D1", coefficients(c.left)) +
                 yaml_matrix("M2", c.right.camera_matrix()) +
                 yaml_matrix("D2", coefficients(c.right));
  f.extrinsics = "%YAML:1.0\n---\n" + yaml_matrix("R", c.R) + yaml_matrix("T", c.T) +
                 yaml_matrix("R1", c.left.rectification) +
                 yaml_matrix("R2", c.right.rectification) + yaml_matrix("P1", c.left.projection) +
                 yaml_matrix("P2", c.right.projection) + (with_q ? yaml_matrix("Q", c.Q) : "");
  return f;
}

OpenCvFiles opencv_xml(const StereoCalibration& c) {
  OpenCvFiles f;
  f.intrinsics = "<?xml version=\"1.0\"?>\n<opencv_storage>\n" +
                 xml_matrix("M1", c.left.camera_matrix()) + xml_matrix("D1", coefficients(c.left)) +
                 xml_matrix("M2", c.right.camera_matrix()) +
                 xml_matrix("D2", coefficients(c.right)) + "</opencv_storage>\n";
  f.extrinsics = "<?xml version=\"1.0\"?>\n<!-- stereo_calib -->\n<opencv_storage>\n" +
                 xml_matrix("R", c.R) + xml_matrix("T", c.T) +
                 xml_matrix("R1", c.left.rectification) + xml_matrix("R2", c.right.rectification) +
                 xml_matrix("P1", c.left.projection) + xml_matrix("P2", c.right.projection) +
                 xml_matrix("Q", c.Q) + "</opencv_storage>\n";
  return f;
}

void expect_geometry(const StereoCalibration& got, const StereoCalibration& want, double tol) {
  EXPECT_EQ(got.width, want.width);
  EXPECT_EQ(got.height, want.height);
  EXPECT_LE((got.left.camera_matrix() - want.left.camera_matrix()).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.right.camera_matrix() - want.right.camera_matrix()).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((coefficients(got.left) - coefficients(want.left)).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((coefficients(got.right) - coefficients(want.right)).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.R - want.R).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.T - want.T).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.left.rectification - want.left.rectification).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.right.rectification - want.right.rectification).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.left.projection - want.left.projection).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.right.projection - want.right.projection).cwiseAbs().maxCoeff(), tol);
  EXPECT_LE((got.Q - want.Q).cwiseAbs().maxCoeff(), tol * 1000);
}

using test::error_of;

TEST(OpenCvImport, YamlAsTheSampleWritesIt) {
  const StereoCalibration want = test::sample_calibration();
  const OpenCvFiles f = opencv_yaml(want);
  const auto in = write_temp("cv-intrinsics.yml", f.intrinsics);
  const auto ex = write_temp("cv-extrinsics.yml", f.extrinsics);
  const StereoCalibration got = import_opencv_calibration(in, ex, 640, 480);
  expect_geometry(got, want, 0.0);  // %.16e: every bit survives
  EXPECT_EQ(got.left.id, "left");
  EXPECT_NE(got.source.find("opencv"), std::string::npos);
  EXPECT_FALSE(got.date.empty());
  EXPECT_FALSE(got.rms.has_value());
  // The result is a valid calibration file.
  expect_geometry(parse_calibration(format_calibration(got), "x.yaml"), want, 0.0);
}

TEST(OpenCvImport, XmlGivesTheSameCalibration) {
  const StereoCalibration want = test::sample_calibration();
  const OpenCvFiles f = opencv_xml(want);
  const auto in = write_temp("cv-intrinsics.xml", f.intrinsics);
  const auto ex = write_temp("cv-extrinsics.xml", f.extrinsics);
  expect_geometry(import_opencv_calibration(in, ex, 640, 480), want, 0.0);
}

TEST(OpenCvImport, QIsComputedWhenAbsentAndSizeReadWhenRecorded) {
  const StereoCalibration want = test::sample_calibration();
  OpenCvFiles f = opencv_yaml(want, false);
  f.intrinsics += "image_width: 640\nimage_height: 480\n";
  const auto in = write_temp("cv-intrinsics-size.yml", f.intrinsics);
  const auto ex = write_temp("cv-extrinsics-noq.yml", f.extrinsics);
  expect_geometry(import_opencv_calibration(in, ex), want, 1e-12);
  // One file holding everything works too.
  const auto both = write_temp("cv-all.yml", f.intrinsics + f.extrinsics.substr(14));
  expect_geometry(import_opencv_calibration(both, both), want, 1e-12);
}

TEST(OpenCvImport, BadInputNamesTheKeyAndFile) {
  const StereoCalibration c = test::sample_calibration();
  const OpenCvFiles f = opencv_yaml(c);
  const auto in = write_temp("cv-in.yml", f.intrinsics);
  const auto ex = write_temp("cv-ex.yml", f.extrinsics);
  // No image size recorded or given.
  EXPECT_NE(error_of([&] { import_opencv_calibration(in, ex); }).find("image size"),
            std::string::npos);
  // Swapped files still find every key; a missing one is named with both files.
  const auto only_in = [&](const std::string& text) {
    const auto file = write_temp("cv-broken.yml", text);
    return error_of([&] { import_opencv_calibration(in, file, 640, 480); });
  };
  std::string e = only_in("%YAML:1.0\n" + yaml_matrix("R", c.R));
  EXPECT_NE(e.find("missing key 'T'"), std::string::npos) << e;
  EXPECT_NE(e.find("cv-broken.yml"), std::string::npos) << e;
  // Wrong sizes, bad numbers, bad dt.
  e = only_in(f.extrinsics + yaml_matrix("P1x", c.R));
  EXPECT_EQ(e, "") << e;
  std::string wrong = f.extrinsics;
  wrong.replace(wrong.find("R1: !!opencv-matrix\n   rows: 3\n   cols: 3"), 41,
                "R1: !!opencv-matrix\n   rows: 1\n   cols: 9");
  e = only_in(wrong);
  EXPECT_NE(e.find("R1: expected a 3x3 matrix, found 1x9"), std::string::npos) << e;
  std::string nan = f.extrinsics;
  nan.replace(nan.find("data", nan.find("T: !!")) + 8, 23, ".Nan");
  e = only_in(nan);
  EXPECT_NE(e.find("T"), std::string::npos) << e;
  EXPECT_NE(e.find("finite"), std::string::npos) << e;
  std::string dt = f.extrinsics;
  dt.replace(dt.find("dt: d"), 5, "dt: \"3d\"");
  e = only_in(dt);
  EXPECT_NE(e.find("single-channel"), std::string::npos) << e;
  e = only_in("%YAML:1.0\nR: [unclosed\n");
  EXPECT_NE(e.find("malformed YAML"), std::string::npos) << e;
  // A rotation that is not one, in OpenCV's names.
  std::string scaled = f.extrinsics;
  scaled.replace(scaled.find("data", scaled.find("R1: !!")) + 8, 22, "2.0");
  e = only_in(scaled);
  EXPECT_NE(e.find("R1: is not a rotation"), std::string::npos) << e;
}

TEST(OpenCvImport, OtherDistortionModels) {
  const StereoCalibration c = test::sample_calibration();
  OpenCvFiles f = opencv_yaml(c);
  Eigen::Matrix<double, 1, 8> rational = Eigen::Matrix<double, 1, 8>::Zero();
  rational.head<5>() = coefficients(c.left);
  // k4 k5 k6 all zero: the same model, accepted.
  const std::string d1 = yaml_matrix("D1", coefficients(c.left));
  std::string zero = f.intrinsics;
  zero.replace(zero.find(d1), d1.size(), yaml_matrix("D1", rational));
  const auto ex = write_temp("cv-ex-d.yml", f.extrinsics);
  const auto in_zero = write_temp("cv-in-d8.yml", zero);
  expect_geometry(import_opencv_calibration(in_zero, ex, 640, 480), c, 0.0);
  // A real rational model is refused, naming the coefficient.
  rational(6) = 0.01;
  std::string real = f.intrinsics;
  real.replace(real.find(d1), d1.size(), yaml_matrix("D1", rational));
  const auto in_real = write_temp("cv-in-d8r.yml", real);
  const std::string e = error_of([&] { import_opencv_calibration(in_real, ex, 640, 480); });
  EXPECT_NE(e.find("D1"), std::string::npos) << e;
  EXPECT_NE(e.find("not supported"), std::string::npos) << e;
  // Four coefficients: k3 = 0.
  std::string four = f.intrinsics;
  four.replace(four.find(d1), d1.size(),
               yaml_matrix("D1", Eigen::Matrix<double, 1, 4>(coefficients(c.left).head<4>())));
  const StereoCalibration got =
      import_opencv_calibration(write_temp("cv-in-d4.yml", four), ex, 640, 480);
  EXPECT_EQ(got.left.camera.distortion.k3, 0.0);
  EXPECT_EQ(got.left.camera.distortion.k1, c.left.camera.distortion.k1);
}

TEST(OpenCvImport, MalformedXml) {
  const StereoCalibration c = test::sample_calibration();
  const OpenCvFiles f = opencv_xml(c);
  const auto in = write_temp("cv-in.xml", f.intrinsics);
  for (const std::string& bad : {std::string("<?xml version=\"1.0\"?>\n<opencv_storage>\n<R>1 2 3"),
                                 std::string("<opencv_storage><R></T></opencv_storage>"),
                                 std::string("<opencv_storage><R a=1></R></opencv_storage>"),
                                 std::string("<opencv_storage>&bogus;</opencv_storage>"),
                                 std::string("<something_else/>")}) {
    SCOPED_TRACE(bad);
    const auto ex = write_temp("cv-bad.xml", bad);
    const std::string e = error_of([&] { import_opencv_calibration(in, ex, 640, 480); });
    EXPECT_NE(e.find("cv-bad.xml"), std::string::npos) << e;
  }
  // Entities and comments are fine.
  std::string commented = f.extrinsics;
  commented.insert(commented.find("<R type_id"), "<!-- a <comment> & more -->\n");
  const auto ex = write_temp("cv-commented.xml", commented);
  expect_geometry(import_opencv_calibration(in, ex, 640, 480), c, 0.0);
}

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

// `epipole calibrate --export-opencv/--export-ros`, then --from-opencv/--from-ros: the same
// calibration (OpenCV: every bit, so the same file; ROS: R and T recovered from the
// rectification, to rounding).
TEST(CalibrationExport, OpenCvFilesImportToTheSameFile) {
  const StereoCalibration want = test::sample_calibration();
  const std::filesystem::path folder = std::filesystem::path(::testing::TempDir()) / "export-cv";
  export_opencv_calibration(want, folder);
  StereoCalibration got =
      import_opencv_calibration(folder / "intrinsics.yml", folder / "extrinsics.yml");
  EXPECT_EQ(got.width, want.width) << "the size is in the files";
  expect_geometry(got, want, 0.0);
  // What the OpenCV files do not carry: the ids, the errors, the provenance.
  got.left.id = want.left.id;
  got.right.id = want.right.id;
  got.rms = want.rms;
  got.views = want.views;
  got.date = want.date;
  got.source = want.source;
  EXPECT_EQ(format_calibration(got), format_calibration(want));
}

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
              export_opencv_calibration(broken, std::filesystem::path(::testing::TempDir()));
            }),
            "")
      << "an invalid calibration is not exported";
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

}  // namespace
}  // namespace epipole::calib

// OpenCV's calibration files through cv::FileStorage (the host tool's import and export), from
// text in the exact form OpenCV's stereo_calib sample writes
// (tests/reference/calibration_opencv_test.cpp checks files written by cv::FileStorage itself).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../calib/calibration_checks.hpp"
#include "../calib/sample_calibration.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "error_of.hpp"

namespace epipole::tools {
namespace {

using calib::StereoCalibration;
using test::coefficients;
using test::error_of;
using test::expect_geometry;
using test::numbers;
using test::write_temp;

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
  expect_geometry(calib::parse_calibration(calib::format_calibration(got), "x.yaml"), want, 0.0);
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
  EXPECT_NE(e.find("cv-broken.yml: malformed YAML (line 2: "), std::string::npos) << e;
  e = only_in("R: [1, 2, 3]\n");
  EXPECT_NE(e.find("cv-broken.yml: not an OpenCV FileStorage file"), std::string::npos) << e;
  e = only_in("");
  EXPECT_NE(e.find("cv-broken.yml: the file is empty"), std::string::npos) << e;
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
  const std::string header = "<?xml version=\"1.0\"?>\n";
  const struct {
    std::string text;
    std::string error;
  } cases[] = {
      {header + "<opencv_storage>\n<R>1 2 3", "malformed XML (line 3: "},
      {header + "<opencv_storage><R></T></opencv_storage>", "malformed XML (line 2: "},
      {header + "<something_else/>", "malformed XML (line 2: <opencv_storage> tag is missing)"},
      {header + "<opencv_storage><R>1 2 x</R></opencv_storage>", "R: "},
      {"<opencv_storage><R>1</R></opencv_storage>", "not an OpenCV FileStorage file"},
      // OpenCV 4.6 crashes on these two; they are refused before it sees them.
      {"<?xml version=", "malformed XML (line 1: "},
      {header + std::string("<opencv_storage><R>1</R>\0</opencv_storage>", 42),
       "not a text file (a NUL byte at offset 46)"},
  };
  for (const auto& bad : cases) {
    SCOPED_TRACE(bad.text);
    const auto ex = write_temp("cv-bad.xml", bad.text);
    const std::string e = error_of([&] { import_opencv_calibration(in, ex, 640, 480); });
    EXPECT_NE(e.find("cv-bad.xml: " + bad.error), std::string::npos) << e;
  }
  // Entities and comments are fine.
  std::string commented = f.extrinsics;
  commented.insert(commented.find("<R type_id"), "<!-- a <comment> & more -->\n");
  const auto ex = write_temp("cv-commented.xml", commented);
  expect_geometry(import_opencv_calibration(in, ex, 640, 480), c, 0.0);
}

// OpenCV 4.6's parsers hang on some malformed YAML (found by calibration_fuzz) and overflow
// their stack on deep nesting in every syntax: each file is parsed in a child process first.
TEST(OpenCvImport, FilesThatHangOrCrashOpenCvAreRefused) {
  const StereoCalibration c = test::sample_calibration();
  const auto in = write_temp("cv-in.yml", opencv_yaml(c).intrinsics);
  const auto deep = [](const std::string& open, const std::string& close) {
    std::string text;
    for (int i = 0; i < 200000; ++i) text += open;
    for (int i = 0; i < 200000; ++i) text += close;
    return text;
  };
  const struct {
    std::string name;
    std::string text;
    std::string error;
  } cases[] = {
      {"cv-hang.yml", "%YAML:1.0\n c: 1\nD:\n-\n",
       "malformed YAML (OpenCV's reader was still parsing it after 5 s)"},
      {"cv-deep.yml", "%YAML:1.0\na: " + deep("[", "]") + "\n",
       "malformed YAML (OpenCV's reader crashed on it)"},
      {"cv-deep.json", "{\"a\": " + deep("[", "]") + "}\n",
       "malformed JSON (OpenCV's reader crashed on it)"},
      {"cv-deep.xml",
       "<?xml version=\"1.0\"?>\n<opencv_storage>" + deep("<a>", "</a>") + "</opencv_storage>\n",
       "malformed XML (OpenCV's reader crashed on it)"},
  };
  for (const auto& bad : cases) {
    SCOPED_TRACE(bad.name);
    const auto ex = write_temp(bad.name, bad.text);
    const std::string e = error_of([&] { import_opencv_calibration(in, ex, 640, 480); });
    EXPECT_TRUE(e.ends_with("/" + bad.name + ": " + bad.error)) << e;
  }
  // The good files are still read, after their trial.
  const auto ex = write_temp("cv-ex.yml", opencv_yaml(c).extrinsics);
  expect_geometry(import_opencv_calibration(in, ex, 640, 480), c, 0.0);
}

// FileStorage's third syntax: JSON, as cv::FileStorage writes it.
template <typename Derived>
std::string json_matrix(const char* name, const Eigen::MatrixBase<Derived>& m) {
  return cat("\"", name, "\": {\"type_id\": \"opencv-matrix\", \"rows\": ", m.rows(),
             ", \"cols\": ", m.cols(), ", \"dt\": \"d\", \"data\": [", numbers(m, ", "), "]}");
}

TEST(OpenCvImport, JsonGivesTheSameCalibration) {
  const StereoCalibration c = test::sample_calibration();
  const std::string json =
      "{\n\"image_width\": 640, \"image_height\": 480,\n" +
      json_matrix("M1", c.left.camera_matrix()) + ",\n" + json_matrix("D1", coefficients(c.left)) +
      ",\n" + json_matrix("M2", c.right.camera_matrix()) + ",\n" +
      json_matrix("D2", coefficients(c.right)) + ",\n" + json_matrix("R", c.R) + ",\n" +
      json_matrix("T", c.T) + ",\n" + json_matrix("R1", c.left.rectification) + ",\n" +
      json_matrix("R2", c.right.rectification) + ",\n" + json_matrix("P1", c.left.projection) +
      ",\n" + json_matrix("P2", c.right.projection) + "\n}\n";
  const auto file = write_temp("cv-all.json", json);
  expect_geometry(import_opencv_calibration(file, file), c, 1e-12);
  const auto broken = write_temp("cv-broken.json", json.substr(0, json.size() / 2));
  const std::string e = error_of([&] { import_opencv_calibration(broken, broken); });
  EXPECT_NE(e.find("cv-broken.json: malformed JSON (line "), std::string::npos) << e;
}

// `epipole calibrate --export-opencv`, then --from-opencv: every bit, so the same file.
TEST(OpenCvExport, FilesImportToTheSameFile) {
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
  EXPECT_EQ(calib::format_calibration(got), calib::format_calibration(want));
}

TEST(OpenCvExport, AFolderThatCannotBeMadeIsNamedAndAnInvalidCalibrationRefused) {
  const std::filesystem::path file = write_temp("not-a-folder-cv", "x");
  const std::string error =
      error_of([&] { export_opencv_calibration(test::sample_calibration(), file / "cv"); });
  EXPECT_NE(error.find("not-a-folder-cv/cv"), std::string::npos) << error;
  calib::StereoCalibration broken = test::sample_calibration();
  broken.width = 0;
  EXPECT_NE(error_of([&] {
              export_opencv_calibration(broken, std::filesystem::path(::testing::TempDir()));
            }),
            "")
      << "an invalid calibration is not exported";
}

}  // namespace
}  // namespace epipole::tools

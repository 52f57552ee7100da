// calib against OpenCV on the real chessboard pairs (samples/left*.jpg, right*.jpg): the
// calibration procedure against OpenCV's stereo_calib sample, imports of files written by
// cv::FileStorage, the map builder against cv::initUndistortRectifyMap, triangulation against
// cv::reprojectImageTo3D, and the health figure on real images of a rig turned by known angles.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/health.hpp"
#include "epipole/calib/rectification_map.hpp"
#include "epipole/calib/triangulation.hpp"
#include "epipole/firmware/stereo_rectification.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "opencv_view.hpp"
#include "test_data.hpp"

namespace epipole::calib {
namespace {

const cv::Size kBoard(9, 6);
constexpr double kSquare = 0.025;

std::vector<cv::Point2f> find_corners(const cv::Mat& image, bool* found) {
  std::vector<cv::Point2f> corners;
  *found = cv::findChessboardCorners(image, kBoard, corners,
                                     cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  if (*found) {
    cv::cornerSubPix(image, corners, {11, 11}, {-1, -1},
                     {cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01});
  }
  return corners;
}

struct DataSet {
  std::vector<std::string> ids;
  std::vector<std::vector<cv::Point3f>> objects;
  std::vector<std::vector<cv::Point2f>> left;
  std::vector<std::vector<cv::Point2f>> right;
  cv::Size size;
};

// The 13 pairs' corners, detected once.
const DataSet& data_set() {
  static const DataSet data = [] {
    DataSet d;
    std::vector<cv::Point3f> object;
    for (int r = 0; r < kBoard.height; ++r) {
      for (int c = 0; c < kBoard.width; ++c) {
        object.emplace_back(static_cast<float>(c * kSquare), static_cast<float>(r * kSquare), 0.0f);
      }
    }
    for (const char* id :
         {"01", "02", "03", "04", "05", "06", "07", "08", "09", "11", "12", "13", "14"}) {
      const cv::Mat l = cv::imread(test::data_file(std::string("samples/left") + id + ".jpg"),
                                   cv::IMREAD_GRAYSCALE);
      const cv::Mat r = cv::imread(test::data_file(std::string("samples/right") + id + ".jpg"),
                                   cv::IMREAD_GRAYSCALE);
      bool found_l = false;
      bool found_r = false;
      auto cl = find_corners(l, &found_l);
      auto cr = find_corners(r, &found_r);
      if (!found_l || !found_r) continue;
      d.ids.emplace_back(id);
      d.objects.push_back(object);
      d.left.push_back(std::move(cl));
      d.right.push_back(std::move(cr));
      d.size = l.size();
    }
    return d;
  }();
  return data;
}

struct CvStereo {
  double rms = 0;
  cv::Mat K1, D1, K2, D2, R, T, R1, R2, P1, P2, Q;
};

CvStereo deep_copy(const CvStereo& s) {
  // cv::Mat copies share their data, and OpenCV writes into outputs of the right size in place.
  return {s.rms,       s.K1.clone(), s.D1.clone(), s.K2.clone(), s.D2.clone(), s.R.clone(),
          s.T.clone(), s.R1.clone(), s.R2.clone(), s.P1.clone(), s.P2.clone(), s.Q.clone()};
}

// What `epipole calibrate` does: each camera alone, then stereoCalibrate with every parameter
// free, then stereoRectify (alpha 0). Computed once; each caller gets its own copy.
CvStereo epipole_procedure() {
  static const CvStereo s = [] {
    const DataSet& d = data_set();
    CvStereo c;
    std::vector<cv::Mat> rv, tv;
    cv::calibrateCamera(d.objects, d.left, d.size, c.K1, c.D1, rv, tv);
    cv::calibrateCamera(d.objects, d.right, d.size, c.K2, c.D2, rv, tv);
    cv::Mat E, F, errors;
    c.rms = cv::stereoCalibrate(d.objects, d.left, d.right, c.K1, c.D1, c.K2, c.D2, d.size, c.R,
                                c.T, E, F, errors, cv::CALIB_USE_INTRINSIC_GUESS,
                                {cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10});
    cv::stereoRectify(c.K1, c.D1, c.K2, c.D2, d.size, c.R, c.T, c.R1, c.R2, c.P1, c.P2, c.Q,
                      cv::CALIB_ZERO_DISPARITY, 0);
    return c;
  }();
  return deep_copy(s);
}

// Mean |y_left - y_right| of the corners rectified by cv::undistortPoints (iterated to
// convergence).
double opencv_row_error(const CvStereo& c) {
  const DataSet& d = data_set();
  const cv::TermCriteria converge(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-14);
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < d.left.size(); ++i) {
    std::vector<cv::Point2f> l, r;
    cv::undistortPoints(d.left[i], l, c.K1, c.D1, c.R1, c.P1, converge);
    cv::undistortPoints(d.right[i], r, c.K2, c.D2, c.R2, c.P2, converge);
    for (std::size_t j = 0; j < l.size(); ++j) {
      sum += std::abs(static_cast<double>(l[j].y) - static_cast<double>(r[j].y));
      ++n;
    }
  }
  return sum / n;
}

template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> eigen(const cv::Mat& m) {
  Eigen::Matrix<double, Rows, Cols> e;
  for (int r = 0; r < Rows; ++r) {
    for (int c = 0; c < Cols; ++c) e(r, c) = m.at<double>(r * Cols + c);
  }
  return e;
}

CameraCalibration camera(const cv::Mat& k, const cv::Mat& d, const cv::Mat& r, const cv::Mat& p) {
  CameraCalibration c;
  c.camera.intrinsics = {k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2),
                         k.at<double>(1, 2)};
  c.camera.distortion = {d.at<double>(0), d.at<double>(1), d.at<double>(2), d.at<double>(3),
                         d.total() > 4 ? d.at<double>(4) : 0.0};
  c.rectification = eigen<3, 3>(r);
  c.projection = eigen<3, 4>(p);
  return c;
}

StereoCalibration calibration_of(const CvStereo& s, cv::Size size) {
  StereoCalibration c;
  c.width = size.width;
  c.height = size.height;
  c.left = camera(s.K1, s.D1, s.R1, s.P1);
  c.right = camera(s.K2, s.D2, s.R2, s.P2);
  c.left.id = "left";
  c.right.id = "right";
  c.R = eigen<3, 3>(s.R);
  c.T = eigen<3, 1>(s.T);
  c.Q = eigen<4, 4>(s.Q);
  c.date = utc_now();
  validate(c);
  return c;
}

std::filesystem::path temp(const std::string& name) {
  return std::filesystem::path(::testing::TempDir()) / name;
}

void write_storage(const CvStereo& s, const std::string& suffix) {
  cv::FileStorage in(temp("cv-intrinsics" + suffix).string(), cv::FileStorage::WRITE);
  in << "M1" << s.K1 << "D1" << s.D1 << "M2" << s.K2 << "D2" << s.D2;
  in.release();
  cv::FileStorage ex(temp("cv-extrinsics" + suffix).string(), cv::FileStorage::WRITE);
  ex << "R" << s.R << "T" << s.T << "R1" << s.R1 << "R2" << s.R2 << "P1" << s.P1 << "P2" << s.P2
     << "Q" << s.Q;
  ex.release();
}

void expect_exact(const StereoCalibration& c, const CvStereo& s, bool q_in_file = true) {
  EXPECT_EQ(c.left.camera_matrix(), (eigen<3, 3>(s.K1)));
  EXPECT_EQ(c.right.camera_matrix(), (eigen<3, 3>(s.K2)));
  const Distortion& d = c.right.camera.distortion;
  EXPECT_EQ(d.k1, s.D2.at<double>(0));
  EXPECT_EQ(d.p2, s.D2.at<double>(3));
  EXPECT_EQ(d.k3, s.D2.at<double>(4));
  EXPECT_EQ(c.R, (eigen<3, 3>(s.R)));
  EXPECT_EQ(c.T, (eigen<3, 1>(s.T)));
  EXPECT_EQ(c.left.rectification, (eigen<3, 3>(s.R1)));
  EXPECT_EQ(c.right.rectification, (eigen<3, 3>(s.R2)));
  EXPECT_EQ(c.left.projection, (eigen<3, 4>(s.P1)));
  EXPECT_EQ(c.right.projection, (eigen<3, 4>(s.P2)));
  if (q_in_file) {
    EXPECT_EQ(c.Q, (eigen<4, 4>(s.Q)));
  } else {
    EXPECT_LT((c.Q - eigen<4, 4>(s.Q)).cwiseAbs().maxCoeff(), 1e-9);  // computed from P1, P2
  }
}

TEST(CalibrationVsOpenCV, AllThirteenPairsAreFound) {
  EXPECT_EQ(data_set().ids.size(), 13u);
  EXPECT_EQ(data_set().size, cv::Size(640, 480));
}

// The design brief: OpenCV's stereo_calib sample gives RMS 0.634 px and a rectified row error
// of 0.185 px on these pairs. The epipole procedure must do no worse on either.
TEST(CalibrationVsOpenCV, NoWorseThanTheStereoCalibSample) {
  const DataSet& d = data_set();
  CvStereo sample;
  sample.K1 = cv::initCameraMatrix2D(d.objects, d.left, d.size, 0);
  sample.K2 = cv::initCameraMatrix2D(d.objects, d.right, d.size, 0);
  cv::Mat E, F, errors;
  sample.rms = cv::stereoCalibrate(d.objects, d.left, d.right, sample.K1, sample.D1, sample.K2,
                                   sample.D2, d.size, sample.R, sample.T, E, F, errors,
                                   cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_ZERO_TANGENT_DIST |
                                       cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_SAME_FOCAL_LENGTH |
                                       cv::CALIB_RATIONAL_MODEL | cv::CALIB_FIX_K3 |
                                       cv::CALIB_FIX_K4 | cv::CALIB_FIX_K5,
                                   {cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-5});
  cv::stereoRectify(sample.K1, sample.D1, sample.K2, sample.D2, d.size, sample.R, sample.T,
                    sample.R1, sample.R2, sample.P1, sample.P2, sample.Q, cv::CALIB_ZERO_DISPARITY,
                    1);
  const double sample_row_error = opencv_row_error(sample);
  EXPECT_NEAR(sample.rms, 0.634, 0.005);
  EXPECT_NEAR(sample_row_error, 0.185, 0.005);

  const CvStereo ours = epipole_procedure();
  const double our_row_error = opencv_row_error(ours);
  std::printf(
      "stereo_calib sample: RMS %.4f px, row error %.4f px; epipole: RMS %.4f px, row "
      "error %.4f px\n",
      sample.rms, sample_row_error, ours.rms, our_row_error);
  EXPECT_LT(ours.rms, sample.rms);
  EXPECT_LT(our_row_error, sample_row_error);

  // calib's own measure (rectify_point) agrees with OpenCV's undistortPoints.
  const StereoCalibration c = calibration_of(ours, d.size);
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < d.left.size(); ++i) {
    for (std::size_t j = 0; j < d.left[i].size(); ++j) {
      const Eigen::Vector2d l = rectify_point(c.left, {d.left[i][j].x, d.left[i][j].y});
      const Eigen::Vector2d r = rectify_point(c.right, {d.right[i][j].x, d.right[i][j].y});
      sum += std::abs(l.y() - r.y());
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, our_row_error, 1e-4);
}

TEST(CalibrationVsOpenCV, ImportsFileStorageYamlAndXml) {
  const CvStereo s = epipole_procedure();
  for (const std::string suffix : {".yml", ".xml", ".yaml"}) {
    SCOPED_TRACE(suffix);
    write_storage(s, suffix);
    const StereoCalibration c = tools::import_opencv_calibration(
        temp("cv-intrinsics" + suffix), temp("cv-extrinsics" + suffix), 640, 480);
    expect_exact(c, s);
    // And through our own file, unchanged.
    const std::filesystem::path file = temp("imported" + suffix + ".rig.yaml");
    save_calibration(file, c);
    expect_exact(load_calibration(file), s);
  }
}

// `epipole calibrate --export-opencv`: OpenCV's FileStorage reads the files and finds the
// calibration's matrices, every bit, and the image size.
TEST(CalibrationVsOpenCV, ExportedFilesAreReadByFileStorage) {
  const CvStereo s = epipole_procedure();
  write_storage(s, ".yml");
  const StereoCalibration c = tools::import_opencv_calibration(temp("cv-intrinsics.yml"),
                                                               temp("cv-extrinsics.yml"), 640, 480);
  const std::filesystem::path folder = temp("exported-opencv");
  tools::export_opencv_calibration(c, folder);
  CvStereo read;
  cv::FileStorage in((folder / "intrinsics.yml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(in.isOpened());
  in["M1"] >> read.K1;
  in["D1"] >> read.D1;
  in["M2"] >> read.K2;
  in["D2"] >> read.D2;
  EXPECT_EQ(static_cast<int>(in["image_width"]), 640);
  EXPECT_EQ(static_cast<int>(in["image_height"]), 480);
  cv::FileStorage ex((folder / "extrinsics.yml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(ex.isOpened());
  ex["R"] >> read.R;
  ex["T"] >> read.T;
  ex["R1"] >> read.R1;
  ex["R2"] >> read.R2;
  ex["P1"] >> read.P1;
  ex["P2"] >> read.P2;
  ex["Q"] >> read.Q;
  expect_exact(c, read);
  EXPECT_EQ(read.D1.total(), 5u);
  EXPECT_EQ(c.left.camera.distortion.k2, read.D1.at<double>(1));
}

TEST(CalibrationVsOpenCV, ImportsTheDataSetsIntrinsics) {
  // samples/intrinsics.yml as OpenCV wrote it (M1 D1 M2 D2), with extrinsics rectified for it.
  const std::filesystem::path intrinsics = test::data_file("samples/intrinsics.yml");
  cv::FileStorage fs(intrinsics.string(), cv::FileStorage::READ);
  CvStereo s = epipole_procedure();
  fs["M1"] >> s.K1;
  fs["D1"] >> s.D1;
  fs["M2"] >> s.K2;
  fs["D2"] >> s.D2;
  cv::stereoRectify(s.K1, s.D1, s.K2, s.D2, {640, 480}, s.R, s.T, s.R1, s.R2, s.P1, s.P2, s.Q,
                    cv::CALIB_ZERO_DISPARITY, 0);
  cv::FileStorage ex(temp("cv-data-extrinsics.yml").string(), cv::FileStorage::WRITE);
  ex << "R" << s.R << "T" << s.T << "R1" << s.R1 << "R2" << s.R2 << "P1" << s.P1 << "P2" << s.P2;
  ex.release();
  const StereoCalibration c =
      tools::import_opencv_calibration(intrinsics, temp("cv-data-extrinsics.yml"), 640, 480);
  expect_exact(c, s, false);
}

TEST(CalibrationVsOpenCV, QFromProjectionsIsStereoRectifysQ) {
  CvStereo s = epipole_procedure();
  const cv::Size size(640, 480);
  for (const double alpha : {0.0, 0.5, 1.0}) {
    for (const bool vertical : {false, true}) {
      SCOPED_TRACE(cat("alpha ", alpha, vertical ? " vertical" : " horizontal"));
      cv::Mat t = s.T.clone();
      if (vertical) std::swap(t.at<double>(0), t.at<double>(1));
      for (const int flags : {static_cast<int>(cv::CALIB_ZERO_DISPARITY), 0}) {
        cv::Mat R1, R2, P1, P2, Q;
        cv::stereoRectify(s.K1, s.D1, s.K2, s.D2, size, s.R, t, R1, R2, P1, P2, Q, flags, alpha);
        const Eigen::Matrix4d ours = disparity_to_depth(eigen<3, 4>(P1), eigen<3, 4>(P2));
        EXPECT_LT((ours - eigen<4, 4>(Q)).cwiseAbs().maxCoeff(), 1e-9) << ours << "\n" << Q;
      }
    }
  }
}

// Every entry of both cameras' maps within one fixed-point step of OpenCV's, over the image.
void expect_maps_match(const StereoCalibration& c, const cv::Mat& K1, const cv::Mat& D1,
                       const cv::Mat& K2, const cv::Mat& D2, const cv::Mat& R1, const cv::Mat& R2,
                       const cv::Mat& P1, const cv::Mat& P2) {
  const cv::Size size(c.width, c.height);
  const struct {
    Side side;
    const cv::Mat &K, &D, &R, &P;
  } cameras[] = {{Side::left, K1, D1, R1, P1}, {Side::right, K2, D2, R2, P2}};
  for (const auto& cam : cameras) {
    const char* name = cam.side == Side::left ? "left" : "right";
    SCOPED_TRACE(name);
    cv::Mat map1, map2, fx, fy;
    cv::initUndistortRectifyMap(cam.K, cam.D, cam.R, cam.P, size, CV_16SC2, map1, map2);
    cv::initUndistortRectifyMap(cam.K, cam.D, cam.R, cam.P, size, CV_32FC1, fx, fy);
    const FixedPointMap ours = build_fixed_point_map(c, cam.side);
    Image<float> xs(c.width, c.height);
    Image<float> ys(c.width, c.height);
    build_float_map(camera_of(c, cam.side), xs.view(), ys.view());
    long long exact = 0;
    long long worst = 0;
    double worst_float = 0;
    for (int v = 0; v < c.height; ++v) {
      for (int u = 0; u < c.width; ++u) {
        const cv::Vec2s cv_xy = map1.at<cv::Vec2s>(v, u);
        const int cv_fraction = map2.at<std::uint16_t>(v, u) & 1023;
        const int our_fraction = ours.fractions(u, v);
        const long long cx = cv_xy[0] * 32LL + (cv_fraction & 31);
        const long long cy = cv_xy[1] * 32LL + (cv_fraction >> 5);
        const long long ox = ours.xy(2 * u, v) * 32LL + (our_fraction & 31);
        const long long oy = ours.xy(2 * u + 1, v) * 32LL + (our_fraction >> 5);
        const long long d = std::max(std::llabs(cx - ox), std::llabs(cy - oy));
        worst = std::max(worst, d);
        exact += d == 0;
        worst_float = std::max(
            {worst_float,
             std::abs(static_cast<double>(xs(u, v)) - static_cast<double>(fx.at<float>(v, u))),
             std::abs(static_cast<double>(ys(u, v)) - static_cast<double>(fy.at<float>(v, u)))});
      }
    }
    std::printf(
        "%s map: %lld of %d entries identical to initUndistortRectifyMap, largest "
        "difference %lld step(s); float maps differ by at most %.2e px\n",
        name, exact, c.width * c.height, worst, worst_float);
    EXPECT_LE(worst, 1);
    EXPECT_GT(exact, c.width * c.height * 99LL / 100);
    EXPECT_LT(worst_float, 1e-3);
  }
}

TEST(CalibrationVsOpenCV, MapsWithinOneFixedPointStepOfInitUndistortRectifyMap) {
  const CvStereo s = epipole_procedure();
  expect_maps_match(calibration_of(s, {640, 480}), s.K1, s.D1, s.K2, s.D2, s.R1, s.R2, s.P1, s.P2);
}

TEST(CalibrationVsOpenCV, MapsMatchForTheDataSetsIntrinsicsAtEveryAlpha) {
  cv::FileStorage fs(test::data_file("samples/intrinsics.yml").string(), cv::FileStorage::READ);
  CvStereo s = epipole_procedure();
  fs["M1"] >> s.K1;
  fs["D1"] >> s.D1;
  fs["M2"] >> s.K2;
  fs["D2"] >> s.D2;
  for (const double alpha : {0.0, 1.0}) {
    SCOPED_TRACE(alpha);
    cv::stereoRectify(s.K1, s.D1, s.K2, s.D2, {640, 480}, s.R, s.T, s.R1, s.R2, s.P1, s.P2, s.Q,
                      cv::CALIB_ZERO_DISPARITY, alpha);
    expect_maps_match(calibration_of(s, {640, 480}), s.K1, s.D1, s.K2, s.D2, s.R1, s.R2, s.P1,
                      s.P2);
  }
}

// The rectified images themselves: calib's maps in the firmware's Rectifier against
// cv::remap with OpenCV's maps. Pixels differ only where a map entry is one step apart.
TEST(CalibrationVsOpenCV, RectifiedImagesAgreeWithCvRemap) {
  const CvStereo s = epipole_procedure();
  const StereoCalibration c = calibration_of(s, {640, 480});
  firmware::StereoRectifiers rectifiers = firmware::make_stereo_rectifiers(c);
  const cv::Mat left = cv::imread(test::data_file("samples/left01.jpg"), cv::IMREAD_GRAYSCALE);
  cv::Mat map1, map2, expected;
  cv::initUndistortRectifyMap(s.K1, s.D1, s.R1, s.P1, left.size(), CV_16SC2, map1, map2);
  cv::remap(left, expected, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  const GrayView ours = rectifiers.left.rectify(test::view_of(left));
  int differ = 0;
  int worst = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const int d = std::abs(ours(u, v) - expected.at<std::uint8_t>(v, u));
      differ += d != 0;
      worst = std::max(worst, d);
    }
  }
  std::printf("rectified left01: %d of 307200 pixels differ from cv::remap, by at most %d\n",
              differ, worst);
  EXPECT_LT(differ, 307200 / 100);
  EXPECT_LE(worst, 8);  // one 1/32 step of a bilinear weight on a strong edge
}

TEST(CalibrationVsOpenCV, RectifyPointMatchesUndistortPoints) {
  const CvStereo s = epipole_procedure();
  const StereoCalibration c = calibration_of(s, {640, 480});
  const DataSet& d = data_set();
  std::vector<cv::Point2d> raw;
  for (int v = 0; v <= 480; v += 24) {
    for (int u = 0; u <= 640; u += 32) raw.emplace_back(u, v);
  }
  for (const auto& corner : d.left[0]) raw.emplace_back(corner.x, corner.y);
  std::vector<cv::Point2d> expected;
  cv::undistortPoints(raw, expected, s.K1, s.D1, s.R1, s.P1,
                      {cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 500, 1e-15});
  double worst = 0;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const Eigen::Vector2d p = rectify_point(c.left, {raw[i].x, raw[i].y});
    worst = std::max(worst, (p - Eigen::Vector2d(expected[i].x, expected[i].y)).norm());
  }
  std::printf("rectify_point vs undistortPoints: largest difference %.2e px\n", worst);
  EXPECT_LT(worst, 1e-6);
}

TEST(CalibrationVsOpenCV, TriangulationMatchesReprojectImageTo3D) {
  const CvStereo s = epipole_procedure();
  cv::Mat disparity(480, 640, CV_32FC1);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> any(0.25f, 128.0f);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) disparity.at<float>(v, u) = any(rng);
  }
  cv::Mat expected;
  cv::reprojectImageTo3D(disparity, expected, s.Q, false, CV_32F);
  Triangulator t(calibration_of(s, {640, 480}));
  const ImageView<const Point3f> points = t.reproject(ImageView<const float>(
      disparity.ptr<float>(), 640, 480, static_cast<std::ptrdiff_t>(disparity.step1())));
  double worst = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const cv::Vec3f e = expected.at<cv::Vec3f>(v, u);
      const Point3f p = points(u, v);
      const double norm = std::sqrt(static_cast<double>(e.dot(e)));
      const double error = std::sqrt(std::pow(static_cast<double>(p.x - e[0]), 2) +
                                     std::pow(static_cast<double>(p.y - e[1]), 2) +
                                     std::pow(static_cast<double>(p.z - e[2]), 2));
      worst = std::max(worst, error / norm);
    }
  }
  std::printf("triangulation vs reprojectImageTo3D: largest relative difference %.2e\n", worst);
  EXPECT_LT(worst, 1e-6);  // both compute in double and round to float
}

// The health figure on real images: calibrations whose R is turned by known angles about the
// x axis (stereoRectify redone for each), the pairs rectified by the firmware's rectifiers, the
// board's corners found again in the rectified images and matched by index.
TEST(CalibrationVsOpenCV, HealthFigureFollowsRotationsOnRealImages) {
  const CvStereo base = epipole_procedure();
  std::vector<cv::Mat> lefts;
  std::vector<cv::Mat> rights;
  for (const char* id :
       {"01", "02", "03", "04", "05", "06", "07", "08", "09", "11", "12", "13", "14"}) {
    lefts.push_back(cv::imread(test::data_file(std::string("samples/left") + id + ".jpg"),
                               cv::IMREAD_GRAYSCALE));
    rights.push_back(cv::imread(test::data_file(std::string("samples/right") + id + ".jpg"),
                                cv::IMREAD_GRAYSCALE));
  }
  CalibrationHealth health(static_cast<int>(lefts.size()) * 54);
  double previous = -1;
  double baseline_signed = 0;
  for (const double degrees : {0.0, 0.05, 0.1, 0.2}) {
    SCOPED_TRACE(degrees);
    CvStereo s = deep_copy(base);
    const double angle = degrees * std::numbers::pi / 180;
    const cv::Matx33d turn(1, 0, 0, 0, std::cos(angle), -std::sin(angle), 0, std::sin(angle),
                           std::cos(angle));
    s.R = cv::Mat(turn * cv::Matx33d(base.R));
    cv::stereoRectify(s.K1, s.D1, s.K2, s.D2, {640, 480}, s.R, s.T, s.R1, s.R2, s.P1, s.P2, s.Q,
                      cv::CALIB_ZERO_DISPARITY, 0);
    const StereoCalibration c = calibration_of(s, {640, 480});
    firmware::StereoRectifiers rectifiers = firmware::make_stereo_rectifiers(c);
    std::vector<RectifiedMatch> matches;
    for (std::size_t i = 0; i < lefts.size(); ++i) {
      const GrayView l = rectifiers.left.rectify(test::view_of(lefts[i]));
      const GrayView r = rectifiers.right.rectify(test::view_of(rights[i]));
      const cv::Mat lm(480, 640, CV_8UC1, const_cast<std::uint8_t*>(l.data()),
                       static_cast<std::size_t>(l.stride()));
      const cv::Mat rm(480, 640, CV_8UC1, const_cast<std::uint8_t*>(r.data()),
                       static_cast<std::size_t>(r.stride()));
      bool found_l = false;
      bool found_r = false;
      const auto cl = find_corners(lm.clone(), &found_l);
      auto cr = find_corners(rm.clone(), &found_r);
      if (!found_l || !found_r) continue;
      // findChessboardCorners may start from the opposite corner in one image: match the
      // orderings (reversed, corresponding corners would be rows of squares apart).
      double same = 0;
      double reversed = 0;
      for (std::size_t j = 0; j < cl.size(); ++j) {
        same += static_cast<double>(std::abs(cl[j].y - cr[j].y));
        reversed += static_cast<double>(std::abs(cl[j].y - cr[cr.size() - 1 - j].y));
      }
      if (reversed < same) std::reverse(cr.begin(), cr.end());
      for (std::size_t j = 0; j < cl.size(); ++j) {
        matches.push_back({cl[j].x, cl[j].y, cr[j].x, cr[j].y});
      }
    }
    ASSERT_GE(matches.size(), 4u * 54);  // boards found in both cropped rectified images
    const HealthFigure h = health.measure(matches);
    const double predicted = c.left.projection(1, 1) * std::tan(angle);
    if (degrees == 0) baseline_signed = h.median_signed_px;
    std::printf(
        "real images, R turned %.2f deg: %d matches, median %.3f px, p90 %.3f px, signed "
        "median %+.3f px (predicted shift %.3f px)\n",
        degrees, h.matches, h.median_px, h.p90_px, h.median_signed_px, predicted);
    if (degrees == 0) {
      EXPECT_LT(h.median_px, 0.15);
    } else {
      EXPECT_NEAR(std::abs(h.median_signed_px - baseline_signed), predicted, 0.15 * predicted);
    }
    EXPECT_GT(h.median_px, previous);
    previous = h.median_px;
  }
}

}  // namespace
}  // namespace epipole::calib

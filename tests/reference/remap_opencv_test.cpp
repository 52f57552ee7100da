// The rectifier against cv::remap(INTER_LINEAR, BORDER_CONSTANT) with the same fixed-point maps,
// built by cv::initUndistortRectifyMap from the real calibration of the data set's stereo
// camera, on real images; and the float-to-fixed conversion against cv::convertMaps.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "epipole/vision/remap.hpp"
#include "opencv_view.hpp"
#include "test_data.hpp"

namespace epipole::vision {
namespace {

// Our map from OpenCV's CV_16SC2 + CV_16UC1 pair: the same bytes.
RemapMap from_opencv(const cv::Mat& map1, const cv::Mat& map2) {
  CV_Assert(map1.type() == CV_16SC2 && map2.type() == CV_16UC1 && map1.size() == map2.size());
  const ImageView<const std::int16_t> xy(map1.ptr<std::int16_t>(), 2 * map1.cols, map1.rows,
                                         static_cast<std::ptrdiff_t>(map1.step1()));
  const ImageView<const std::uint16_t> fractions(map2.ptr<std::uint16_t>(), map2.cols, map2.rows,
                                                 static_cast<std::ptrdiff_t>(map2.step1()));
  return RemapMap(xy, fractions);
}

ImageView<const float> float_view(const cv::Mat& mat) {
  CV_Assert(mat.type() == CV_32FC1);
  return {mat.ptr<float>(), mat.cols, mat.rows, static_cast<std::ptrdiff_t>(mat.step1())};
}

cv::Mat read_gray(const char* name) {
  cv::Mat gray = cv::imread(test::data_file(std::string("samples/") + name), cv::IMREAD_GRAYSCALE);
  if (gray.empty()) throw std::runtime_error(std::string("cannot read ") + name);
  return gray;
}

// The rectification of the data set's stereo camera (samples/intrinsics.yml: M1, D1, M2, D2,
// 640x480) for a rig with a 6 cm baseline and a relative rotation of about 1.5 degrees.
struct StereoMaps {
  cv::Mat left_xy, left_fraction, right_xy, right_fraction;  // CV_16SC2, CV_16UC1
  cv::Mat left_x, left_y;                                    // the left map as CV_32FC1
};

StereoMaps stereo_maps() {
  cv::FileStorage file(test::data_file("samples/intrinsics.yml").string(), cv::FileStorage::READ);
  cv::Mat m1, d1, m2, d2;
  file["M1"] >> m1;
  file["D1"] >> d1;
  file["M2"] >> m2;
  file["D2"] >> d2;
  if (m1.empty() || d1.empty() || m2.empty() || d2.empty())
    throw std::runtime_error("intrinsics.yml lacks M1, D1, M2 or D2");
  const cv::Size size(640, 480);
  cv::Mat rotation;
  cv::Rodrigues(cv::Vec3d(0.012, -0.021, 0.008), rotation);
  const cv::Vec3d translation(-0.06, 0.0015, 0.0008);
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(m1, d1, m2, d2, size, rotation, translation, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0.3, size);
  StereoMaps maps;
  cv::initUndistortRectifyMap(m1, d1, r1, p1, size, CV_16SC2, maps.left_xy, maps.left_fraction);
  cv::initUndistortRectifyMap(m2, d2, r2, p2, size, CV_16SC2, maps.right_xy, maps.right_fraction);
  cv::initUndistortRectifyMap(m1, d1, r1, p1, size, CV_32FC1, maps.left_x, maps.left_y);
  return maps;
}

struct Agreement {
  int differing = 0;
  int max_difference = 0;
};

Agreement compare(const cv::Mat& expected, GrayView ours) {
  Agreement a;
  for (int y = 0; y < expected.rows; ++y)
    for (int x = 0; x < expected.cols; ++x) {
      const int d = std::abs(static_cast<int>(expected.at<std::uint8_t>(y, x)) - ours(x, y));
      a.differing += d != 0;
      a.max_difference = std::max(a.max_difference, d);
    }
  return a;
}

void expect_like_opencv(const char* name, const cv::Mat& gray, const cv::Mat& xy,
                        const cv::Mat& fraction) {
  ASSERT_EQ(gray.size(), cv::Size(640, 480)) << name;
  for (const int border : {0, 128}) {
    cv::Mat expected;
    cv::remap(gray, expected, xy, fraction, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
              cv::Scalar(border));
    // Pixels OpenCV takes (at least partly) from the border: the map reaches outside.
    int border_pixels = 0;
    for (int y = 0; y < xy.rows; ++y)
      for (int x = 0; x < xy.cols; ++x) {
        const cv::Vec2s s = xy.at<cv::Vec2s>(y, x);
        border_pixels += s[0] < 0 || s[1] < 0 || s[0] >= gray.cols - 1 || s[1] >= gray.rows - 1;
      }
    for (const SimdPath path : available_simd_paths()) {
      Rectifier rectifier({.source_width = gray.cols,
                           .source_height = gray.rows,
                           .width = xy.cols,
                           .height = xy.rows,
                           .border = static_cast<std::uint8_t>(border)},
                          from_opencv(xy, fraction), path);
      const Agreement a = compare(expected, rectifier.rectify(test::view_of(gray)));
      std::printf(
          "remap vs cv::remap: %s border %d %s: %d of %d pixels differ, max %d "
          "(%d pixels at the border)\n",
          name, border, std::string(to_string(path)).c_str(), a.differing, xy.cols * xy.rows,
          a.max_difference, border_pixels);
      EXPECT_LE(a.max_difference, 1) << name << " " << to_string(path);
      // The arithmetic is OpenCV's: identical results are expected, not just close ones.
      EXPECT_EQ(a.differing, 0) << name << " " << to_string(path);
      EXPECT_GT(border_pixels, 100) << name << ": the map should reach outside the image";
    }
  }
}

TEST(RemapVsOpenCV, SameRectificationOnRealStereoPair) {
  const StereoMaps maps = stereo_maps();
  expect_like_opencv("left01", read_gray("left01.jpg"), maps.left_xy, maps.left_fraction);
  expect_like_opencv("right01", read_gray("right01.jpg"), maps.right_xy, maps.right_fraction);
  cv::Mat aloe_small;
  cv::resize(read_gray("aloeL.jpg"), aloe_small, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  expect_like_opencv("aloeL_640x480", aloe_small, maps.left_xy, maps.left_fraction);
}

TEST(RemapVsOpenCV, SameRectificationWithTheSingleCameraCalibration) {
  // samples/left_intrinsics.yml: camera_matrix, distortion_coefficients (k1 k2 p1 p2 k3), with
  // a 3 degree rotation and a new camera matrix that zooms out a little.
  cv::FileStorage file(test::data_file("samples/left_intrinsics.yml").string(),
                       cv::FileStorage::READ);
  cv::Mat camera, distortion;
  file["camera_matrix"] >> camera;
  file["distortion_coefficients"] >> distortion;
  ASSERT_FALSE(camera.empty() || distortion.empty());
  cv::Mat rotation;
  cv::Rodrigues(cv::Vec3d(0.0, 0.05, 0.02), rotation);
  cv::Mat new_camera = camera.clone();
  new_camera.at<double>(0, 0) *= 0.85;
  new_camera.at<double>(1, 1) *= 0.85;
  cv::Mat xy, fraction;
  cv::initUndistortRectifyMap(camera, distortion, rotation, new_camera, cv::Size(640, 480),
                              CV_16SC2, xy, fraction);
  expect_like_opencv("left02 (left_intrinsics)", read_gray("left02.jpg"), xy, fraction);
}

TEST(RemapVsOpenCV, FloatToFixedLikeConvertMaps) {
  const StereoMaps maps = stereo_maps();
  // Awkward values too: exact ties at 1/64, negative ties, large and just-outside coordinates.
  cv::Mat awkward_x(7, 33, CV_32FC1), awkward_y(7, 33, CV_32FC1);
  for (int y = 0; y < awkward_x.rows; ++y)
    for (int x = 0; x < awkward_x.cols; ++x) {
      const float tie = static_cast<float>(x - 16) / 64.0f;
      awkward_x.at<float>(y, x) = tie * static_cast<float>(1 + 37 * y);
      awkward_y.at<float>(y, x) = -tie * static_cast<float>(y * y * 1000 + 1) + 0.3f;
    }
  cv::Mat fixed_xy, fixed_fraction;
  const std::pair<cv::Mat, cv::Mat> inputs[] = {{maps.left_x, maps.left_y}, {awkward_x, awkward_y}};
  for (const auto& [map_x, map_y] : inputs) {
    cv::convertMaps(map_x, map_y, fixed_xy, fixed_fraction, CV_16SC2, false);
    const RemapMap ours = RemapMap::from_float(float_view(map_x), float_view(map_y));
    int differing = 0;
    for (int y = 0; y < map_x.rows; ++y)
      for (int x = 0; x < map_x.cols; ++x) {
        const cv::Vec2s s = fixed_xy.at<cv::Vec2s>(y, x);
        const bool same = ours.xy()(2 * x, y) == s[0] && ours.xy()(2 * x + 1, y) == s[1] &&
                          ours.fractions()(x, y) == fixed_fraction.at<std::uint16_t>(y, x);
        differing += !same;
        if (!same && differing < 5) {
          ADD_FAILURE() << "at " << x << "," << y << " (" << map_x.at<float>(y, x) << ", "
                        << map_y.at<float>(y, x) << "): ours " << ours.xy()(2 * x, y) << ","
                        << ours.xy()(2 * x + 1, y) << " f " << ours.fractions()(x, y) << ", OpenCV "
                        << s[0] << "," << s[1] << " f " << fixed_fraction.at<std::uint16_t>(y, x);
        }
      }
    std::printf("float->fixed vs cv::convertMaps: %d of %d entries differ\n", differing,
                map_x.cols * map_x.rows);
    EXPECT_EQ(differing, 0);
  }

  // The map built from the float maps rectifies like cv::remap with convertMaps' result.
  cv::convertMaps(maps.left_x, maps.left_y, fixed_xy, fixed_fraction, CV_16SC2, false);
  const cv::Mat gray = read_gray("left01.jpg");
  cv::Mat expected;
  cv::remap(gray, expected, fixed_xy, fixed_fraction, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  Rectifier rectifier({.source_width = 640, .source_height = 480, .width = 640, .height = 480},
                      RemapMap::from_float(float_view(maps.left_x), float_view(maps.left_y)));
  const Agreement a = compare(expected, rectifier.rectify(test::view_of(gray)));
  EXPECT_EQ(a.differing, 0);
}

}  // namespace
}  // namespace epipole::vision

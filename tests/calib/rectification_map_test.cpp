// The map builder: its fixed-point rounding is vision::RemapMap's, bit for bit; its geometry
// inverts rectify_point (tests/reference/calibration_opencv_test.cpp compares with OpenCV).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "epipole/calib/rectification_map.hpp"
#include "epipole/core/fixed_point.hpp"
#include "epipole/vision/remap.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

TEST(CameraModel, UndistortInvertsDistort) {
  const StereoCalibration c = test::sample_calibration();
  for (const PinholeCamera& camera : {c.left.camera, c.right.camera}) {
    for (double y = -0.5; y <= 0.5; y += 0.05) {
      for (double x = -0.7; x <= 0.7; x += 0.05) {
        const Eigen::Vector2d ideal(x, y);
        const Eigen::Vector2d back = camera.undistort(camera.distort(ideal));
        EXPECT_LT((back - ideal).norm(), 1e-12) << x << ", " << y;
      }
    }
  }
  // Far outside the lens's domain the model folds over: no answer rather than a wrong one.
  const PinholeCamera strong{{500, 500, 320, 240}, {-0.9, 0, 0, 0, 0}};
  const Eigen::Vector2d far = strong.undistort({3.0, 3.0});
  EXPECT_TRUE(std::isnan(far.x())) << far.transpose();
}

TEST(RectificationMap, IdentityCalibrationGivesTheIdentityMap) {
  CameraCalibration camera;
  camera.camera.intrinsics = {500, 500, 31.5, 20.25};
  camera.projection << 500, 0, 31.5, 0, 0, 500, 20.25, 0, 0, 0, 1, 0;
  const FixedPointMap map = build_fixed_point_map(camera, 64, 40);
  ASSERT_EQ(map.width(), 64);
  ASSERT_EQ(map.height(), 40);
  ASSERT_EQ(map.xy.width(), 128);
  for (int v = 0; v < 40; ++v) {
    for (int u = 0; u < 64; ++u) {
      EXPECT_EQ(map.xy(2 * u, v), u);
      EXPECT_EQ(map.xy(2 * u + 1, v), v);
      EXPECT_EQ(map.fractions(u, v), 0);
    }
  }
}

// The shared rounding (core/fixed_point.hpp) against an independent statement of it: the
// nearest integer of v * 32 in the default rounding mode (ties to even), saturated to int32.
TEST(RectificationMap, FixedPointRoundingForSpecialValues) {
  std::vector<float> values = {0.0f,
                               -0.0f,
                               1.0f / 64,
                               3.0f / 64,
                               -1.0f / 64,
                               -3.0f / 64,
                               0.5f,
                               -0.5f,
                               639.984375f,
                               639.9921875f,
                               -1.0f,
                               -1.015625f,
                               1023.99f,
                               32767.0f,
                               32768.0f,
                               -32769.0f,
                               1e9f,
                               -1e9f,
                               3e38f,
                               -3e38f,
                               std::numeric_limits<float>::infinity(),
                               -std::numeric_limits<float>::infinity(),
                               std::numeric_limits<float>::quiet_NaN(),
                               std::numeric_limits<float>::denorm_min()};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> any(-2000.0f, 2000.0f);
  for (int i = 0; i < 100000; ++i) values.push_back(any(rng));
  for (int k = -4096; k <= 4096; ++k) values.push_back(static_cast<float>(k) / 64);  // ties
  for (const float v : values) {
    std::int16_t integer = 0;
    const int fraction = to_fixed_point(v, &integer);
    const double scaled = static_cast<double>(v) * 32;
    std::int64_t fixed = std::numeric_limits<std::int32_t>::min();
    if (!std::isnan(v)) {
      fixed = static_cast<std::int64_t>(
          std::clamp<double>(std::nearbyint(scaled), std::numeric_limits<std::int32_t>::min(),
                             std::numeric_limits<std::int32_t>::max()));
    }
    const std::int64_t whole = (fixed - (fixed & 31)) / 32;  // floor division
    ASSERT_EQ(fraction, fixed & 31) << v;
    ASSERT_EQ(integer, std::clamp<std::int64_t>(whole, -32768, 32767)) << v;
  }
}

// The documented promise: build_fixed_point_map == RemapMap::from_float(build_float_map).
TEST(RectificationMap, EqualsRemapMapFromFloatOfTheFloatMaps) {
  const StereoCalibration c = test::sample_calibration();
  for (const Side side : {Side::left, Side::right}) {
    Image<float> xs(c.width, c.height);
    Image<float> ys(c.width, c.height);
    build_float_map(camera_of(c, side), xs.view(), ys.view());
    const vision::RemapMap expected = vision::RemapMap::from_float(xs.view(), ys.view());
    const FixedPointMap map = build_fixed_point_map(c, side);
    ASSERT_EQ(map.width(), expected.width());
    ASSERT_EQ(map.height(), expected.height());
    long long differ = 0;
    for (int v = 0; v < c.height; ++v) {
      for (int u = 0; u < c.width; ++u) {
        differ += map.xy(2 * u, v) != expected.xy()(2 * u, v);
        differ += map.xy(2 * u + 1, v) != expected.xy()(2 * u + 1, v);
        differ += map.fractions(u, v) != expected.fractions()(u, v);
      }
    }
    EXPECT_EQ(differ, 0) << (side == Side::left ? "left" : "right");
  }
}

TEST(RectificationMap, RectifyPointInvertsTheMap) {
  const StereoCalibration c = test::sample_calibration();
  for (const Side side : {Side::left, Side::right}) {
    const CameraCalibration& camera = camera_of(c, side);
    double worst = 0;
    for (int v = 0; v < c.height; v += 7) {
      for (int u = 0; u < c.width; u += 7) {
        const Eigen::Vector2d source = source_of_rectified(camera, u, v);
        const Eigen::Vector2d back = rectify_point(camera, source);
        worst = std::max(worst, (back - Eigen::Vector2d(u, v)).norm());
      }
    }
    EXPECT_LT(worst, 1e-8);
  }
}

TEST(RectificationMap, BadSizes) {
  const StereoCalibration c = test::sample_calibration();
  EXPECT_THROW(build_fixed_point_map(c.left, 0, 480), Error);
  EXPECT_THROW(build_fixed_point_map(c.left, 40000, 480), Error);
  Image<float> xs(10, 10);
  Image<float> ys(10, 11);
  EXPECT_THROW(build_float_map(c.left, xs.view(), ys.view()), Error);
}

}  // namespace
}  // namespace epipole::calib

// The calibration health figure: exact statistics on known offsets, and a rig whose right
// camera turns by known small angles about its x axis after calibration.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "epipole/calib/health.hpp"
#include "epipole/calib/rectification_map.hpp"
#include "epipole/core/error.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

RectifiedMatch offset(float dy) {
  return {100, 50, 90, 50 + dy};
}

TEST(CalibrationHealth, Percentiles) {
  CalibrationHealth health(64);
  std::vector<RectifiedMatch> matches;
  for (int i = 1; i <= 10; ++i) matches.push_back(offset(static_cast<float>(i % 2 == 0 ? -i : i)));
  const HealthFigure f = health.measure(matches);
  EXPECT_EQ(f.matches, 10);
  EXPECT_NEAR(f.median_px, 5.5, 1e-6);  // |offsets| 1..10
  EXPECT_NEAR(f.p90_px, 9.1, 1e-6);     // position 0.9 * 9 = 8.1: 9 + 0.1 * (10 - 9)
  // Signed: sorted -10 -8 -6 -4 -2 1 3 5 7 9, median (-2 + 1) / 2 = -0.5.
  EXPECT_NEAR(f.median_signed_px, -0.5, 1e-6);

  const RectifiedMatch one = offset(-2.5f);
  const HealthFigure single = health.measure({&one, 1});
  EXPECT_EQ(single.matches, 1);
  EXPECT_FLOAT_EQ(static_cast<float>(single.median_px), 2.5f);
  EXPECT_FLOAT_EQ(static_cast<float>(single.p90_px), 2.5f);
  EXPECT_FLOAT_EQ(static_cast<float>(single.median_signed_px), -2.5f);
}

TEST(CalibrationHealth, NonFiniteMatchesAreSkippedAndNoneIsNaN) {
  CalibrationHealth health(4);
  const std::vector<RectifiedMatch> matches = {offset(1), offset(std::nanf("")), offset(3),
                                               offset(HUGE_VALF)};
  const HealthFigure f = health.measure(matches);
  EXPECT_EQ(f.matches, 2);
  EXPECT_NEAR(f.median_px, 2.0, 1e-6);
  const HealthFigure none = health.measure({});
  EXPECT_EQ(none.matches, 0);
  EXPECT_TRUE(std::isnan(none.median_px));
  EXPECT_TRUE(std::isnan(none.p90_px));
}

TEST(CalibrationHealth, Capacity) {
  EXPECT_THROW(CalibrationHealth(0), Error);
  CalibrationHealth health(2);
  const std::vector<RectifiedMatch> three(3, offset(1));
  EXPECT_THROW(health.measure(three), Error);
  EXPECT_EQ(health.working_set_bytes(), 16u);
}

// Matches of random scene points when the right camera has turned by `degrees` about its own
// x axis since the calibration `c` was made (true R = Rx(angle) R), rectified with `c`, with
// Gaussian noise of `noise` px on the detected (raw) positions.
std::vector<RectifiedMatch> drifted_matches(const StereoCalibration& c, double degrees,
                                            double noise, int count) {
  const double angle = degrees * std::numbers::pi / 180;
  const Eigen::Matrix3d true_r = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()) * c.R;
  const Eigen::Matrix3d new_k_inverse = c.left.projection.leftCols<3>().inverse();
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(40, c.width - 40.0);
  std::uniform_real_distribution<double> v(40, c.height - 40.0);
  std::uniform_real_distribution<double> depth(0.8, 5.0);
  std::normal_distribution<double> jitter(0, noise);
  std::vector<RectifiedMatch> matches;
  while (static_cast<int>(matches.size()) < count) {
    // A scene point seen at a random rectified left pixel, in the left camera's frame.
    const Eigen::Vector3d rectified = new_k_inverse * Eigen::Vector3d(u(rng), v(rng), 1);
    const Eigen::Vector3d left = c.left.rectification.transpose() * (rectified * depth(rng));
    const Eigen::Vector3d right = true_r * left + c.T;
    const Eigen::Vector2d raw_left = c.left.camera.project(left);
    const Eigen::Vector2d raw_right = c.right.camera.project(right);
    if (raw_right.x() < 0 || raw_right.x() >= c.width || raw_right.y() < 0 ||
        raw_right.y() >= c.height) {
      continue;
    }
    const Eigen::Vector2d noisy_left = raw_left + Eigen::Vector2d(jitter(rng), jitter(rng));
    const Eigen::Vector2d noisy_right = raw_right + Eigen::Vector2d(jitter(rng), jitter(rng));
    const Eigen::Vector2d l = rectify_point(c.left, noisy_left);
    const Eigen::Vector2d r = rectify_point(c.right, noisy_right);
    matches.push_back({static_cast<float>(l.x()), static_cast<float>(l.y()),
                       static_cast<float>(r.x()), static_cast<float>(r.y())});
  }
  return matches;
}

TEST(CalibrationHealth, FollowsAKnownRotationOfTheRig) {
  const StereoCalibration c = test::sample_calibration();
  const double f = c.left.projection(1, 1);
  constexpr int kMatches = 500;
  CalibrationHealth health(kMatches);
  double previous_median = -1;
  double previous_p90 = -1;
  for (const double degrees : {0.0, 0.05, 0.1, 0.2}) {
    SCOPED_TRACE(degrees);
    const std::vector<RectifiedMatch> matches = drifted_matches(c, degrees, 0.05, kMatches);
    const HealthFigure h = health.measure(matches);
    // A turn by a about the x axis moves the rectified right image by about f tan(a) rows.
    const double predicted = f * std::tan(degrees * std::numbers::pi / 180);
    std::printf(
        "rotation %.2f deg: predicted %.3f px, median %.3f px, p90 %.3f px, "
        "signed median %.3f px\n",
        degrees, predicted, h.median_px, h.p90_px, h.median_signed_px);
    EXPECT_EQ(h.matches, kMatches);
    if (degrees == 0) {
      EXPECT_LT(h.median_px, 0.06);  // noise only: 0.05 px on each of four coordinates
      EXPECT_LT(h.p90_px, 0.15);
    } else {
      EXPECT_NEAR(std::abs(h.median_signed_px), predicted, 0.1 * predicted + 0.02);
      EXPECT_NEAR(h.median_px, predicted, 0.1 * predicted + 0.02);
      EXPECT_GT(h.p90_px, h.median_px);
      EXPECT_LT(h.p90_px, 1.5 * predicted + 0.1);
    }
    EXPECT_GT(h.median_px, previous_median);
    EXPECT_GT(h.p90_px, previous_p90);
    previous_median = h.median_px;
    previous_p90 = h.p90_px;
  }
}

}  // namespace
}  // namespace epipole::calib

// The drift estimator on matches made from 3-D points seen by a rig whose right camera turned
// (a real calibration's R2, so the rectified frame and the camera's differ): the turns it
// corrects are found within a hundredth of a degree, through noise and a fifth of wrong matches;
// an undrifted rig's estimate is nil; too few pairs or matches are no estimate.
#include "epipole/calib/drift_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "epipole/calib/camera_turn.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

// A pair's matches: points 1..12 m away in view of both cameras, the right camera turned by
// `turn` since the calibration; rows with Gaussian noise (pixels), `wrong` of them moved by up to
// 4 pixels.
std::vector<RectifiedMatch> drifted_matches(const StereoCalibration& rig, const CameraTurn& turn,
                                            int count, double noise, double wrong,
                                            std::mt19937& rng) {
  const Eigen::Matrix3d r2 = rig.right.rectification;
  // What the old rectification makes of the turned camera's rays: M = R2 D^T R2^T.
  const Eigen::Matrix3d m = r2 * turn_rotation(turn).transpose() * r2.transpose();
  const double fx = rig.left.projection(0, 0), fy = rig.left.projection(1, 1);
  const double cx = rig.left.projection(0, 2), cy = rig.left.projection(1, 2);
  const double b = -rig.right.projection(0, 3) / rig.right.projection(0, 0);
  std::uniform_real_distribution<double> u(0, rig.width), v(0, rig.height), depth(1, 12),
      unit(0, 1), off(-4, 4);
  std::normal_distribution<double> n(0, noise);
  std::vector<RectifiedMatch> matches;
  while (static_cast<int>(matches.size()) < count) {
    const double z = depth(rng);
    const Eigen::Vector3d x((u(rng) - cx) / fx * z, (v(rng) - cy) / fy * z, z);
    const Eigen::Vector3d r = m * (x - Eigen::Vector3d(b, 0, 0));
    if (r.z() <= 0) continue;
    RectifiedMatch match;
    match.left_x = static_cast<float>(fx * x.x() / z + cx);
    match.left_y = static_cast<float>(fy * x.y() / z + cy);
    match.right_x = static_cast<float>(fx * r.x() / r.z() + rig.right.projection(0, 2));
    match.right_y = static_cast<float>(fy * r.y() / r.z() + rig.right.projection(1, 2) + n(rng));
    const double xr = match.right_x, yr = match.right_y;
    if (xr < 0 || xr >= rig.width || yr < 0 || yr >= rig.height) {
      continue;
    }
    if (unit(rng) < wrong) match.right_y += static_cast<float>(off(rng));
    matches.push_back(match);
  }
  return matches;
}

DriftEstimate run(const CameraTurn& turn, int pairs, unsigned seed, double wrong = 0.2) {
  const StereoCalibration rig = test::sample_calibration();
  DriftEstimator estimator(rig, {});
  std::mt19937 rng(seed);
  for (int i = 0; i < pairs; ++i) {
    const auto matches = drifted_matches(rig, turn, 300, 0.08, wrong, rng);
    estimator.add_pair(matches);
  }
  return estimator.estimate();
}

TEST(DriftEstimator, FindsTheTurnsItCorrects) {
  const double hundredth = radians(0.01);
  unsigned seed = 1;
  for (const CameraTurn turn :
       {CameraTurn{radians(0.3), radians(0.2), 0}, CameraTurn{radians(-0.8), radians(0.05), 0},
        CameraTurn{radians(0.02), radians(-1.0), 0}, CameraTurn{radians(1.0), radians(1.0), 0},
        CameraTurn{radians(-0.15), radians(-0.4), radians(0.3)}}) {
    const DriftEstimate e = run(turn, 30, seed++);
    ASSERT_TRUE(e.valid);
    EXPECT_EQ(e.pairs, 30);
    EXPECT_NEAR(e.pitch, turn.pitch, hundredth) << degrees(turn.pitch) << "," << degrees(turn.roll);
    EXPECT_NEAR(e.roll, turn.roll, hundredth) << degrees(turn.pitch) << "," << degrees(turn.roll);
    EXPECT_GT(e.pitch_sigma, 0);
    EXPECT_LT(e.pitch_sigma, hundredth / 2);
    EXPECT_LT(e.roll_sigma, hundredth / 2);
    // Yaw is not estimated: its keystone (x y, second order) stays in the rows.
    EXPECT_LT(e.median_corrected_px, turn.yaw == 0 ? 0.1 : 0.2);
  }
  // 0.3 degrees of pitch on f = 519 pixels: rows about 2.7 pixels apart, then about none.
  const DriftEstimate e = run({radians(0.3), radians(0.2), 0}, 30, 99);
  EXPECT_GT(e.median_offset_px, 2.0);
  EXPECT_LT(e.median_corrected_px, 0.1);
}

TEST(DriftEstimator, AnUndriftedRigIsNotTurned) {
  const DriftEstimate e = run({}, 30, 7);
  ASSERT_TRUE(e.valid);
  EXPECT_LT(std::abs(e.pitch), 3 * e.pitch_sigma + radians(0.002));
  EXPECT_LT(std::abs(e.roll), 3 * e.roll_sigma + radians(0.002));
  EXPECT_LT(e.median_offset_px, 0.1);
}

TEST(DriftEstimator, TooLittleIsNoEstimate) {
  EXPECT_FALSE(run({radians(0.3), 0, 0}, 2, 3).valid) << "two pairs";
  const StereoCalibration rig = test::sample_calibration();
  DriftEstimator estimator(rig, {});
  std::mt19937 rng(5);
  for (int i = 0; i < 10; ++i) {
    estimator.add_pair(drifted_matches(rig, {radians(0.3), 0, 0}, 8, 0.08, 0, rng));
  }
  EXPECT_FALSE(estimator.estimate().valid) << "8 matches a pair, fewer than min_matches";
  EXPECT_EQ(estimator.estimate().pairs, 0);
  // The window forgotten.
  for (int i = 0; i < 5; ++i) {
    estimator.add_pair(drifted_matches(rig, {radians(0.3), 0, 0}, 200, 0.08, 0, rng));
  }
  EXPECT_TRUE(estimator.estimate().valid);
  estimator.clear();
  EXPECT_EQ(estimator.estimate().pairs, 0);
  // Bad configurations and too many matches.
  EXPECT_THROW(DriftEstimator(rig, {.window_pairs = 2}), Error);
  EXPECT_THROW(DriftEstimator(rig, {.pair_matches = 4}), Error);
  DriftEstimator small(rig, {.max_matches = 10});
  EXPECT_THROW(small.add_pair(drifted_matches(rig, {}, 11, 0.1, 0, rng)), Error);
}

}  // namespace
}  // namespace epipole::calib

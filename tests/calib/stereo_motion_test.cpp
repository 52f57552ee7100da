// The rig's motion between two pairs (calib/stereo_motion.hpp) on synthetic matches with exact
// truth: noise, wrong matches, matches the right camera missed, a wrong prediction, too little
// to go on.
#include "epipole/calib/stereo_motion.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "epipole/core/error.hpp"
#include "motion_scenes.hpp"

namespace epipole::calib {
namespace {

RigidMotion walking_step(SplitMix64& random) {
  // 1 m/s at 15 pairs a second, turning up to 90 degrees a second.
  return {test::random_turn(random, 6 * random.uniform()),
          Eigen::Vector3d(0.05 * test::gaussian(random), 0.02 * test::gaussian(random),
                          -0.067 + 0.01 * test::gaussian(random))};
}

TEST(StereoMotion, ExactMatchesGiveTheExactMotion) {
  SplitMix64 random(1);
  StereoMotionEstimator estimator(test::motion_rig(), {});
  for (int trial = 0; trial < 20; ++trial) {
    const test::MotionScene s = test::motion_scene(random, walking_step(random), 200, 0, 0);
    const StereoMotion m = estimator.estimate(s.matches, RigidMotion{});
    ASSERT_TRUE(m.valid);
    EXPECT_EQ(m.inliers, 200);
    EXPECT_LT(test::rotation_error_deg(m.motion.rotation, s.truth.rotation), 1e-7);
    EXPECT_LT((m.motion.translation - s.truth.translation).norm(), 1e-8);
    EXPECT_LT(m.rms_px, 1e-6);
  }
}

// Half a pixel of noise and 30 % of the matches wrong, predicted by no motion at all: within
// 0.05 degrees and 1 cm, the wrong matches left out, the right ones kept.
TEST(StereoMotion, NoisyMatchesWithOutliers) {
  SplitMix64 random(2);
  StereoMotionEstimator estimator(test::motion_rig(), {});
  double worst_deg = 0, worst_m = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const test::MotionScene s = test::motion_scene(random, walking_step(random), 400, 0.5, 0.3);
    const StereoMotion m = estimator.estimate(s.matches, RigidMotion{});
    ASSERT_TRUE(m.valid) << trial;
    worst_deg = std::max(worst_deg, test::rotation_error_deg(m.motion.rotation, s.truth.rotation));
    worst_m = std::max(worst_m, (m.motion.translation - s.truth.translation).norm());
    int right = 0, kept = 0, wrong_kept = 0;
    for (std::size_t i = 0; i < s.matches.size(); ++i) {
      right += s.wrong[i] ? 0 : 1;
      kept += estimator.inliers()[i] != 0 && !s.wrong[i] ? 1 : 0;
      wrong_kept += estimator.inliers()[i] != 0 && s.wrong[i] ? 1 : 0;
    }
    // A 1 px gate on 0.5 px of noise keeps a match with probability 1 - e^-2 (its left image's
    // 2-D error) times 0.95 (its right image's, where seen): 82 %.
    EXPECT_GE(kept, right * 75 / 100);
    EXPECT_LE(wrong_kept, 3);
  }
  std::printf("30 steps, 0.5 px, 30 %% wrong: worst %.4f deg, %.2f mm\n", worst_deg,
              worst_m * 1000);
  EXPECT_LT(worst_deg, 0.05);
  EXPECT_LT(worst_m, 0.01);
}

// The covariance says how far off the motion is: the normalised squared error of 6 dimensions
// averages 6 over many steps (a consistent estimate); between 3 and 12 here.
TEST(StereoMotion, TheCovarianceMatchesTheErrors) {
  SplitMix64 random(3);
  StereoMotionEstimator estimator(test::motion_rig(), {});
  double sum = 0;
  const int steps = 60;
  for (int trial = 0; trial < steps; ++trial) {
    const test::MotionScene s = test::motion_scene(random, walking_step(random), 300, 0.3, 0.1);
    const StereoMotion m = estimator.estimate(s.matches, RigidMotion{});
    ASSERT_TRUE(m.valid);
    // The error as the perturbation d of truth = exp(d) estimate.
    const Eigen::Matrix3d turn = s.truth.rotation * m.motion.rotation.transpose();
    const Eigen::AngleAxisd aa(turn);
    Eigen::Matrix<double, 6, 1> d;
    d.head<3>() = aa.angle() * aa.axis();
    d.tail<3>() = s.truth.translation - turn * m.motion.translation;
    sum += d.dot(m.covariance.ldlt().solve(d));
  }
  const double mean = sum / steps;
  std::printf("mean normalised squared error %.2f (6 expected)\n", mean);
  EXPECT_GT(mean, 3);
  EXPECT_LT(mean, 12);
}

TEST(StereoMotion, TooFewOrNoConsistentMatchesGiveNoMotion) {
  SplitMix64 random(4);
  StereoMotionEstimator estimator(test::motion_rig(), {});
  const test::MotionScene few = test::motion_scene(random, walking_step(random), 12, 0.3, 0);
  EXPECT_FALSE(estimator.estimate(few.matches, RigidMotion{}).valid) << "under min_inliers";
  const test::MotionScene noise = test::motion_scene(random, walking_step(random), 300, 0.3, 1.0);
  const StereoMotion lost = estimator.estimate(noise.matches, RigidMotion{});
  EXPECT_FALSE(lost.valid) << lost.inliers << " inliers among random matches";
  EXPECT_EQ(lost.samples, estimator.config().iterations) << "the whole budget, no more";
  EXPECT_FALSE(estimator.estimate({}, RigidMotion{}).valid);
}

TEST(StereoMotion, ARightPredictionNeedsFewSamples) {
  SplitMix64 random(5);
  StereoMotionEstimator estimator(test::motion_rig(), {});
  const test::MotionScene s = test::motion_scene(random, walking_step(random), 300, 0.3, 0.05);
  const StereoMotion m = estimator.estimate(s.matches, s.truth);
  ASSERT_TRUE(m.valid);
  EXPECT_LT(m.samples, 10) << "most matches agree with the prediction already";
}

TEST(StereoMotion, SettingsOutOfRangeAndTooManyMatchesAreErrors) {
  StereoMotionConfig c;
  c.iterations = 0;
  EXPECT_THROW(StereoMotionEstimator(test::motion_rig(), c), Error);
  c = {};
  c.inlier_px = 0;
  EXPECT_THROW(StereoMotionEstimator(test::motion_rig(), c), Error);
  RectifiedStereoCameras no_baseline = test::motion_rig();
  no_baseline.baseline = 0;
  EXPECT_THROW(StereoMotionEstimator(no_baseline, {}), Error);
  c = {};
  c.max_matches = 10;
  StereoMotionEstimator small(test::motion_rig(), c);
  SplitMix64 random(6);
  const test::MotionScene s = test::motion_scene(random, RigidMotion{}, 11, 0, 0);
  EXPECT_THROW(small.estimate(s.matches, RigidMotion{}), Error);
}

}  // namespace
}  // namespace epipole::calib

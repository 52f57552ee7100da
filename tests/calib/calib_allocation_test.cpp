// The per-frame calls of calib allocate nothing: triangulation and the health figure.
#include <gtest/gtest.h>

#include <vector>

#include "allocation_counter.hpp"
#include "epipole/calib/health.hpp"
#include "epipole/calib/stereo_motion.hpp"
#include "epipole/calib/triangulation.hpp"
#include "motion_scenes.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

TEST(CalibAllocations, TriangulationAllocatesNothingPerFrame) {
  Triangulator t(test::sample_calibration());
  Image<float> disparity(640, 480);
  Image<std::uint16_t> disparity16(640, 480);
  Image<Point3f> points(640, 480);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      disparity(u, v) = static_cast<float>((u * 7 + v) % 64);
      disparity16(u, v) = static_cast<std::uint16_t>((u * 5 + v) % 1024);
    }
  }
  float sink = 0;
  const test::AllocationCounter counter;
  for (int frame = 0; frame < 100; ++frame) {
    sink += t.reproject(disparity.view())(320, 240).z;
    sink += t.reproject(disparity16.view())(100, 200).z;
    t.reproject(disparity.view(), points.view());
    sink += static_cast<float>(t.depth(frame + 1.0));
  }
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_NE(sink, 0.0f);
}

TEST(CalibAllocations, HealthFigureAllocatesNothingPerFrame) {
  CalibrationHealth health(2000);
  std::vector<RectifiedMatch> matches;
  for (int i = 0; i < 2000; ++i) {
    const auto x = static_cast<float>(i % 640);
    const auto y = static_cast<float>(i % 480);
    matches.push_back({x, y, x - 10, y + 0.01f * static_cast<float>(i % 37)});
  }
  double sink = 0;
  const test::AllocationCounter counter;
  for (int frame = 0; frame < 100; ++frame) {
    const std::size_t n = 500 + static_cast<std::size_t>(frame) * 15;
    sink += health.measure({matches.data(), n}).p90_px;
  }
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_GT(sink, 0.0);
}

TEST(CalibAllocations, StereoMotionAllocatesNothingPerPair) {
  StereoMotionEstimator estimator(test::motion_rig(), {});
  SplitMix64 random(9);
  std::vector<test::MotionScene> scenes;
  for (int i = 0; i < 10; ++i) {
    const RigidMotion step{test::random_turn(random, 3), Eigen::Vector3d(0.02, 0, -0.07)};
    scenes.push_back(test::motion_scene(random, step, 500, 0.4, 0.25));
  }
  int valid = 0;
  const test::AllocationCounter counter;
  for (const test::MotionScene& s : scenes) {
    valid += estimator.estimate(s.matches, RigidMotion{}).valid ? 1 : 0;
  }
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_EQ(valid, 10);
}

}  // namespace
}  // namespace epipole::calib

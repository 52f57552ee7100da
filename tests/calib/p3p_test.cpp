// Perspective-three-point, the quartic it solves and absolute orientation (calib/p3p.hpp), on
// random poses with exact truth.
#include "epipole/calib/p3p.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "motion_scenes.hpp"

namespace epipole::calib {
namespace {

TEST(Quartic, RealRootsOfKnownPolynomials) {
  // (x - 1)(x - 2)(x + 3)(x - 0.5) = x^4 - 0.5 x^3 - 7 x^2 + 9.5 x - 3
  std::array<double, 4> roots{};
  ASSERT_EQ(real_quartic_roots({-3, 9.5, -7, -0.5, 1}, roots), 4);
  std::sort(roots.begin(), roots.end());
  EXPECT_NEAR(roots[0], -3, 1e-12);
  EXPECT_NEAR(roots[1], 0.5, 1e-12);
  EXPECT_NEAR(roots[2], 1, 1e-12);
  EXPECT_NEAR(roots[3], 2, 1e-12);
  // 2 (x^2 + 1)(x - 2)(x - 3) = 2 x^4 - 10 x^3 + 14 x^2 - 10 x + 12: two real roots.
  ASSERT_EQ(real_quartic_roots({12, -10, 14, -10, 2}, roots), 2);
  std::sort(roots.begin(), roots.begin() + 2);
  EXPECT_NEAR(roots[0], 2, 1e-12);
  EXPECT_NEAR(roots[1], 3, 1e-12);
  EXPECT_EQ(real_quartic_roots({1, 0, 2, 0, 1}, roots), 0) << "(x^2 + 1)^2";
}

TEST(AlignPoints, RecoversARigidMotionAndRefusesAReflection) {
  SplitMix64 random(7);
  const RigidMotion truth{test::random_turn(random, 70), Eigen::Vector3d(0.3, -2, 5)};
  std::vector<Eigen::Vector3d> from, to;
  for (int i = 0; i < 10; ++i) {
    from.emplace_back(random.uniform(), random.uniform(), random.uniform());
    to.push_back(truth.apply(from.back()));
  }
  const RigidMotion m = align_points(from.data(), to.data(), 10);
  EXPECT_LT(test::rotation_error_deg(m.rotation, truth.rotation), 1e-9);
  EXPECT_LT((m.translation - truth.translation).norm(), 1e-9);
  // Mirrored targets: the best rotation, never a reflection.
  for (Eigen::Vector3d& p : to) p.x() = -p.x();
  EXPECT_NEAR(align_points(from.data(), to.data(), 10).rotation.determinant(), 1, 1e-12);
}

// Random poses (any rotation, the points 0.5..20 m before the camera): the truth is among the
// solutions, to a millionth of a degree and of the scene's size.
TEST(P3P, TheTruePoseIsAmongTheSolutions) {
  SplitMix64 random(11);
  int found = 0, trials = 0;
  for (; trials < 2000; ++trials) {
    const RigidMotion truth{
        test::random_turn(random, 180 * random.uniform()),
        Eigen::Vector3d(test::gaussian(random), test::gaussian(random), test::gaussian(random))};
    std::array<Eigen::Vector3d, 3> points, bearings;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d seen((random.uniform() - 0.5) * 10, (random.uniform() - 0.5) * 8,
                                 0.5 + 19.5 * random.uniform());
      bearings[static_cast<std::size_t>(i)] = seen.normalized();
      points[static_cast<std::size_t>(i)] = truth.inverse().apply(seen);
    }
    std::array<RigidMotion, 4> poses;
    const int n = solve_p3p(points, bearings, poses);
    for (int k = 0; k < n; ++k) {
      const RigidMotion& p = poses[static_cast<std::size_t>(k)];
      if (test::rotation_error_deg(p.rotation, truth.rotation) < 1e-6 &&
          (p.translation - truth.translation).norm() < 1e-6 * 20) {
        ++found;
        break;
      }
    }
  }
  // A configuration on the danger cylinder has a double root that rounding can lose: rare.
  EXPECT_GE(found, trials * 995 / 1000) << found << " of " << trials;
}

TEST(P3P, EverySolutionSeesThePointsAlongTheirRays) {
  SplitMix64 random(12);
  for (int trial = 0; trial < 200; ++trial) {
    const RigidMotion truth{test::random_turn(random, 40), Eigen::Vector3d(0.2, 0.1, -0.4)};
    std::array<Eigen::Vector3d, 3> points, bearings;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d seen((random.uniform() - 0.5) * 6, (random.uniform() - 0.5) * 4,
                                 1 + 9 * random.uniform());
      bearings[static_cast<std::size_t>(i)] = seen.normalized();
      points[static_cast<std::size_t>(i)] = truth.inverse().apply(seen);
    }
    std::array<RigidMotion, 4> poses;
    const int n = solve_p3p(points, bearings, poses);
    ASSERT_GE(n, 1);
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3d x =
            poses[static_cast<std::size_t>(k)].apply(points[static_cast<std::size_t>(i)]);
        EXPECT_GT(x.z(), 0);
        EXPECT_NEAR(x.normalized().dot(bearings[static_cast<std::size_t>(i)]), 1, 1e-9);
      }
    }
  }
}

TEST(P3P, CollinearOrCoincidentPointsHaveNoPose) {
  std::array<RigidMotion, 4> poses;
  const std::array<Eigen::Vector3d, 3> rays = {Eigen::Vector3d(0, 0, 1),
                                               Eigen::Vector3d(0.1, 0, 1).normalized(),
                                               Eigen::Vector3d(0, 0.1, 1).normalized()};
  EXPECT_EQ(
      solve_p3p({Eigen::Vector3d(0, 0, 5), Eigen::Vector3d(1, 0, 5), Eigen::Vector3d(2, 0, 5)},
                rays, poses),
      0);
  EXPECT_EQ(
      solve_p3p({Eigen::Vector3d(0, 0, 5), Eigen::Vector3d(0, 0, 5), Eigen::Vector3d(2, 0, 5)},
                rays, poses),
      0);
}

}  // namespace
}  // namespace epipole::calib

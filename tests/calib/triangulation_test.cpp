// Triangulation with Q on known geometry (tests/reference/ compares with reprojectImageTo3D).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/error.hpp"
#include "sample_calibration.hpp"

namespace epipole::calib {
namespace {

TEST(Triangulation, RecoversPointsSeenByBothRectifiedCameras) {
  const StereoCalibration c = test::sample_calibration();
  const Triangulator t(c);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> lateral(-1.0, 1.0);
  std::uniform_real_distribution<double> depth(0.3, 20.0);
  for (int i = 0; i < 1000; ++i) {
    // A point in the rectified left frame, seen by both rectified cameras.
    const Eigen::Vector3d p(lateral(rng), lateral(rng), depth(rng));
    const Eigen::Vector3d l = c.left.projection * p.homogeneous();
    const Eigen::Vector3d r = c.right.projection * p.homogeneous();
    const double ul = l.x() / l.z();
    const double vl = l.y() / l.z();
    const double ur = r.x() / r.z();
    ASSERT_NEAR(vl, r.y() / r.z(), 1e-9);  // same row
    const double d = ul - ur;
    const Eigen::Vector3d back = t.point(ul, vl, d);
    EXPECT_LT((back - p).norm(), 1e-9 * p.norm()) << p.transpose();
    EXPECT_NEAR(t.depth(d), p.z(), 1e-9 * p.z());
  }
  // Z = f B / d: the baseline is |T|'s rectified x, 0.0834 m, f 518.86 px.
  const double fb = c.left.projection(0, 0) * -c.right.projection(0, 3) / c.right.projection(0, 0);
  EXPECT_NEAR(t.depth(10.0), fb / 10.0, 1e-12);
}

TEST(Triangulation, DisparitiesWithoutAPointAreNaN) {
  const Triangulator t(test::sample_calibration());
  for (const double d : {0.0, -1.0, std::nan(""), HUGE_VAL, -HUGE_VAL}) {
    EXPECT_TRUE(std::isnan(t.depth(d))) << d;
    EXPECT_TRUE(std::isnan(t.point(100, 100, d).z())) << d;
  }
  Image<float> disparity(640, 480);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) disparity(u, v) = (u + v) % 3 == 0 ? 0.0f : 20.0f;
  }
  Triangulator owned(test::sample_calibration());
  const ImageView<const Point3f> points = owned.reproject(disparity.view());
  for (int v = 0; v < 480; v += 13) {
    for (int u = 0; u < 640; u += 11) {
      if ((u + v) % 3 == 0) {
        EXPECT_TRUE(std::isnan(points(u, v).z));
      } else {
        EXPECT_FLOAT_EQ(points(u, v).z, static_cast<float>(t.depth(20.0)));
      }
    }
  }
}

TEST(Triangulation, FixedPointDisparitiesAgreeWithFloat) {
  Triangulator t(test::sample_calibration());
  Image<std::uint16_t> d16(640, 480);
  Image<float> d(640, 480);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> any(0, 64 * 16);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      d16(u, v) = static_cast<std::uint16_t>(any(rng));
      d(u, v) = static_cast<float>(d16(u, v)) / 16;
    }
  }
  Image<Point3f> from_float(640, 480);
  t.reproject(d.view(), from_float.view());
  const ImageView<const Point3f> from_fixed = t.reproject(d16.view());
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const Point3f a = from_fixed(u, v);
      const Point3f b = from_float(u, v);
      if (d16(u, v) == 0) {
        ASSERT_TRUE(std::isnan(a.z));
      } else {
        ASSERT_EQ(a.x, b.x);
        ASSERT_EQ(a.y, b.y);
        ASSERT_EQ(a.z, b.z);
      }
    }
  }
}

TEST(Triangulation, BadInput) {
  const StereoCalibration c = test::sample_calibration();
  EXPECT_THROW(Triangulator(Eigen::Matrix4d::Identity(), 640, 480), Error);  // Q(3,2) = 0
  Eigen::Matrix4d q = c.Q;
  q(0, 0) = std::nan("");
  EXPECT_THROW(Triangulator(q, 640, 480), Error);
  EXPECT_THROW(Triangulator(c.Q, 0, 480), Error);
  Triangulator t(c);
  Image<float> small(320, 240);
  EXPECT_THROW(t.reproject(small.view()), Error);
  Image<float> d(640, 480);
  Image<Point3f> wrong(640, 479);
  EXPECT_THROW(t.reproject(d.view(), wrong.view()), Error);
}

}  // namespace
}  // namespace epipole::calib

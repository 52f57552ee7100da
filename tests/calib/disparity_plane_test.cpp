// Planes of disparity space in metres through Q: a plane's disparities, made from its pixels'
// depths by the projections, give back the plane, its pitch and roll, and which points stand
// clear of it.
#include "epipole/calib/disparity_plane.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

namespace epipole::calib {
namespace {

// A rectified pair's Q as cv::stereoRectify makes it, with the principal points apart
// (cx - cx' = 10 px) so that Q's disparity offset is exercised.
constexpr double kF = 500, kCx = 320, kCy = 240, kCxRight = 310, kTx = -0.1;
Eigen::Matrix4d rig_q() {
  Eigen::Matrix4d q = Eigen::Matrix4d::Zero();
  q(0, 0) = q(1, 1) = 1;
  q(0, 3) = -kCx;
  q(1, 3) = -kCy;
  q(2, 3) = kF;
  q(3, 2) = -1 / kTx;
  q(3, 3) = (kCx - kCxRight) / kTx;
  return q;
}

double radians(double deg) {
  return deg * std::numbers::pi / 180;
}

// The ground's downward normal for a camera pitched down and rolled right side down.
Eigen::Vector3d ground_normal(double pitch_deg, double roll_deg) {
  const double p = radians(pitch_deg), r = radians(roll_deg);
  return {std::sin(r) * std::cos(p), std::cos(r) * std::cos(p), std::sin(p)};
}

// The disparity of the plane n . X = h at a pixel, by projection.
double disparity_at(const Eigen::Vector3d& n, double h, double u, double v) {
  const Eigen::Vector3d ray((u - kCx) / kF, (v - kCy) / kF, 1);
  const double z = h / n.dot(ray);
  return -kF * kTx / z + (kCx - kCxRight);
}

// a, b, c through three of the plane's pixels.
Eigen::Vector3d disparity_plane(const Eigen::Vector3d& n, double h) {
  Eigen::Matrix3d m;
  Eigen::Vector3d d;
  const double pixels[3][2] = {{100, 400}, {500, 420}, {300, 300}};
  for (int i = 0; i < 3; ++i) {
    m.row(i) << pixels[i][0], pixels[i][1], 1;
    d(i) = disparity_at(n, h, pixels[i][0], pixels[i][1]);
  }
  return m.lu().solve(d);
}

TEST(DisparityPlane, GivesBackTheGroundOfAnyRig) {
  for (const double pitch : {-20.0, 0.0, 10.0, 35.0}) {
    for (const double roll : {-25.0, 0.0, 5.0}) {
      for (const double h : {0.1, 0.5, 2.5}) {
        const Eigen::Vector3d n = ground_normal(pitch, roll);
        const Eigen::Vector3d abc = disparity_plane(n, h);
        const auto plane = metric_plane(rig_q(), abc(0), abc(1), abc(2));
        ASSERT_TRUE(plane.has_value());
        EXPECT_NEAR(plane->distance, h, 1e-9 * h);
        EXPECT_NEAR((plane->normal - n).norm(), 0, 1e-9);
        EXPECT_NEAR(pitch_deg(*plane), pitch, 1e-7);
        EXPECT_NEAR(roll_deg(*plane), roll, 1e-7);
      }
    }
  }
}

TEST(DisparityPlane, TellsWhatStandsClearOfTheGround) {
  const Eigen::Vector3d n = ground_normal(12, -7);
  const double h = 0.6, clearance = 0.1;
  const Eigen::Vector3d abc = disparity_plane(n, h);
  const auto plane = metric_plane(rig_q(), abc(0), abc(1), abc(2));
  ASSERT_TRUE(plane.has_value());
  const Eigen::Vector4d form = clearance_form(rig_q(), *plane, clearance);
  // Points straight above ground points, at heights either side of the clearance.
  for (const double u : {50.0, 320.0, 600.0}) {
    for (const double v : {300.0, 420.0}) {
      const Eigen::Vector3d ray((u - kCx) / kF, (v - kCy) / kF, 1);
      const Eigen::Vector3d on_ground = ray * (h / n.dot(ray));
      for (const double height : {0.0, 0.05, 0.09, 0.11, 0.3}) {
        const Eigen::Vector3d point = on_ground - n * height;
        const Eigen::Vector4d pixel(kF * point.x() / point.z() + kCx,
                                    kF * point.y() / point.z() + kCy,
                                    -kF * kTx / point.z() + (kCx - kCxRight), 1);
        EXPECT_EQ(form.dot(pixel) >= 0, height >= clearance)
            << "u " << u << " v " << v << " height " << height;
      }
    }
  }
}

TEST(DisparityPlane, NoPlaneThroughTheCameraOrWithoutQ) {
  EXPECT_FALSE(metric_plane(Eigen::Matrix4d::Zero(), 0, 0.1, 1).has_value());
  // d = -f Tx / Z + offset for every pixel of a plane through the centre: Z infinite nowhere;
  // the plane a = b = 0, c = offset is the plane at infinity (W = 0): no finite plane.
  EXPECT_FALSE(metric_plane(rig_q(), 0, 0, kCx - kCxRight).has_value());
}

}  // namespace
}  // namespace epipole::calib

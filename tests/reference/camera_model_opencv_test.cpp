// The radial-tangential camera model against cv::projectPoints.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <random>

#include "epipole/calib/camera_model.hpp"
#include "epipole/core/error.hpp"

namespace epipole::calib {
namespace {

TEST(CameraModelVsOpenCV, ProjectsLikeProjectPoints) {
  const PinholeCamera camera{{532.8, 531.2, 342.5, 233.9}, {-0.28, 0.07, 0.0012, -0.0009, 0.11}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> lateral(-1.0, 1.0), depth(1.5, 6.0);
  std::vector<cv::Point3d> points;
  for (int i = 0; i < 500; ++i) points.emplace_back(lateral(rng), lateral(rng), depth(rng));

  const cv::Matx33d K(532.8, 0, 342.5, 0, 531.2, 233.9, 0, 0, 1);
  const std::vector<double> dist{-0.28, 0.07, 0.0012, -0.0009, 0.11};
  std::vector<cv::Point2d> expected;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, expected);

  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d p = camera.project({points[i].x, points[i].y, points[i].z});
    EXPECT_NEAR(p.x(), expected[i].x, 1e-9) << i;
    EXPECT_NEAR(p.y(), expected[i].y, 1e-9) << i;
  }
}

TEST(CameraModel, RejectsPointsBehindTheCamera) {
  const PinholeCamera camera{{500, 500, 320, 240}, {}};
  EXPECT_THROW(camera.project({0, 0, 0}), Error);
  EXPECT_THROW(camera.project({1, 1, -2}), Error);
}

}  // namespace
}  // namespace epipole::calib

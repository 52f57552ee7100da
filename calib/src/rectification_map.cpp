#include "epipole/calib/rectification_map.hpp"

#include "epipole/core/fixed_point.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "epipole/core/error.hpp"

namespace epipole::calib {

namespace {

// (P[:, 0:3] R)^-1: rectified pixel (u, v, 1) to a ray in the camera's own frame.
Eigen::Matrix3d rectified_to_ray(const CameraCalibration& camera) {
  const Eigen::Matrix3d new_k = camera.projection.leftCols<3>();
  return (new_k * camera.rectification).inverse();
}

Eigen::Vector2d source_from_ray(const PinholeCamera& camera, const Eigen::Vector3d& ray) {
  // As OpenCV: no test of the sign of the depth (a ray behind the camera maps somewhere far).
  const double w = 1 / ray.z();
  const Eigen::Vector2d d = camera.distort({ray.x() * w, ray.y() * w});
  const Intrinsics& k = camera.intrinsics;
  return {k.fx * d.x() + k.cx, k.fy * d.y() + k.cy};
}

}  // namespace

Eigen::Vector2d source_of_rectified(const CameraCalibration& camera, double u, double v) {
  return source_from_ray(camera.camera, rectified_to_ray(camera) * Eigen::Vector3d(u, v, 1));
}

Eigen::Vector2d rectify_point(const CameraCalibration& camera, const Eigen::Vector2d& pixel) {
  const Eigen::Vector2d n = camera.camera.normalize(pixel);
  const Eigen::Vector3d r = camera.rectification * Eigen::Vector3d(n.x(), n.y(), 1);
  const Eigen::Vector3d p = camera.projection.leftCols<3>() * r;
  return p.head<2>() / p.z();
}

void build_float_map(const CameraCalibration& camera, ImageView<float> map_x,
                     ImageView<float> map_y) {
  require(same_size(map_x, map_y), "rectification float maps differ in size: ", map_x.width(), "x",
          map_x.height(), " and ", map_y.width(), "x", map_y.height());
  const Eigen::Matrix3d to_ray = rectified_to_ray(camera);
  for (int v = 0; v < map_x.height(); ++v) {
    float* xs = map_x.row(v);
    float* ys = map_y.row(v);
    for (int u = 0; u < map_x.width(); ++u) {
      const Eigen::Vector2d s = source_from_ray(camera.camera, to_ray * Eigen::Vector3d(u, v, 1));
      xs[u] = static_cast<float>(s.x());
      ys[u] = static_cast<float>(s.y());
    }
  }
}

FixedPointMap build_fixed_point_map(const CameraCalibration& camera, int width, int height) {
  require(width >= 1 && height >= 1 && width <= 32767 && height <= 32767, "rectification map size ",
          width, "x", height, " is outside [1, 32767]");
  FixedPointMap map{Image<std::int16_t>(2 * width, height), Image<std::uint16_t>(width, height)};
  fill_fixed_point_map(camera, map.xy.view(), map.fractions.view());
  return map;
}

void fill_fixed_point_map(const CameraCalibration& camera, ImageView<std::int16_t> xy_plane,
                          ImageView<std::uint16_t> fraction_plane) {
  require(xy_plane.width() == 2 * fraction_plane.width() &&
              xy_plane.height() == fraction_plane.height(),
          "rectification map planes of ", xy_plane.width(), "x", xy_plane.height(), " and ",
          fraction_plane.width(), "x", fraction_plane.height(), " do not make one map");
  const Eigen::Matrix3d to_ray = rectified_to_ray(camera);
  for (int v = 0; v < fraction_plane.height(); ++v) {
    std::int16_t* xy = xy_plane.row(v);
    std::uint16_t* fractions = fraction_plane.row(v);
    for (int u = 0; u < fraction_plane.width(); ++u) {
      // Through float, as build_float_map(), so that the result equals RemapMap::from_float.
      const Eigen::Vector2d s = source_from_ray(camera.camera, to_ray * Eigen::Vector3d(u, v, 1));
      const int fx = to_fixed_point(static_cast<float>(s.x()), &xy[2 * u]);
      const int fy = to_fixed_point(static_cast<float>(s.y()), &xy[2 * u + 1]);
      fractions[u] = static_cast<std::uint16_t>(fy * FixedPointMap::kFractionSteps + fx);
    }
  }
}

FixedPointMap build_fixed_point_map(const StereoCalibration& calibration, Side side) {
  return build_fixed_point_map(camera_of(calibration, side), calibration.width, calibration.height);
}

}  // namespace epipole::calib

// A simulated scene's right camera turned after its calibration (sim_drift.hpp).
#include "sim/sim_drift.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "epipole/calib/camera_turn.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"

namespace epipole::hal {

namespace {

// Where each pixel of the turned camera's image is in the old one (NaN: outside the lens).
struct SourceMap {
  int width = 0, height = 0;
  std::vector<float> x, y;
};

SourceMap source_map(const calib::PinholeCamera& camera, const Eigen::Matrix3d& rotation, int width,
                     int height) {
  SourceMap map{width, height, {}, {}};
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  map.x.assign(pixels, NAN);
  map.y.assign(pixels, NAN);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector2d n = camera.normalize({u, v});
      if (!n.allFinite()) continue;
      const Eigen::Vector3d old_ray = rotation * Eigen::Vector3d(n.x(), n.y(), 1.0);
      if (old_ray.z() <= 0) continue;
      const Eigen::Vector2d p = camera.project(old_ray);
      const auto i = static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                     static_cast<std::size_t>(u);
      map.x[i] = static_cast<float>(p.x());
      map.y[i] = static_cast<float>(p.y());
    }
  }
  return map;
}

// Keys' cubic convolution (a = -0.5) at (x, y), the border repeated: sharper than bilinear,
// whose blur at half-pixel shifts a turned real camera would not have.
double bicubic(GrayView image, double x, double y) {
  const auto weights = [](double t) {
    const double t2 = t * t, t3 = t2 * t;
    return std::array<double, 4>{-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1,
                                 -1.5 * t3 + 2 * t2 + 0.5 * t, 0.5 * t3 - 0.5 * t2};
  };
  const double x0 = std::floor(x), y0 = std::floor(y);
  const std::array<double, 4> wx = weights(x - x0), wy = weights(y - y0);
  const auto ix = static_cast<int>(x0), iy = static_cast<int>(y0);
  double sum = 0;
  for (int j = 0; j < 4; ++j) {
    const int row = std::clamp(iy - 1 + j, 0, image.height() - 1);
    double across = 0;
    for (int i = 0; i < 4; ++i) {
      across += wx[static_cast<std::size_t>(i)] *
                image(std::clamp(ix - 1 + i, 0, image.width() - 1), row);
    }
    sum += wy[static_cast<std::size_t>(j)] * across;
  }
  return sum;
}

GrayImage remapped(GrayView image, const SourceMap& map) {
  GrayImage out(map.width, map.height);
  for (int v = 0; v < map.height; ++v) {
    for (int u = 0; u < map.width; ++u) {
      const auto i = static_cast<std::size_t>(v) * static_cast<std::size_t>(map.width) +
                     static_cast<std::size_t>(u);
      const auto x = static_cast<double>(map.x[i]), y = static_cast<double>(map.y[i]);
      // Outside the old image (or its lens): black, as a rendered world's empty rays.
      // (A border pixel mapped a rounding error outside stays in.)
      constexpr double kSlack = 1e-3;
      const double last_x = image.width() - 1, last_y = image.height() - 1;
      if (!(x >= -kSlack && y >= -kSlack && x <= last_x + kSlack && y <= last_y + kSlack)) {
        out(u, v) = 0;
        continue;
      }
      const double cx = std::clamp(x, 0.0, last_x), cy = std::clamp(y, 0.0, last_y);
      out(u, v) =
          static_cast<std::uint8_t>(std::clamp(std::lround(bicubic(image, cx, cy)), 0L, 255L));
    }
  }
  return out;
}

}  // namespace

Eigen::Matrix3d drift_rotation(const SimDrift& drift) {
  return calib::turn_rotation(
      {radians(drift.pitch_deg), radians(drift.roll_deg), radians(drift.yaw_deg)});
}

void drift_right_images(StereoImages& images, const calib::StereoCalibration& rig,
                        const SimDrift& drift) {
  if (images.right.empty()) return;
  const GrayImage& first = images.right.front();
  require(first.width() == rig.width && first.height() == rig.height, "a drift needs images of ",
          "the calibration's size, ", rig.width, "x", rig.height, "; these are ", first.width(),
          "x", first.height());
  const SourceMap map = source_map(rig.right.camera, drift_rotation(drift), rig.width, rig.height);
  for (GrayImage& right : images.right) right = remapped(right.view(), map);
}

}  // namespace epipole::hal

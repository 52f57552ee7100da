#include "epipole/calib/triangulation.hpp"

#include <cmath>
#include <limits>

#include "epipole/core/error.hpp"

namespace epipole::calib {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

}  // namespace

Triangulator::Triangulator(const Eigen::Matrix4d& Q, int width, int height) : q_(Q) {
  require(Q.allFinite(), "Q has a non-finite number");
  require(Q(3, 2) != 0, "Q(3,2) is 0: Q maps no disparity to a depth");
  require(width >= 1 && height >= 1 && width <= 32767 && height <= 32767, "triangulator size ",
          width, "x", height, " is outside [1, 32767]");
  points_ = Image<Point3f>(width, height);
}

Triangulator::Triangulator(const StereoCalibration& calibration)
    : Triangulator(calibration.Q, calibration.width, calibration.height) {}

double Triangulator::depth(double disparity) const {
  const double w = q_(3, 2) * disparity + q_(3, 3);
  if (!std::isfinite(disparity) || !(w > 0)) return kNaN;
  return q_(2, 3) / w;  // Q(2,0..2) are 0 for any rectified pair
}

Eigen::Vector3d Triangulator::point(double u, double v, double disparity) const {
  const Eigen::Vector4d h = q_ * Eigen::Vector4d(u, v, disparity, 1);
  if (!std::isfinite(disparity) || !(h.w() > 0)) return {kNaN, kNaN, kNaN};
  return h.head<3>() / h.w();
}

template <typename T>
void Triangulator::reproject_rows(ImageView<const T> disparity, double scale, bool zero_is_missing,
                                  ImageView<Point3f> points) const {
  require(disparity.width() == width() && disparity.height() == height(), "disparity image is ",
          disparity.width(), "x", disparity.height(), ", the triangulator ", width(), "x",
          height());
  require(same_size(disparity, points), "point image is ", points.width(), "x", points.height(),
          ", the triangulator ", width(), "x", height());
  const Eigen::Matrix4d& q = q_;
  for (int v = 0; v < height(); ++v) {
    const T* d = disparity.row(v);
    Point3f* out = points.row(v);
    // Q (u, v, d, 1) = row terms + u * column 0 + d * column 2.
    const double x0 = q(0, 1) * v + q(0, 3);
    const double y0 = q(1, 1) * v + q(1, 3);
    const double z0 = q(2, 1) * v + q(2, 3);
    const double w0 = q(3, 1) * v + q(3, 3);
    for (int u = 0; u < width(); ++u) {
      const double value = static_cast<double>(d[u]);
      const double dv = value * scale;
      const double w = w0 + q(3, 0) * u + q(3, 2) * dv;
      if ((zero_is_missing && value == 0) || !std::isfinite(dv) || !(w > 0)) {
        out[u] = {kNaNf, kNaNf, kNaNf};
        continue;
      }
      const double iw = 1 / w;
      out[u] = {static_cast<float>((x0 + q(0, 0) * u + q(0, 2) * dv) * iw),
                static_cast<float>((y0 + q(1, 0) * u + q(1, 2) * dv) * iw),
                static_cast<float>((z0 + q(2, 0) * u + q(2, 2) * dv) * iw)};
    }
  }
}

ImageView<const Point3f> Triangulator::reproject(ImageView<const float> disparity) {
  reproject_rows(disparity, 1.0, false, points_.view());
  return points_.view();
}

ImageView<const Point3f> Triangulator::reproject(ImageView<const std::uint16_t> disparity16) {
  reproject_rows(disparity16, 1.0 / 16, true, points_.view());
  return points_.view();
}

void Triangulator::reproject(ImageView<const float> disparity, ImageView<Point3f> points) const {
  reproject_rows(disparity, 1.0, false, points);
}

}  // namespace epipole::calib

#include "epipole/calib/imported_calibration.hpp"

#include <cmath>

#include "epipole/core/error.hpp"

namespace epipole::calib {

Distortion radial_tangential_distortion(std::span<const double> d, const std::string& where) {
  const std::size_t n = d.size();
  require(n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14, where, ": ", n,
          " distortion coefficients (expected 4, 5, 8, 12 or 14)");
  for (std::size_t i = 5; i < n; ++i) {
    require(d[i] == 0, where, ": coefficient ", i + 1, " of ", n, " is ", d[i],
            ": the rational, thin-prism and tilted models are not supported "
            "(only radial-tangential k1 k2 p1 p2 k3)");
  }
  Distortion out;
  if (n >= 4) out = {d[0], d[1], d[2], d[3], n >= 5 ? d[4] : 0.0};
  return out;
}

CameraCalibration pinhole_camera(const Eigen::Matrix3d& k, const Distortion& d,
                                 const std::string& where) {
  const bool pinhole = std::abs(k(0, 1)) <= 1e-9 * std::abs(k(0, 0)) && k(1, 0) == 0 &&
                       k(2, 0) == 0 && k(2, 1) == 0 && k(2, 2) == 1;
  require(pinhole, where,
          ": the camera matrix must be [fx 0 cx; 0 fy cy; 0 0 1] (skew is not "
          "supported)");
  CameraCalibration c;
  c.camera.intrinsics = {k(0, 0), k(1, 1), k(0, 2), k(1, 2)};
  c.camera.distortion = d;
  return c;
}

void validate_imported(const StereoCalibration& c, const std::string& files,
                       std::initializer_list<KeyName> names) {
  try {
    validate(c);
  } catch (const Error& e) {
    std::string message = e.what();
    for (const auto& [ours, theirs] : names) {
      if (message.starts_with(ours)) {
        message = std::string(theirs) + message.substr(ours.size());
        break;
      }
    }
    throw Error(cat(files, ": ", message));
  }
}

}  // namespace epipole::calib

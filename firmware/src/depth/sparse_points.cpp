#include "epipole/firmware/sparse_points.hpp"

namespace epipole::firmware {

std::size_t triangulate_matches(const calib::Triangulator& triangulator,
                                std::span<const vision::SparseMatch> matches,
                                std::span<SparsePoint> out, bool* truncated) {
  std::size_t n = 0;
  if (truncated != nullptr) *truncated = false;
  for (const vision::SparseMatch& m : matches) {
    const Eigen::Vector3d p = triangulator.point(
        static_cast<double>(m.xl), static_cast<double>(m.yl), static_cast<double>(m.disparity));
    if (!p.allFinite()) continue;
    if (n == out.size()) {
      if (truncated != nullptr) *truncated = true;
      break;
    }
    out[n++] = {m.xl,
                m.yl,
                m.xr,
                m.yr,
                m.disparity,
                static_cast<float>(p.x()),
                static_cast<float>(p.y()),
                static_cast<float>(p.z()),
                m.distance,
                m.left_feature};
  }
  return n;
}

}  // namespace epipole::firmware

// Sparse matches to 3-D points with the sample rig's Q: the same points as
// calib::Triangulator::point, matches without a point skipped, the output's bound kept.
#include "epipole/firmware/sparse_points.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "../calib/sample_calibration.hpp"

namespace epipole::firmware {
namespace {

TEST(SparsePoints, TriangulatesWithQ) {
  const calib::Triangulator triangulator(test::sample_calibration());
  std::vector<vision::SparseMatch> matches;
  for (const float d : {40.0f, 12.25f, 0.0f, 3.5f, -2.0f}) {
    matches.push_back({.xl = 100.0f + d, .yl = 50.0f, .xr = 100.0f, .yr = 51.0f, .disparity = d});
  }
  std::array<SparsePoint, 8> out{};
  bool truncated = true;
  const std::size_t n = triangulate_matches(triangulator, matches, out, &truncated);
  ASSERT_EQ(n, 3u) << "disparities 0 and -2 give no point";
  EXPECT_FALSE(truncated);
  const std::size_t kept[3] = {0, 1, 3};
  for (std::size_t i = 0; i < n; ++i) {
    const vision::SparseMatch& m = matches[kept[i]];
    const Eigen::Vector3d p = triangulator.point(m.xl, m.yl, m.disparity);
    EXPECT_EQ(out[i].xl, m.xl);
    EXPECT_EQ(out[i].yr, m.yr);
    EXPECT_EQ(out[i].disparity, m.disparity);
    EXPECT_FLOAT_EQ(out[i].x, static_cast<float>(p.x()));
    EXPECT_FLOAT_EQ(out[i].y, static_cast<float>(p.y()));
    EXPECT_FLOAT_EQ(out[i].z, static_cast<float>(p.z()));
    EXPECT_GT(out[i].z, 0.0f);
  }
  // Depth is baseline * focal length / disparity: 40 px is ~1.08 m on this rig.
  EXPECT_NEAR(out[0].z, 0.0834 * 518.86 / 40, 0.01);

  std::array<SparsePoint, 2> small{};
  EXPECT_EQ(triangulate_matches(triangulator, matches, small, &truncated), 2u);
  EXPECT_TRUE(truncated);
  EXPECT_EQ(triangulate_matches(triangulator, {}, small), 0u);
}

}  // namespace
}  // namespace epipole::firmware

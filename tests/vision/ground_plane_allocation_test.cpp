#include <gtest/gtest.h>

#include <cmath>

#include "allocation_counter.hpp"
#include "epipole/vision/ground_plane.hpp"

namespace epipole::vision {
namespace {

// A rig 0.6 m over flat ground, pitched down, rolled a little: a ground is found every time.
TEST(GroundAllocations, FindingTheGroundNeverAllocates) {
  constexpr int kW = 320, kH = 240;
  Image<std::int16_t> disparity(kW, kH);
  const double nx = 0.05, ny = 0.97, nz = 0.23, f = 260, b = 0.08, h = 0.6;
  for (int v = 0; v < kH; ++v) {
    for (int u = 0; u < kW; ++u) {
      const double d = b / h * (nx * (u - 160) + ny * (v - 120) + nz * f);
      disparity(u, v) = d > 0.5
                            ? static_cast<std::int16_t>(std::lround(d * 16 + (u * 7 + v) % 5 - 2))
                            : std::int16_t{-16};
    }
  }
  GroundPlaneConfig config;
  config.width = kW;
  config.height = kH;
  config.centre_column = 160;
  for (const SimdPath path : {SimdPath::reference, best_simd_path()}) {
    GroundPlaneFinder finder(config, path);
    int found = 0;
    test::AllocationCounter counter;
    for (int i = 0; i < 50; ++i) found += finder.find(disparity.view()).found ? 1 : 0;
    EXPECT_EQ(counter.count(), 0u) << to_string(path);
    EXPECT_EQ(found, 50) << to_string(path);
  }
}

}  // namespace
}  // namespace epipole::vision

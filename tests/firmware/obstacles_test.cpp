#include "epipole/firmware/obstacles.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "epipole/vision/stereo.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware {
namespace {

constexpr int kW = 160;
constexpr int kH = 96;
constexpr double kF = 100;
constexpr double kB = 0.1;

struct Fixture {
  calib::Triangulator triangulator{test::ideal_rig(kW, kH, kF, kB).Q, 1, 1};
  Image<std::int16_t> disparity{kW, kH};
  Fixture() {
    for (int y = 0; y < kH; ++y) {
      std::fill_n(disparity.view().row(y), kW, vision::kInvalidDisparity);
    }
  }
  void fill(int x0, int x1, int y0, int y1, int d16) {
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) disparity.view()(x, y) = static_cast<std::int16_t>(d16);
    }
  }
  ObstacleConfig config(int sectors) const {
    ObstacleConfig c;
    c.width = kW;
    c.height = kH;
    c.max_disparity = 32;
    c.sectors = sectors;
    return c;
  }
};

TEST(ObstacleSectors, NearestDepthPerSectorByAngle) {
  Fixture f;
  f.fill(0, kW, 0, kH, 4 * 16 + 8);   // a wall at 4.5 px: 2.22 m
  f.fill(120, 150, 30, 70, 20 * 16);  // a box on the right at 20 px: 0.5 m
  ObstacleSectors sectors(f.config(8), f.triangulator, kF, (kW - 1) / 2.0);
  const protocol::Obstacles& o = sectors.measure(f.disparity.view(), 42);
  EXPECT_EQ(o.frame, 42u);
  EXPECT_EQ(o.count, 8);
  // The horizontal view: from the left edge (-0.5) to the right edge (159.5), pinhole.
  const double fov = 2 * std::atan(80.0 / kF) * 180 / 3.14159265358979;
  EXPECT_EQ(o.field_of_view_centideg, static_cast<int>(std::lround(fov * 100)));
  const auto wall = static_cast<std::uint16_t>(std::lround(kF * kB / 4.5 * 1000));
  const auto box = static_cast<std::uint16_t>(std::lround(kF * kB / 20.0 * 1000));
  for (int s = 0; s < 8; ++s) {
    // Which sectors does the box (columns 120..149) cover? Sector centres in degrees:
    const double centre = sectors.sector_centre_deg(s);
    const double left_edge_of_box = std::atan((119.5 - 79.5) / kF) * 180 / 3.14159265358979;
    const double right_edge_of_box = std::atan((149.5 - 79.5) / kF) * 180 / 3.14159265358979;
    const double half = fov / 16;
    const bool sees_box = centre + half > left_edge_of_box && centre - half < right_edge_of_box;
    EXPECT_EQ(o.nearest_mm[static_cast<std::size_t>(s)], sees_box ? box : wall) << "sector " << s;
  }
}

TEST(ObstacleSectors, AFewWrongDisparitiesMakeNoObstacle) {
  Fixture f;
  f.fill(10, 13, 40, 43, 30 * 16);  // 9 pixels: below min_pixels
  ObstacleSectors sectors(f.config(4), f.triangulator, kF, (kW - 1) / 2.0);
  const protocol::Obstacles& o = sectors.measure(f.disparity.view(), 1);
  for (int s = 0; s < 4; ++s) {
    EXPECT_EQ(o.nearest_mm[static_cast<std::size_t>(s)], protocol::kUnknownDepth) << s;
  }
}

TEST(ObstacleSectors, OutsideTheBandAndBeyondTheRangeIsNothing) {
  Fixture f;
  f.fill(0, kW, 0, 20, 25 * 16);  // above the band (rows 24..71)
  f.fill(0, kW, 30, 60, 1 * 16);  // 1 px: 6.7 m, beyond a 5 m range
  ObstacleConfig c = f.config(2);
  c.max_depth_m = 5;
  ObstacleSectors sectors(c, f.triangulator, kF, (kW - 1) / 2.0);
  const protocol::Obstacles& o = sectors.measure(f.disparity.view(), 1);
  EXPECT_EQ(o.nearest_mm[0], protocol::kUnknownDepth);
  EXPECT_EQ(o.nearest_mm[1], protocol::kUnknownDepth);
}

// With a minimum confidence, the pixels the matcher trusts less are not counted: a near patch
// of doubtful disparities (a repeated texture, say) makes no obstacle in front of the wall.
TEST(ObstacleSectors, PixelsBelowTheMinimumConfidenceAreLeftOut) {
  Fixture f;
  f.fill(0, kW, 0, kH, 4 * 16);     // the wall at 4 px: 2.5 m
  f.fill(20, 60, 30, 70, 20 * 16);  // a patch at 20 px: 0.5 m, ...
  Image<std::uint8_t> confidence(kW, kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      confidence.view()(x, y) = x >= 20 && x < 60 && y >= 30 && y < 70 ? 40 : 200;  // ... doubtful
    }
  }
  const auto wall = static_cast<std::uint16_t>(std::lround(kF * kB / 4.0 * 1000));
  ObstacleConfig c = f.config(2);
  ObstacleSectors every_pixel(c, f.triangulator, kF, (kW - 1) / 2.0);
  EXPECT_NE(every_pixel.measure(f.disparity.view(), 1, confidence.view()).nearest_mm[0], wall)
      << "without a minimum the patch is the nearest";
  c.min_confidence = 64;
  ObstacleSectors trusted(c, f.triangulator, kF, (kW - 1) / 2.0);
  const protocol::Obstacles& o = trusted.measure(f.disparity.view(), 1, confidence.view());
  EXPECT_EQ(o.nearest_mm[0], wall);
  EXPECT_EQ(o.nearest_mm[1], wall);
  EXPECT_THROW(trusted.measure(f.disparity.view(), 1), Error) << "no confidence given";
  c.min_confidence = 256;
  EXPECT_THROW(ObstacleSectors(c, f.triangulator, kF, 80), Error);
}

TEST(ObstacleSectors, BadInputIsAnError) {
  Fixture f;
  ObstacleConfig c = f.config(0);
  EXPECT_THROW(ObstacleSectors(c, f.triangulator, kF, 80), Error);
  c = f.config(73);
  EXPECT_THROW(ObstacleSectors(c, f.triangulator, kF, 80), Error);
  c = f.config(8);
  EXPECT_THROW(ObstacleSectors(c, f.triangulator, -1, 80), Error);
  ObstacleSectors sectors(c, f.triangulator, kF, 80);
  Image<std::int16_t> small(10, 10);
  EXPECT_THROW(sectors.measure(small.view(), 0), Error);
}

}  // namespace
}  // namespace epipole::firmware

#include "epipole/firmware/obstacles.hpp"
#include "epipole/firmware/depth_grid.hpp"

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
  DepthCellsConfig grid(int columns, int rows) const {
    DepthCellsConfig c;
    c.width = kW;
    c.height = kH;
    c.max_disparity = 32;
    c.columns = columns;
    c.rows = rows;
    return c;
  }
  // The rig's rectified camera: fx = fy, the principal point in the middle.
  static RectifiedPinhole camera() { return {kF, (kW - 1) / 2.0, kF, (kH - 1) / 2.0}; }
  ObstacleConfig config(int sectors) const {
    ObstacleConfig c;
    c.width = kW;
    c.height = kH;
    c.max_disparity = 32;
    c.columns = sectors;
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

// A 4 x 3 grid over the whole view splits it evenly by angle: column edges at -38.7, -19.3, 0,
// 19.3 and 38.7 degrees (pixel columns 0..114 | 115..159 for the last), row edges at -25.6, -8.6,
// 8.6 and 25.6 degrees (rows 0..32 | 33..62 | 63..95). A box in columns 120..149, rows 30..69
// is in the last column's three cells; the wall behind it is in every other.
TEST(DepthGrid, NearestDepthPerCellByAngleBothWays) {
  Fixture f;
  f.fill(0, kW, 0, kH, 4 * 16 + 8);   // a wall at 4.5 px: 2.22 m
  f.fill(120, 150, 30, 70, 20 * 16);  // a box at 20 px: 0.5 m
  DepthGrid grid(f.grid(4, 3), f.triangulator, Fixture::camera());
  const protocol::DepthGrid& g = grid.measure(f.disparity.view(), 7);
  EXPECT_EQ(g.frame, 7u);
  EXPECT_EQ(g.columns, 4);
  EXPECT_EQ(g.count, 12);
  const auto centideg = [](double half_pixels) {
    return static_cast<int>(
        std::lround(2 * std::atan(half_pixels / kF) * 180 / 3.14159265358979 * 100));
  };
  EXPECT_EQ(g.field_of_view_centideg, centideg(80));
  EXPECT_EQ(g.vertical_field_of_view_centideg, centideg(48));
  const auto wall = static_cast<std::uint16_t>(std::lround(kF * kB / 4.5 * 1000));
  const auto box = static_cast<std::uint16_t>(std::lround(kF * kB / 20.0 * 1000));
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 4; ++column) {
      EXPECT_EQ(g.nearest_mm[static_cast<std::size_t>(row * 4 + column)], column == 3 ? box : wall)
          << column << "," << row;
    }
  }
  // Taller than the box's top rows (30..32 are 90 pixels of the top cell): a box moved down
  // below row 33 leaves the top row to the wall.
  f.fill(0, kW, 0, kH, 4 * 16 + 8);
  f.fill(120, 150, 40, 70, 20 * 16);
  const protocol::DepthGrid& lower = grid.measure(f.disparity.view(), 8);
  EXPECT_EQ(lower.nearest_mm[3], wall);
  EXPECT_EQ(lower.nearest_mm[7], box);
  EXPECT_EQ(lower.nearest_mm[11], box);
}

// The grid takes the board's minimum confidence as the sectors do.
TEST(DepthGrid, PixelsBelowTheMinimumConfidenceAreLeftOut) {
  Fixture f;
  f.fill(0, kW, 0, kH, 4 * 16);
  f.fill(0, 60, 0, 40, 20 * 16);  // a doubtful near patch in the top left cell
  Image<std::uint8_t> confidence(kW, kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) confidence.view()(x, y) = x < 60 && y < 40 ? 40 : 200;
  }
  const auto wall = static_cast<std::uint16_t>(std::lround(kF * kB / 4.0 * 1000));
  DepthCellsConfig c = f.grid(2, 2);
  DepthGrid every_pixel(c, f.triangulator, Fixture::camera());
  EXPECT_NE(every_pixel.measure(f.disparity.view(), 1, confidence.view()).nearest_mm[0], wall);
  c.min_confidence = 64;
  DepthGrid trusted(c, f.triangulator, Fixture::camera());
  const protocol::DepthGrid& g = trusted.measure(f.disparity.view(), 1, confidence.view());
  for (int cell = 0; cell < 4; ++cell)
    EXPECT_EQ(g.nearest_mm[static_cast<std::size_t>(cell)], wall);
  EXPECT_THROW(trusted.measure(f.disparity.view(), 1), Error) << "no confidence given";
}

// One cell over a large view: its nearest bin's sum of disparities (x16) passes 2^32.
TEST(DepthGrid, OneCellOverALargeViewAtTheLargestDisparity) {
  constexpr int kW2 = 1920, kH2 = 1080;
  const calib::Triangulator triangulator{test::ideal_rig(kW2, kH2, 1000, kB).Q, 1, 1};
  Image<std::int16_t> disparity(kW2, kH2);
  for (int y = 0; y < kH2; ++y)
    std::fill_n(disparity.view().row(y), kW2, std::int16_t{255 * 16 + 8});
  DepthCellsConfig c;
  c.width = kW2;
  c.height = kH2;
  c.max_disparity = 256;
  DepthGrid grid(c, triangulator, {1000, (kW2 - 1) / 2.0, 1000, (kH2 - 1) / 2.0});
  const protocol::DepthGrid& g = grid.measure(disparity.view(), 3);
  ASSERT_EQ(g.count, 1);
  EXPECT_EQ(g.nearest_mm[0], static_cast<std::uint16_t>(std::lround(1000 * kB / 255.5 * 1000)));
}

TEST(DepthGrid, BadInputIsAnError) {
  Fixture f;
  EXPECT_THROW(DepthGrid(f.grid(0, 3), f.triangulator, Fixture::camera()), Error);
  EXPECT_THROW(DepthGrid(f.grid(16, 16), f.triangulator, Fixture::camera()), Error)
      << "more cells than a message holds";
  EXPECT_THROW(DepthGrid(f.grid(4, 3), f.triangulator, {kF, 80, 0, 48}), Error) << "no fy";
  DepthCellsConfig far = f.grid(4, 3);
  far.max_depth_m = 70;
  EXPECT_THROW(DepthGrid(far, f.triangulator, Fixture::camera()), Error);
  EXPECT_THROW(DepthGrid(f.grid(1 << 16, 1 << 16), f.triangulator, Fixture::camera()), Error)
      << "columns x rows overflows an int";
  DepthGrid grid(f.grid(16, 15), f.triangulator, Fixture::camera());
  Image<std::int16_t> small(10, 10);
  EXPECT_THROW(grid.measure(small.view(), 0), Error);
}

}  // namespace
}  // namespace epipole::firmware

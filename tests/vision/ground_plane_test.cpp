// The ground finder: its v-disparity kernels against the reference bit for bit (odd widths,
// unaligned rows, every bin count), and the plane it fits to disparities made from a known
// ground under rigs at many heights, pitches and rolls, with obstacles, a wall, noise, holes and
// wrong pixels.
#include "epipole/vision/ground_plane.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "epipole/core/error.hpp"
#include "ground_plane_kernels.hpp"

namespace epipole::vision {
namespace {

TEST(GroundKernels, VDisparityRowsMatchTheReference) {
  std::mt19937 random(7);
  for (const int bins : {2, 7, 16, 64, 129, 300}) {
    for (int width = 1; width <= 83; width += 3) {
      for (int offset = 0; offset < 3; ++offset) {
        std::vector<std::int16_t> row(static_cast<std::size_t>(width + offset));
        std::uniform_int_distribution<int> value(-40, (bins + 3) * 16);
        for (auto& v : row) v = static_cast<std::int16_t>(value(random));
        // Runs of one disparity, as the ground's rows have them.
        for (int x = 0; x < width / 2; ++x) row[static_cast<std::size_t>(offset + x)] = 16 * 1 + 5;
        const auto n = static_cast<std::size_t>(bins);
        std::vector<std::uint16_t> ref(n, 0xAAAA), neon(n, 0x5555);
        std::vector<std::uint16_t> scratch(kernels::kVDisparityLanes * n, 0x1234);
        kernels::v_disparity_row_ref(row.data() + offset, width, bins, ref.data(), nullptr);
        kernels::v_disparity_row_neon(row.data() + offset, width, bins, neon.data(),
                                      scratch.data());
        ASSERT_EQ(ref, neon) << "bins " << bins << " width " << width << " offset " << offset;
        unsigned counted = 0;
        for (int x = 0; x < width; ++x) {
          const int d = row[static_cast<std::size_t>(offset + x)] >> 4;
          counted += d >= 1 && d < bins ? 1 : 0;
        }
        unsigned sum = 0;
        for (const std::uint16_t c : ref) sum += c;
        EXPECT_EQ(sum, counted);
        EXPECT_EQ(ref[0], 0);
      }
    }
  }
}

// A rig's view of flat ground: the camera `height_m` above it, pitched down `pitch_deg`,
// rolled `roll_deg` (right side down), baseline `baseline_m`.
struct Rig {
  double height_m, pitch_deg, roll_deg;
};
constexpr double kFocal = 520, kBaseline = 0.083;
constexpr int kWidth = 640, kHeight = 480, kDisparities = 128;
constexpr double kCx = 330, kCy = 236;

double radians(double deg) {
  return deg * std::numbers::pi / 180;
}

// The ground's disparity at (u, v): d = baseline / height * (n . (u - cx, v - cy, f)), with n the
// ground's downward normal in the camera frame; 0 above the horizon.
double ground_disparity(const Rig& rig, double u, double v) {
  const double p = radians(rig.pitch_deg), r = radians(rig.roll_deg);
  const double nx = std::sin(r) * std::cos(p), ny = std::cos(r) * std::cos(p), nz = std::sin(p);
  const double along = nx * (u - kCx) + ny * (v - kCy) + nz * kFocal;
  return along > 0 ? kBaseline / rig.height_m * along : 0;
}

// The ground, a box standing on it, a wall far behind, matching noise, holes and wrong pixels.
Image<std::int16_t> scene_disparity(const Rig& rig, std::uint32_t seed, double offset = 0) {
  Image<std::int16_t> disparity(kWidth, kHeight);
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> noise(-0.3, 0.3), unit(0, 1), any(1, kDisparities - 1);
  const int box_left = kWidth * 3 / 10, box_right = kWidth / 2;
  // The box stands where the ground has this disparity at the box's foot.
  const int box_foot = kHeight * 8 / 10;
  const double box_d = ground_disparity(rig, (box_left + box_right) / 2.0, box_foot);
  const double wall_d = kFocal * kBaseline / 8.0;
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      double d = ground_disparity(rig, u, v);
      if (d < wall_d) d = wall_d;  // the wall hides the ground beyond it
      if (u >= box_left && u < box_right && v <= box_foot && v >= box_foot - kHeight / 3 &&
          box_d > d) {
        d = box_d;
      }
      d += noise(random) - offset;
      const double fate = unit(random);
      if (fate < 0.03) d = any(random);  // a wrong match
      std::int16_t value = static_cast<std::int16_t>(std::lround(d * 16));
      if (fate > 0.95 || d >= kDisparities || d < 0) value = -16;  // a hole
      disparity(u, v) = value;
    }
  }
  return disparity;
}

// The Hough transform's bounds for rigs 0.05 .. 3 m high, pitched -45 .. 45 degrees and
// rolled -30 .. 30 degrees (the firmware derives them so from the board's ranges).
GroundPlaneConfig finder_config() {
  GroundPlaneConfig c;
  c.width = kWidth;
  c.height = kHeight;
  c.max_disparity = kDisparities;
  const double max_pitch = radians(45), max_roll = radians(30);
  c.min_slope = kBaseline * std::cos(max_pitch) * std::cos(max_roll) / 3.0;
  c.max_slope = kBaseline / 0.05;
  c.min_horizon = kCy - kFocal * std::tan(max_pitch) / std::cos(max_roll);
  c.max_horizon = kCy + kFocal * std::tan(max_pitch) / std::cos(max_roll);
  c.centre_column = kCx;
  c.max_tilt = std::tan(max_roll);
  return c;
}

class GroundFits : public ::testing::TestWithParam<Rig> {};

TEST_P(GroundFits, ThePlaneOfTheGroundUnderAnyRig) {
  const Rig rig = GetParam();
  for (const SimdPath path : {SimdPath::reference, best_simd_path()}) {
    GroundPlaneFinder finder(finder_config(), path);
    const Image<std::int16_t> disparity = scene_disparity(rig, 3);
    const GroundPlaneFit& fit = finder.find(disparity.view());
    ASSERT_TRUE(fit.found) << to_string(path) << ": " << fit.candidates << " candidates, "
                           << fit.inliers << " inliers, votes " << fit.votes;
    // The fitted disparity where the ground is seen, against the truth.
    double worst = 0;
    for (int v = 0; v < kHeight; v += 8) {
      for (int u = 0; u < kWidth; u += 8) {
        const double truth = ground_disparity(rig, u, v);
        if (truth < 2 || truth >= kDisparities) continue;
        worst = std::max(worst, std::abs(fit.a * u + fit.b * v + fit.c - truth));
      }
    }
    EXPECT_LT(worst, 0.25) << to_string(path) << ": a " << fit.a << " b " << fit.b << " c "
                           << fit.c;
    // The rig: baseline / height * n = (a, b, (c + a cx + b cy) / f).
    const double wx = fit.a, wy = fit.b, wz = (fit.c + fit.a * kCx + fit.b * kCy) / kFocal;
    const double norm = std::sqrt(wx * wx + wy * wy + wz * wz);
    EXPECT_NEAR(kBaseline / norm, rig.height_m, 0.02 * rig.height_m);
    EXPECT_NEAR(std::asin(wz / norm), radians(rig.pitch_deg), radians(0.5));
    EXPECT_NEAR(std::atan2(wx, wy), radians(rig.roll_deg), radians(0.5));
    EXPECT_GT(fit.inliers, fit.valid / 5);
  }
}

INSTANTIATE_TEST_SUITE_P(Rigs, GroundFits,
                         ::testing::Values(Rig{0.5, 10, 0}, Rig{0.3, 25, 8}, Rig{1.2, 5, -12},
                                           Rig{2.0, 35, 20}, Rig{0.15, 2, 3}, Rig{0.8, -5, 0},
                                           Rig{0.6, 15, -25}, Rig{2.8, 40, 0}));

// Rectified principal points apart (cx - cx' = 9 px): every disparity measured 9 px less than
// the geometry's. Told the offset, the finder admits the same grounds and returns the measured
// disparities' plane.
TEST(GroundFinder, TakesQsDisparityOffsetOut) {
  constexpr double kOffset = 9;
  const Rig rig{1.5, 20, -6};
  GroundPlaneConfig config = finder_config();
  config.disparity_offset = kOffset;
  GroundPlaneFinder finder(config, best_simd_path());
  const Image<std::int16_t> disparity = scene_disparity(rig, 4, kOffset);
  const GroundPlaneFit& fit = finder.find(disparity.view());
  ASSERT_TRUE(fit.found);
  for (const double u : {100.0, 330.0, 600.0}) {
    for (const double v : {300.0, 470.0}) {
      EXPECT_NEAR(fit.a * u + fit.b * v + fit.c, ground_disparity(rig, u, v) - kOffset, 0.25);
    }
  }
}

// A tilted table top at 1 m fills the lower half of the view, and the room is seen beyond the
// plane it lies in: a plane, but not the ground.
TEST(GroundFinder, APlaneWithTheRoomSeenThroughItIsNoGround) {
  const Rig table{0.6, 35, 10};  // the table's plane as a ground would be seen
  Image<std::int16_t> disparity(kWidth, kHeight);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const double d = ground_disparity(table, u, v);
      // The table's top ends at row 300; beyond its edge the room, 4 m away.
      disparity(u, v) = static_cast<std::int16_t>(
          std::lround((v > 300 || d <= 0 ? kFocal * kBaseline / 4.0 : d) * 16));
    }
  }
  for (int v = 0; v <= 300; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      disparity(u, v) = static_cast<std::int16_t>(
          std::lround(std::max(ground_disparity(table, u, v), kFocal * kBaseline / 4.0) * 16));
    }
  }
  GroundPlaneFinder finder(finder_config(), best_simd_path());
  const GroundPlaneFit& fit = finder.find(disparity.view());
  EXPECT_FALSE(fit.found) << fit.inliers << " inliers of " << fit.valid << ", " << fit.beyond
                          << " beyond";
  EXPECT_GT(fit.beyond, 0);
  // The same plane down to the bottom of the view, nothing beyond it: a ground.
  for (int v = 301; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      disparity(u, v) = static_cast<std::int16_t>(std::lround(ground_disparity(table, u, v) * 16));
    }
  }
  EXPECT_TRUE(finder.find(disparity.view()).found);
}

// A ground that only a sliver of the view shows (its last 40 rows, under a wall 0.8 m ahead) is
// found as a plane but is too small a share of what is seen to be sure of.
TEST(GroundFinder, TooFewPixelsOnAPlaneAreNoGround) {
  const Rig rig{0.5, 0, 0};
  Image<std::int16_t> disparity(kWidth, kHeight);
  const double wall = kFocal * kBaseline / 0.8;
  std::mt19937 random(8);
  std::uniform_real_distribution<double> rough(-1.5, 1.5);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const double value = v >= kHeight - 40 ? ground_disparity(rig, u, v) : wall + rough(random);
      disparity(u, v) = static_cast<std::int16_t>(std::lround(value * 16));
    }
  }
  GroundPlaneConfig config = finder_config();
  config.max_tilt = std::tan(radians(5));  // a rig that does not roll: a narrow band of candidates
  GroundPlaneFinder finder(config, best_simd_path());
  const GroundPlaneFit& fit = finder.find(disparity.view());
  EXPECT_FALSE(fit.found);
  EXPECT_GT(fit.inliers, 300);
  EXPECT_LT(fit.inliers, fit.valid * config.min_inlier_share);
  EXPECT_NEAR(fit.a * 330 + fit.b * 470 + fit.c, ground_disparity(rig, 330, 470), 0.2)
      << fit.inliers << " inliers of " << fit.valid;
}

TEST(GroundFinder, ReportsNoGroundWhereThereIsNone) {
  GroundPlaneFinder finder(finder_config(), best_simd_path());
  // A wall straight ahead, noisy: its disparity does not grow downwards.
  Image<std::int16_t> wall(kWidth, kHeight);
  std::mt19937 random(5);
  std::uniform_int_distribution<int> noise(-4, 4);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u)
      wall(u, v) = static_cast<std::int16_t>(20 * 16 + noise(random));
  }
  EXPECT_FALSE(finder.find(wall.view()).found);
  // Nothing valid at all.
  Image<std::int16_t> empty(kWidth, kHeight);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) empty(u, v) = -16;
  }
  const GroundPlaneFit& none = finder.find(empty.view());
  EXPECT_FALSE(none.found);
  EXPECT_EQ(none.votes, 0u);
  EXPECT_EQ(none.valid, 0);
}

TEST(GroundFinder, IsTheSameOnEveryRunAndPath) {
  const Image<std::int16_t> disparity = scene_disparity(Rig{0.7, 12, 6}, 9);
  GroundPlaneFinder ref(finder_config(), SimdPath::reference);
  GroundPlaneFinder fast(finder_config(), best_simd_path());
  const GroundPlaneFit a = ref.find(disparity.view());
  const GroundPlaneFit b = fast.find(disparity.view());
  const GroundPlaneFit c = fast.find(disparity.view());
  EXPECT_EQ(a.a, b.a);
  EXPECT_EQ(a.b, b.b);
  EXPECT_EQ(a.c, b.c);
  EXPECT_EQ(b.c, c.c);
  EXPECT_EQ(a.inliers, c.inliers);
}

TEST(GroundFinder, RefusesBadConfigurationsAndSizes) {
  GroundPlaneConfig c = finder_config();
  c.min_slope = 0;
  EXPECT_THROW(GroundPlaneFinder(c, SimdPath::reference), Error);
  c = finder_config();
  c.max_disparity = 5000;
  EXPECT_THROW(GroundPlaneFinder(c, SimdPath::reference), Error);
  c = finder_config();
  c.iterations = 0;
  EXPECT_THROW(GroundPlaneFinder(c, SimdPath::reference), Error);
  GroundPlaneFinder finder(finder_config(), SimdPath::reference);
  Image<std::int16_t> small(kWidth - 1, kHeight);
  EXPECT_THROW(finder.find(small.view()), Error);
}

}  // namespace
}  // namespace epipole::vision

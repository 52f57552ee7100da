// Stereo visual odometry (firmware/visual_odometry.hpp) on synthetic features with exact truth:
// a room of points, each with a descriptor of its own (a few bits wrong at every sighting), seen
// by a rectified rig that drives around a 5 m square at 1 m/s and 15 pairs a second, turning 90
// degrees at each corner, back to its start. The features are what the sparse stage would give:
// corners at whole pixels, stereo matches with a disparity a fifth of a pixel off.
#include "epipole/firmware/visual_odometry.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "allocation_counter.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/splitmix.hpp"

namespace epipole::firmware {
namespace {

constexpr int kW = 640, kH = 480;
constexpr std::size_t kBytes = vision::SparseStereoMatcher::kDescriptorBytes;

calib::RectifiedStereoCameras rig() {
  return {700, 320, 320, 240, 0.12};
}

double gaussian(SplitMix64& random) {
  const double u = std::max(random.uniform(), 1e-300);
  return std::sqrt(-2 * std::log(u)) * std::cos(2 * std::numbers::pi * random.uniform());
}

// Textured surfaces as points: the walls of a 9 m x 9 m room 2.5 m high around the square, and
// its floor; a world frame with y down (the cameras' axes at the start: x right, z forward).
struct Room {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<std::uint8_t, kBytes>> descriptors;
  Room(SplitMix64& random, int count) {
    for (int i = 0; i < count; ++i) {
      const double a = 9 * random.uniform() - 4.5 + 2.5, b = 9 * random.uniform() - 4.5 + 2.5;
      const double h = 0.5 - 2.5 * random.uniform();  // floor at y = 0.5 (the rig 0.5 m up)
      Eigen::Vector3d p;
      switch (i % 5) {
        case 0:
          p = {-2, h, b};
          break;  // walls at x = -2 and 7, z = -2 and 7
        case 1:
          p = {7, h, b};
          break;
        case 2:
          p = {a, h, -2};
          break;
        case 3:
          p = {a, h, 7};
          break;
        default:
          p = {a, 0.5, b};
          break;  // the floor
      }
      points.push_back(p);
      std::array<std::uint8_t, kBytes> d{};
      for (std::uint8_t& byte : d) byte = static_cast<std::uint8_t>(random.next());
      descriptors.push_back(d);
    }
  }
};

// The camera's pose (camera -> world) on the square: start at the origin looking along +z,
// drive 5 m, turn 90 degrees right (about -y... y is down: a right turn is about +y) in place
// over 1.5 s, and so on; `t` in seconds.
calib::RigidMotion pose_at(double t) {
  const double leg = 5.0, turn = 1.5;  // 5 s a leg at 1 m/s, then the turn
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  double heading = 0;  // about +y, radians
  for (int side = 0; side < 4 && t > 0; ++side) {
    const Eigen::Vector3d forward(std::sin(heading), 0, std::cos(heading));
    const double drive = std::min(t, leg);
    at += drive * forward;
    t -= drive;
    const double turned = std::clamp(t / turn, 0.0, 1.0);
    heading += turned * std::numbers::pi / 2;
    t -= std::min(t, turn);
  }
  return {Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitY()).toRotationMatrix(), at};
}

// One pair's features: the room's points the rig sees, as the sparse stage would give them.
struct PairFeatures {
  std::vector<std::int16_t> x, y;
  std::vector<std::uint32_t> row_start = std::vector<std::uint32_t>(kH + 1, 0);
  std::vector<std::uint8_t> descriptors;
  std::vector<SparsePoint> points;
  vision::DescribedCorners corners() const { return {x, y, row_start, descriptors}; }
};

PairFeatures features_at(const Room& room, const calib::RigidMotion& pose, SplitMix64& random,
                         bool blank = false) {
  const calib::RectifiedStereoCameras c = rig();
  const calib::RigidMotion to_camera = pose.inverse();
  struct Seen {
    int x, y;
    std::size_t point;
    double disparity;
  };
  std::vector<Seen> seen;
  if (!blank) {
    for (std::size_t i = 0; i < room.points.size(); ++i) {
      const Eigen::Vector3d p = to_camera.apply(room.points[i]);
      if (p.z() < 0.4 || p.z() > 12) continue;
      const double u = c.f * p.x() / p.z() + c.left_cx, v = c.f * p.y() / p.z() + c.cy;
      const int x = static_cast<int>(std::lround(u)), y = static_cast<int>(std::lround(v));
      if (x < 14 || y < 14 || x >= kW - 14 || y >= kH - 14) continue;
      seen.push_back({x, y, i, c.f * c.baseline / p.z() + 0.2 * gaussian(random)});
    }
  }
  std::sort(seen.begin(), seen.end(),
            [](const Seen& a, const Seen& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  if (seen.size() > 2000) seen.resize(2000);
  PairFeatures f;
  for (std::size_t k = 0; k < seen.size(); ++k) {
    const Seen& s = seen[k];
    f.x.push_back(static_cast<std::int16_t>(s.x));
    f.y.push_back(static_cast<std::int16_t>(s.y));
    ++f.row_start[static_cast<std::size_t>(s.y) + 1];
    std::array<std::uint8_t, kBytes> d = room.descriptors[s.point];
    for (int flip = 0; flip < 8; ++flip) {  // a few bits differ at every sighting
      const auto bit = static_cast<std::size_t>(random.below(kBytes * 8));
      d[bit / 8] = static_cast<std::uint8_t>(d[bit / 8] ^ (1u << (bit % 8)));
    }
    f.descriptors.insert(f.descriptors.end(), d.begin(), d.end());
    if (k % 4 == 3) continue;  // a quarter without a stereo match
    const double z = c.f * c.baseline / s.disparity;
    SparsePoint p;
    p.xl = static_cast<float>(s.x);
    p.yl = static_cast<float>(s.y);
    p.disparity = static_cast<float>(s.disparity);
    p.xr = p.xl - p.disparity;
    p.yr = p.yl;
    p.x = static_cast<float>((s.x - c.left_cx) * z / c.f);
    p.y = static_cast<float>((s.y - c.cy) * z / c.f);
    p.z = static_cast<float>(z);
    p.distance = static_cast<int>(random.below(40));
    p.left_feature = static_cast<int>(k);
    f.points.push_back(p);
  }
  for (int y = 0; y < kH; ++y)
    f.row_start[static_cast<std::size_t>(y) + 1] += f.row_start[static_cast<std::size_t>(y)];
  return f;
}

double heading_error_deg(const calib::RigidMotion& a, const calib::RigidMotion& b) {
  return Eigen::AngleAxisd(a.rotation.transpose() * b.rotation).angle() * 180 / std::numbers::pi;
}

struct LoopRun {
  double end_error_m = 0, end_heading_deg = 0;
  int lost = 0, pairs = 0;
  OdometryState last;
};

// Around the square (26 s) at 15 pairs a second; `dropped` of the pairs never arrive; the
// odometry's pose compared with the truth at the end.
LoopRun drive_the_loop(double dropped, std::uint64_t seed) {
  SplitMix64 random(seed);
  const Room room(random, 6000);
  VisualOdometry odometry(rig(), kW, kH, 4000, 2000, {});
  LoopRun run;
  const int pairs = 26 * 15 + 1;
  for (int i = 0; i < pairs; ++i) {
    if (i > 0 && i < pairs - 1 && random.uniform() < dropped) continue;
    const double t = i / 15.0;
    const PairFeatures f = features_at(room, pose_at(t), random);
    run.last = odometry.update(static_cast<hal::Nanoseconds>(t * 1e9), f.corners(), f.points);
    run.lost += run.last.status == OdometryState::Status::lost ? 1 : 0;
    ++run.pairs;
  }
  const calib::RigidMotion truth = pose_at(26);
  run.end_error_m = (run.last.pose.translation - truth.translation).norm();
  run.end_heading_deg = heading_error_deg(run.last.pose, truth);
  return run;
}

TEST(VisualOdometry, AroundASquareBackToItsStart) {
  const LoopRun run = drive_the_loop(0, 1);
  std::printf("loop: %d pairs, %u keyframes, end %.3f m and %.3f deg off, %d lost\n", run.pairs,
              run.last.keyframes, run.end_error_m, run.end_heading_deg, run.lost);
  EXPECT_EQ(run.lost, 0);
  EXPECT_EQ(run.last.status, OdometryState::Status::tracking);
  EXPECT_LT(run.end_error_m, 0.01 * 20) << "1 % of the 20 m driven";
  EXPECT_LT(run.end_heading_deg, 1.0);
  EXPECT_EQ(run.last.reset_counter, 0);
  EXPECT_GT(run.last.quality, 0);
}

TEST(VisualOdometry, TheSameWithATenthOfThePairsDropped) {
  const LoopRun run = drive_the_loop(0.1, 2);
  std::printf("loop, 10 %% dropped: %d pairs, end %.3f m and %.3f deg off, %d lost\n", run.pairs,
              run.end_error_m, run.end_heading_deg, run.lost);
  EXPECT_LT(run.pairs, 26 * 15 * 95 / 100);
  EXPECT_EQ(run.lost, 0);
  EXPECT_LT(run.end_error_m, 0.01 * 20);
  EXPECT_LT(run.end_heading_deg, 1.0);
}

// Standing still, the keyframe stays and nothing drifts.
TEST(VisualOdometry, StandingStillNothingDrifts) {
  SplitMix64 random(3);
  const Room room(random, 6000);
  VisualOdometry odometry(rig(), kW, kH, 4000, 2000, {});
  const calib::RigidMotion still = pose_at(2);
  OdometryState s;
  for (int i = 0; i < 300; ++i) {
    const PairFeatures f = features_at(room, still, random);
    s = odometry.update(static_cast<hal::Nanoseconds>(i * 66'666'667LL), f.corners(), f.points);
  }
  EXPECT_EQ(s.status, OdometryState::Status::tracking);
  EXPECT_EQ(s.keyframes, 1u) << "the first keyframe throughout";
  EXPECT_LT(s.pose.translation.norm(), 0.005);
  EXPECT_LT(s.velocity.norm(), 0.05);
}

// A blank stretch (nothing to see: a wall without texture) reports the tracking lost, never a
// pose; once there is something to see again, the odometry starts again from where it was,
// and the reset counter says so.
TEST(VisualOdometry, ABlankStretchIsLostTrackingNotAPose) {
  SplitMix64 random(4);
  const Room room(random, 6000);
  VisualOdometry odometry(rig(), kW, kH, 4000, 2000, {});
  int lost = 0;
  OdometryState s;
  calib::RigidMotion before_blank;
  for (int i = 0; i < 120; ++i) {
    const double t = i / 15.0;
    const bool blank = i >= 40 && i < 60;
    const PairFeatures f = features_at(room, pose_at(t), random, blank);
    s = odometry.update(static_cast<hal::Nanoseconds>(t * 1e9), f.corners(), f.points);
    if (i == 39) before_blank = s.pose;
    if (blank) {
      EXPECT_EQ(s.status, OdometryState::Status::lost) << i;
      EXPECT_EQ(s.quality, -1);
      EXPECT_TRUE(s.pose.translation.isApprox(before_blank.translation)) << "no made-up pose";
      ++lost;
    }
  }
  EXPECT_EQ(lost, 20);
  EXPECT_EQ(s.status, OdometryState::Status::tracking);
  EXPECT_EQ(s.reset_counter, 1);
  // The 20 blank pairs' motion (1.33 m) is missing from the pose, the rest is followed.
  const calib::RigidMotion truth = pose_at(119 / 15.0), blank_start = pose_at(39 / 15.0),
                           blank_end = pose_at(60 / 15.0);
  const Eigen::Vector3d missing = blank_end.translation - blank_start.translation;
  EXPECT_LT((s.pose.translation + missing - truth.translation).norm(), 0.1);
}

// A pair lost mid-leg (nothing seen in it): the next step spans both periods, is followed (not
// refused as too fast) and gives the speed driven.
TEST(VisualOdometry, ALostPairIsSpannedByTheNextStep) {
  SplitMix64 random(6);
  const Room room(random, 6000);
  VisualOdometry odometry(rig(), kW, kH, 4000, 2000, {});
  for (int i = 0; i < 40; ++i) {
    const double t = 0.5 + i / 15.0;  // along the first leg, at 1 m/s
    const PairFeatures f = features_at(room, pose_at(t), random, i == 30);
    const OdometryState& s =
        odometry.update(static_cast<hal::Nanoseconds>(t * 1e9), f.corners(), f.points);
    if (i == 30) {
      EXPECT_EQ(s.status, OdometryState::Status::lost);
      continue;
    }
    ASSERT_EQ(s.status, OdometryState::Status::tracking) << i;
    if (i < 2) continue;  // the first pair has no motion yet
    EXPECT_NEAR(s.velocity.norm(), 1.0, 0.1) << i << ": 1 m/s";
    EXPECT_NEAR(s.velocity.z(), 1.0, 0.1) << i << ": forward";
  }
}

TEST(VisualOdometry, APairAllocatesNothing) {
  SplitMix64 random(5);
  const Room room(random, 6000);
  std::vector<PairFeatures> pairs;
  for (int i = 0; i < 40; ++i) pairs.push_back(features_at(room, pose_at(4.5 + i / 15.0), random));
  VisualOdometry odometry(rig(), kW, kH, 4000, 2000, {});
  int tracking = 0;
  const test::AllocationCounter counter;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const OdometryState& s = odometry.update(static_cast<hal::Nanoseconds>(i * 66'666'667LL),
                                             pairs[i].corners(), pairs[i].points);
    tracking += s.status == OdometryState::Status::tracking ? 1 : 0;
  }
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_EQ(tracking, 40) << "through the corner's turn";
}

TEST(VisualOdometry, SettingsOutOfRangeAreErrors) {
  OdometryConfig c;
  c.keyframe_distance_m = 0;
  EXPECT_THROW(VisualOdometry(rig(), kW, kH, 4000, 2000, c), Error);
  c = {};
  c.max_landmarks = 5;  // fewer than min_inliers
  EXPECT_THROW(VisualOdometry(rig(), kW, kH, 4000, 2000, c), Error);
  c = {};
  c.search_radius_px = 0;
  EXPECT_THROW(VisualOdometry(rig(), kW, kH, 4000, 2000, c), Error);
}

}  // namespace
}  // namespace epipole::firmware

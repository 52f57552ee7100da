// A processed pair's results as protocol messages: every field in the protocol's units, counts
// saturating, depths past the field's range unknown, messages only for what ran.
#include "epipole/firmware/pair_messages.hpp"
#include "epipole/core/angles.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace epipole::firmware {
namespace {

using protocol::Stage;
using protocol::stage_bit;

FrameResult nothing_ran(std::uint32_t frame, hal::Nanoseconds trigger_ns) {
  FrameResult r;
  r.frame = frame;
  r.trigger_ns = trigger_ns;
  r.stages = stage_bit(Stage::capture);
  return r;
}

TEST(PairMessages, TheSummaryIsInTheProtocolsUnits) {
  FrameResult r = nothing_ran(41, 5'000'123'456);
  const std::vector<vision::Corner> corners_left(70'000), corners_right(12);
  r.corners_left = corners_left;
  r.corners_right = corners_right;
  r.valid_disparity_permille = 873;
  const PairMessages m = pair_messages(r, 12'345'678, false);
  EXPECT_EQ(m.summary.frame, 41u);
  EXPECT_EQ(m.summary.trigger_ns, 5'000'123'456u);
  EXPECT_EQ(m.summary.latency_us, 12'345u) << "nanoseconds to microseconds, truncated";
  EXPECT_EQ(m.summary.corners_left, 65'535) << "saturates";
  EXPECT_EQ(m.summary.corners_right, 12);
  EXPECT_EQ(m.summary.valid_disparity_permille, 873);
  EXPECT_EQ(m.summary.points, 0);
  EXPECT_EQ(m.summary.detections, 0);
  EXPECT_EQ(m.summary.flags, 0);
  EXPECT_FALSE(m.detections) << "the detector did not run";
  EXPECT_FALSE(m.obstacles);
  EXPECT_FALSE(m.points);

  const PairMessages late = pair_messages(nothing_ran(1, -5), std::int64_t{1} << 62, true);
  EXPECT_EQ(late.summary.trigger_ns, 0u) << "never negative";
  EXPECT_EQ(late.summary.latency_us, std::numeric_limits<std::uint32_t>::max());
  EXPECT_EQ(late.summary.flags, protocol::kFrameTriggerFromCapture);
  EXPECT_EQ(pair_messages(nothing_ran(1, 0), -7, false).summary.latency_us, 0u);
}

TEST(PairMessages, DetectionsCarryTheirDepthInMillimetres) {
  FrameResult r = nothing_ran(7, 0);
  r.stages |= stage_bit(Stage::detect);
  EXPECT_EQ(pair_messages(r, 0, false).detections->count, 0)
      << "the detector ran and found nothing: the robot is told so";

  const std::vector<vision::Detection> boxes{{10, 20, 30, 40, 3},
                                             {1, 2, 3, 4, 300},
                                             {5, 6, 7, 8, 1},
                                             {9, 9, 9, 9, 1},
                                             {0, 0, 70'000, 5, 1}};
  const std::vector<DetectionDepth> depths{
      {true, 12.0f, 2.5}, {false, 0.0f, 1.0}, {true, 1.0f, 65.5}, {true, 1.0f, 0.0}, {}};
  r.detections = boxes;
  r.detection_depths = depths;
  const PairMessages m = pair_messages(r, 0, false);
  EXPECT_EQ(m.summary.detections, 5);
  ASSERT_TRUE(m.detections);
  const protocol::Detections& d = *m.detections;
  EXPECT_EQ(d.frame, 7u);
  ASSERT_EQ(d.count, 5);
  EXPECT_EQ(d.items[0], (protocol::Detection{10, 20, 30, 40, 3, 2500}));
  EXPECT_EQ(d.items[1].neighbors, 255) << "saturates";
  EXPECT_EQ(d.items[1].depth_mm, protocol::kUnknownDepth) << "not valid";
  EXPECT_EQ(d.items[2].depth_mm, protocol::kUnknownDepth) << "65.5 m is past the field";
  EXPECT_EQ(d.items[3].depth_mm, protocol::kUnknownDepth) << "not in front";
  EXPECT_EQ(d.items[4].width, 65'535);
}

TEST(PairMessages, PointsAreTheBestMatchesInMillimetresAndSixteenthsOfAPixel) {
  FrameResult r = nothing_ran(3, 0);
  std::vector<SparsePoint> points(3);
  points[0] = {10.5f, 20.25f, 0, 0, 4.0f, 0.1234f, -0.5f, 2.0f, 9, -1};
  points[1] = {1.0f, 2.0f, 0, 0, 4.0f, 3e6f, -3e6f, 1.2506f, 1, -1};
  points[2] = {0.03f, 0.0f, 0, 0, 4.0f, 0, 0, 1, 5, -1};
  const std::vector<std::uint32_t> best{1, 0};
  r.points = points;
  r.best_points = best;
  const PairMessages m = pair_messages(r, 0, false);
  EXPECT_EQ(m.summary.points, 2);
  ASSERT_TRUE(m.points);
  ASSERT_EQ(m.points->count, 2);
  EXPECT_EQ(m.points->frame, 3u);
  // Clamped to +-2000 km.
  EXPECT_EQ(m.points->items[0], (protocol::Point{16, 32, 2'000'000'000, -2'000'000'000, 1251}));
  EXPECT_EQ(m.points->items[1], (protocol::Point{168, 324, 123, -500, 2000}));
}

TEST(PairMessages, ObstaclesAreSentAsTheSectorsMeasuredThem) {
  FrameResult r = nothing_ran(9, 0);
  protocol::Obstacles o;
  o.frame = 9;
  o.count = 3;
  o.field_of_view_centideg = 9000;
  o.nearest_mm = {1200, protocol::kUnknownDepth, 800};
  r.obstacles = &o;
  const PairMessages m = pair_messages(r, 0, false);
  ASSERT_TRUE(m.obstacles);
  EXPECT_EQ(*m.obstacles, o);

  BoardConfig::Obstacles range;
  range.min_depth_m = 0.2;
  range.max_depth_m = 20.0;
  const mavlink::ObstacleDistance d = obstacle_distance_message(o, 7'000'999, range);
  EXPECT_EQ(d.time_usec, 7'000u);
  EXPECT_EQ(d.min_distance_cm, 20);
  EXPECT_EQ(d.max_distance_cm, 2000);
  EXPECT_EQ(d.distances_cm[0], 120);
  EXPECT_EQ(d.distances_cm[2], 80);
}

TEST(PairMessages, TheDepthGridIsSentAsMeasured) {
  FrameResult r = nothing_ran(9, 0);
  EXPECT_FALSE(pair_messages(r, 0, false).depth_grid) << "no grid measured, none sent";
  protocol::DepthGrid g;
  g.frame = 9;
  g.field_of_view_centideg = 9000;
  g.vertical_field_of_view_centideg = 6000;
  g.columns = 2;
  g.count = 4;
  g.nearest_mm = {1200, protocol::kUnknownDepth, 800, 650};
  r.depth_grid = &g;
  const PairMessages m = pair_messages(r, 0, false);
  ASSERT_TRUE(m.depth_grid);
  EXPECT_EQ(*m.depth_grid, g);
}

TEST(PairMessages, TheStagesOwnMessagesComeWithThePairInTheStagesOrder) {
  FrameResult r = nothing_ran(12, 0);
  for (const protocol::Message* none : pair_messages(r, 0, false).stage_messages) {
    EXPECT_EQ(none, nullptr) << "no stage left a message: none is sent";
  }
  protocol::Message from_disparity = protocol::Obstacles{};
  protocol::Message from_sparse = protocol::CalibrationHealth{};
  r.stage_messages[static_cast<std::size_t>(Stage::sparse)] = &from_sparse;
  r.stage_messages[static_cast<std::size_t>(Stage::disparity)] = &from_disparity;
  const PairMessages m = pair_messages(r, 0, false);
  std::vector<const protocol::Message*> sent;
  for (const protocol::Message* message : m.stage_messages) {
    if (message != nullptr) sent.push_back(message);
  }
  EXPECT_EQ(sent, (std::vector<const protocol::Message*>{&from_disparity, &from_sparse}))
      << "the disparity runs before the sparse matching";
}

TEST(PairMessages, CalibrationHealthInHundredthsOfAPixelAndThousandthsOfADegree) {
  // matches, median |offset|, p90 |offset|, signed median
  const protocol::CalibrationHealth c =
      calibration_health_message({812, 0.184, 0.4449, -0.126}, std::nullopt);
  EXPECT_EQ(c, (protocol::CalibrationHealth{812, -13, 44}));
  const protocol::CalibrationHealth far =
      calibration_health_message({70'000, 700.0, 1e9, -700.0}, std::nullopt);
  EXPECT_EQ(far, (protocol::CalibrationHealth{65'535, -32'768, 65'535})) << "saturates";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(calibration_health_message({0, nan, nan, nan}, std::nullopt),
            (protocol::CalibrationHealth{}))
      << "no finite match: no figure";

  calib::DriftEstimate drift;
  drift.valid = true;
  drift.pairs = 30;
  drift.pitch = radians(0.3004);
  drift.roll = radians(-0.2);
  drift.pitch_sigma = radians(0.0021);
  drift.roll_sigma = radians(0.0436);
  const protocol::CalibrationHealth d = calibration_health_message({500, 3.1, 4.2, 3.05}, drift);
  EXPECT_EQ(d.flags, protocol::kDriftEstimated);
  EXPECT_EQ(d.window_pairs, 30);
  EXPECT_EQ(d.pitch_mdeg, 300);
  EXPECT_EQ(d.roll_mdeg, -200);
  EXPECT_EQ(d.pitch_sigma_mdeg, 2);
  EXPECT_EQ(d.roll_sigma_mdeg, 44);
  drift.valid = false;  // too few pairs yet: none of it
  const protocol::CalibrationHealth none = calibration_health_message({500, 3.1, 4.2, 3.05}, drift);
  EXPECT_EQ(none.flags, 0);
  EXPECT_EQ(none.pitch_mdeg, 0);
}

}  // namespace
}  // namespace epipole::firmware

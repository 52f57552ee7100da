// Stereo visual odometry on the simulated board's rendered room (board/sim's scene `loop`): the
// rig walked round a closed 5 m square at 1 m/s, turning 90 degrees at each corner, back to its
// start; the pipeline's odometry against the exact path the renderer took (world_trajectory).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "board_scene.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/core/splitmix.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "sim/sim_settings.hpp"
#include "sim/world_scene.hpp"

namespace epipole::firmware {
namespace {

// The stages the odometry reads (the dense ones only cost time here).
const std::vector<std::string> kOdometryOnly = {"stages.disparity=false", "stages.detect=false",
                                                "stages.ground=false"};

double rotation_deg(const Eigen::Matrix3d& r) {
  return degrees(Eigen::AngleAxisd(r).angle());
}

struct LoopRun {
  std::size_t pairs = 0;        // processed
  std::size_t lost = 0;         // pairs that reported the tracking lost
  std::size_t last = 0;         // the last pair tracked
  calib::RigidMotion pose;      // its pose
  double worst_position_m = 0;  // the largest error of a tracked pair along the way
  double path_m = 0;            // the distance the truth travels
  std::uint8_t resets = 0;
};

// The scene's pairs through a pipeline, each at its trigger time; `drop` of them left out at
// random (never the first and the last), as a loop that missed them.
LoopRun run_loop(const test::BoardScene& s, const std::vector<calib::RigidMotion>& truth,
                 double rate_hz, double drop) {
  Pipeline pipeline(s.config, s.rig);
  SplitMix64 random(0x5eed);
  LoopRun run;
  const std::size_t n = s.images.left.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) run.path_m += (truth[i].translation - truth[i - 1].translation).norm();
    if (i > 0 && i + 1 < n && random.uniform() < drop) continue;
    const auto trigger_ns =
        static_cast<hal::Nanoseconds>(std::llround(static_cast<double>(i) * 1e9 / rate_hz));
    const FrameResult& r =
        pipeline.process(s.images.left[i].view(), s.images.right[i].view(),
                         static_cast<std::uint32_t>(i), trigger_ns, s.config.stages);
    ++run.pairs;
    EXPECT_NE(r.odometry, nullptr) << "pair " << i;
    if (r.odometry == nullptr) continue;
    run.resets = r.odometry->reset_counter;
    if (r.odometry->status != OdometryState::Status::tracking) {
      ++run.lost;
      continue;
    }
    run.last = i;
    run.pose = r.odometry->pose;
    run.worst_position_m =
        std::max(run.worst_position_m, (run.pose.translation - truth[i].translation).norm());
  }
  return run;
}

TEST(LoopScene, TheLoopClosesWithinOnePercentAndOneDegree) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  const test::BoardScene s = test::board_scene("loop", kOdometryOnly);
  const hal::SimWorld& world = *hal::sim_settings(s.config.sections).chosen().world;
  const std::vector<calib::RigidMotion> truth = hal::world_trajectory(world, *s.rig);
  ASSERT_EQ(truth.size(), s.images.left.size());
  // The truth closes the loop: back at the start, facing as it started.
  EXPECT_LT(truth.back().translation.norm(), 1e-9);
  EXPECT_LT(rotation_deg(truth.back().rotation), 1e-6);

  for (const double drop : {0.0, 0.1}) {
    SCOPED_TRACE(testing::Message() << "pairs dropped: " << drop * 100 << " %");
    const LoopRun run = run_loop(s, truth, world.path->rate_hz, drop);
    ASSERT_EQ(run.last, truth.size() - 1) << "the last pair tracked";
    const double position = (run.pose.translation - truth[run.last].translation).norm();
    const double heading = rotation_deg(truth[run.last].rotation.transpose() * run.pose.rotation);
    std::printf(
        "loop, %.0f %% dropped: %zu pairs, %zu lost, %d resets; %.2f m travelled; at the end "
        "%.3f m (%.2f %%) and %.2f deg off; worst on the way %.3f m\n",
        drop * 100, run.pairs, run.lost, run.resets, run.path_m, position,
        100 * position / run.path_m, heading, run.worst_position_m);
    EXPECT_NEAR(run.path_m, 20.0, 0.05);
    EXPECT_LE(position, 0.01 * run.path_m);
    EXPECT_LE(heading, 1.0);
    EXPECT_EQ(run.lost, 0u);
    EXPECT_EQ(run.resets, 0);
  }
}

// The rig walks towards the room's one textured wall, turns round on the spot and walks on
// towards a blank one over a blank floor: from the moment nothing is left to follow, every pair
// says the tracking is lost, and the pose it keeps is the last one tracked, never a made-up one.
TEST(LoopScene, ABlankStretchIsLostTrackingNotAPose) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  const test::BoardScene s = test::board_scene("loop", kOdometryOnly, false);
  hal::SimWorld world = *hal::sim_settings(s.config.sections).chosen().world;
  const std::filesystem::path blank = std::filesystem::path(::testing::TempDir()) / "blank.png";
  GrayImage grey(64, 64);
  for (int y = 0; y < grey.height(); ++y) {
    for (int x = 0; x < grey.width(); ++x) grey(x, y) = 128;
  }
  save_image(blank, std::as_const(grey).view());
  world.floor.file = blank;
  world.boxes.resize(4);  // the walls, the north one (ahead at the start) textured
  for (std::size_t i = 1; i < 4; ++i) world.boxes[i].texture.file = blank;
  world.path->waypoints_m = {{0, 0}, {0, 1}, {0, -1}};
  const hal::StereoImages images =
      hal::render_world(world, *s.rig, s.config.width(), s.config.height());
  const std::vector<calib::RigidMotion> truth = hal::world_trajectory(world, *s.rig);
  ASSERT_EQ(truth.size(), images.left.size());
  // The turn ends 3 s in (1 m at 1 m/s, then 180 degrees at 90 degrees/s): facing south.
  const auto facing_blank = static_cast<std::size_t>(3 * world.path->rate_hz);

  Pipeline pipeline(s.config, s.rig);
  std::size_t tracked = 0, last_tracked = 0, lost_facing_blank = 0;
  calib::RigidMotion kept;
  for (std::size_t i = 0; i < images.left.size(); ++i) {
    const auto trigger_ns = static_cast<hal::Nanoseconds>(
        std::llround(static_cast<double>(i) * 1e9 / world.path->rate_hz));
    const FrameResult& r =
        pipeline.process(images.left[i].view(), images.right[i].view(),
                         static_cast<std::uint32_t>(i), trigger_ns, s.config.stages);
    ASSERT_NE(r.odometry, nullptr);
    const OdometryState& o = *r.odometry;
    if (o.status == OdometryState::Status::tracking) {
      EXPECT_LT(i, facing_blank) << "a pose with nothing to follow";
      EXPECT_LT((o.pose.translation - truth[i].translation).norm(), 0.15) << "pair " << i;
      ++tracked;
      last_tracked = i;
      kept = o.pose;
      continue;
    }
    if (i >= facing_blank) ++lost_facing_blank;
    EXPECT_EQ(o.status, OdometryState::Status::lost) << "pair " << i;
    EXPECT_EQ(o.quality, -1);
    EXPECT_TRUE(o.pose.translation == kept.translation && o.pose.rotation == kept.rotation)
        << "pair " << i << ": the last pose tracked, kept";
  }
  std::printf("blank stretch: %zu pairs, %zu tracked (the last pair %zu), %zu lost facing blank\n",
              images.left.size(), tracked, last_tracked, lost_facing_blank);
  EXPECT_GE(tracked, 15u) << "the walk towards the textured wall";
  EXPECT_EQ(lost_facing_blank, images.left.size() - facing_blank);
}

}  // namespace
}  // namespace epipole::firmware

// The ground stage on the simulated board's floor (board/sim, scene `ground`: a floor under a
// real rig's calibration, pitched down, two boxes on it, rendered with its exact truth), and on
// the scenes without a floor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "board_scene.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "sim/sim_settings.hpp"
#include "sim/world_scene.hpp"
#include "test_paths.hpp"

namespace epipole::firmware {
namespace {

using protocol::Stage;

using Scene = test::BoardScene;

// The simulated board with scene `name` chosen, its calibration and (with `images`) its pairs.
Scene sim_scene(const std::string& name, std::vector<std::string> overrides = {},
                bool images = true) {
  return test::board_scene(name, overrides, images);
}

double radians(double degrees) {
  return degrees * std::numbers::pi / 180;
}

// The sectors whose centre's ray, level at the camera's height, meets the box's front face
// well inside its width (a sector's width in from either edge).
std::vector<int> sectors_on(const ObstacleSectors& sectors, const hal::WorldBox& box) {
  std::vector<int> on;
  const double width = sectors.field_of_view_deg() / sectors.config().columns;
  for (int k = 0; k < sectors.config().columns; ++k) {
    const double angle = radians(sectors.sector_centre_deg(k));
    const double x = box.z_m * std::tan(angle);  // where the ray meets the face's plane
    const double margin = box.z_m * std::tan(radians(width));
    if (x > box.x_m - box.width_m / 2 + margin && x < box.x_m + box.width_m / 2 - margin) {
      on.push_back(k);
    }
  }
  return on;
}

TEST(GroundScene, TheFloorIsFoundAndIsNoObstacle) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  const Scene s = sim_scene("ground");
  ASSERT_TRUE(s.rig.has_value());
  const hal::SimScene& scene = hal::sim_settings(s.config.sections).chosen();
  ASSERT_TRUE(scene.world.has_value());
  const hal::GroundTruth truth = hal::world_ground_truth(*scene.world, *s.rig);
  Pipeline pipeline(s.config, s.rig);
  ASSERT_TRUE(protocol::has_stage(pipeline.available(), Stage::ground));
  const ObstacleSectors& sectors = *pipeline.obstacle_sectors();
  ASSERT_EQ(scene.world->boxes.size(), 2u);
  const std::vector<int> near_box = sectors_on(sectors, scene.world->boxes[0]);
  const std::vector<int> far_box = sectors_on(sectors, scene.world->boxes[1]);
  ASSERT_GE(near_box.size(), 3u);
  ASSERT_GE(far_box.size(), 3u);
  const double near_m = scene.world->boxes[0].z_m, far_m = scene.world->boxes[1].z_m;
  for (std::size_t i = 0; i < s.images.left.size(); ++i) {
    const FrameResult& r = pipeline.process(s.images.left[i].view(), s.images.right[i].view(),
                                            static_cast<std::uint32_t>(i), 0, s.config.stages);
    SCOPED_TRACE("pair " + std::to_string(i));
    ASSERT_NE(r.ground, nullptr);
    ASSERT_TRUE(r.ground->flags & protocol::kGroundFound);
    EXPECT_NEAR(r.ground->height_mm, truth.height_m * 1000, 25);
    EXPECT_NEAR(r.ground->pitch_cdeg, truth.pitch_deg * 100, 100);
    EXPECT_NEAR(r.ground->roll_cdeg, truth.roll_deg * 100, 100);
    EXPECT_GT(r.ground->inliers_permille, 300);
    ASSERT_NE(r.obstacles, nullptr);
    for (const int k : near_box) {
      EXPECT_NEAR(r.obstacles->nearest_mm[k], near_m * 1000, 0.05 * near_m * 1000)
          << "sector " << k;
    }
    for (const int k : far_box) {
      EXPECT_NEAR(r.obstacles->nearest_mm[k], far_m * 1000, 0.05 * far_m * 1000) << "sector " << k;
    }
    // Nothing nearer than the first box: the floor is no obstacle.
    for (int k = 0; k < r.obstacles->count; ++k) {
      EXPECT_GE(r.obstacles->nearest_mm[k], 0.95 * near_m * 1000) << "sector " << k;
    }
  }
  std::printf("ground truth: height %.4f m, pitch %.3f deg, roll %.3f deg\n", truth.height_m,
              truth.pitch_deg, truth.roll_deg);
}

// The same floor under other mountings of the rig: heights, pitches and rolls a robot has.
TEST(GroundScene, TheFloorUnderOtherMountings) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  Scene s = sim_scene("ground", {}, false);
  const hal::SimWorld& board_world = *hal::sim_settings(s.config.sections).chosen().world;
  for (const hal::RigPose pose :
       {hal::RigPose{0.25, 20, 4}, hal::RigPose{1.2, 6, -8}, hal::RigPose{0.8, 30, 12},
        hal::RigPose{0.4, 3, 0}, hal::RigPose{1.8, 25, -3}}) {
    hal::SimWorld world = board_world;
    world.rig = pose;
    world.frames = 1;
    const hal::StereoImages images =
        hal::render_world(world, *s.rig, s.config.width(), s.config.height());
    const hal::GroundTruth truth = hal::world_ground_truth(world, *s.rig);
    Pipeline pipeline(s.config, s.rig);
    for (std::size_t i = 0; i < images.left.size(); ++i) {
      const FrameResult& r = pipeline.process(images.left[i].view(), images.right[i].view(),
                                              static_cast<std::uint32_t>(i), 0, s.config.stages);
      SCOPED_TRACE(testing::Message() << "height " << pose.height_m << " pitch " << pose.pitch_deg
                                      << " roll " << pose.roll_deg << " pair " << i);
      ASSERT_NE(r.ground, nullptr);
      ASSERT_TRUE(r.ground->flags & protocol::kGroundFound);
      EXPECT_NEAR(r.ground->height_mm, truth.height_m * 1000, 0.05 * truth.height_m * 1000);
      EXPECT_NEAR(r.ground->pitch_cdeg, truth.pitch_deg * 100, 100);
      EXPECT_NEAR(r.ground->roll_cdeg, truth.roll_deg * 100, 100);
    }
  }
}

// Without the ground stage the sectors see the floor: what the stage is for.
TEST(GroundScene, WithoutTheStageTheFloorIsAnObstacle) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  const Scene s = sim_scene("ground", {"stages.ground=false"});
  Pipeline pipeline(s.config, s.rig);
  const FrameResult& r =
      pipeline.process(s.images.left[0].view(), s.images.right[0].view(), 0, 0, s.config.stages);
  EXPECT_EQ(r.ground, nullptr);
  ASSERT_NE(r.obstacles, nullptr);
  const double near_m = hal::sim_settings(s.config.sections).chosen().world->boxes[0].z_m;
  int floor_sectors = 0;
  for (int k = 0; k < r.obstacles->count; ++k) {
    floor_sectors += r.obstacles->nearest_mm[k] < 0.9 * near_m * 1000 ? 1 : 0;
  }
  EXPECT_GT(floor_sectors, r.obstacles->count / 2);
}

// The scenes without a floor to see: no ground, or one that holds still while the rig does.
TEST(GroundScene, ScenesWithoutAFloorReportNoneOrAConsistentOne) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  for (const char* name : {"chessboard", "aloe", "faces"}) {
    SCOPED_TRACE(name);
    const Scene s = sim_scene(name);
    Pipeline pipeline(s.config, s.rig);
    std::vector<double> heights, pitches;
    for (std::size_t i = 0; i < s.images.left.size(); ++i) {
      const FrameResult& r = pipeline.process(s.images.left[i].view(), s.images.right[i].view(),
                                              static_cast<std::uint32_t>(i), 0, s.config.stages);
      ASSERT_NE(r.ground, nullptr);
      if ((r.ground->flags & protocol::kGroundFound) == 0) {
        EXPECT_EQ(r.ground->height_mm, 0);
        EXPECT_EQ(r.ground->inliers_permille, 0);
        continue;
      }
      std::printf("%s %zu: height %d mm pitch %d roll %d inliers %d permille\n", name, i,
                  r.ground->height_mm, r.ground->pitch_cdeg, r.ground->roll_cdeg,
                  r.ground->inliers_permille);
      heights.push_back(r.ground->height_mm);
      pitches.push_back(r.ground->pitch_cdeg);
    }
    std::printf("%s: a ground in %zu of %zu pairs\n", name, heights.size(), s.images.left.size());
    if (heights.size() < 2) continue;
    const auto [low, high] = std::minmax_element(heights.begin(), heights.end());
    EXPECT_LT(*high - *low, 0.1 * *high);
    const auto [least, most] = std::minmax_element(pitches.begin(), pitches.end());
    EXPECT_LT(*most - *least, 200);
  }
}

}  // namespace
}  // namespace epipole::firmware

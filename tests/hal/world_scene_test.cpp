#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/core/temporary_folder.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "error_of.hpp"
#include "ideal_rig.hpp"
#include "random_image.hpp"
#include "sim/sim_settings.hpp"
#include "sim/world_scene.hpp"

namespace epipole::hal {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

using test::ideal_rig;

// Photos of noise in a temporary folder: the textures, no data files needed.
class WorldPhotos {
 public:
  WorldPhotos() : folder_("epipole-world-test") {
    for (std::uint32_t i = 0; i < 3; ++i) {
      GrayImage photo(96, 64);
      test::fill(photo.view(), test::Pattern::noise, 11 + i);
      save_image(file(static_cast<int>(i)), photo.view());
    }
  }
  std::filesystem::path file(int i) const {
    return folder_.path() / ("photo" + std::to_string(i) + ".png");
  }

 private:
  TemporaryFolder folder_;
};

// The rig 0.5 m above a floor of 1 cm texels, looking down by `pitch_deg`.
SimWorld floor_world(const WorldPhotos& photos, double pitch_deg) {
  SimWorld world;
  world.rig.height_m = 0.5;
  world.rig.pitch_deg = pitch_deg;
  world.floor = {photos.file(0), 10};
  world.noise = 2;
  world.frames = 2;
  return world;
}

bool same_pixels(const GrayImage& a, const GrayImage& b) {
  if (a.width() != b.width() || a.height() != b.height()) return false;
  for (int y = 0; y < a.height(); ++y) {
    for (int x = 0; x < a.width(); ++x) {
      if (a(x, y) != b(x, y)) return false;
    }
  }
  return true;
}

// The mean of |a(x, y) - b(x + shift, y)| over the rectangle [x0, x1) x [y0, y1) of a.
double mean_abs_difference(const GrayImage& a, const GrayImage& b, int x0, int y0, int x1, int y1,
                           int shift = 0) {
  double sum = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) sum += std::abs(a(x, y) - b(x + shift, y));
  }
  return sum / ((x1 - x0) * (y1 - y0));
}

struct Spread {
  double mean = 0;
  double deviation = 0;
};
Spread spread_of_rows(const GrayImage& image, int y0, int y1) {
  double sum = 0;
  double squares = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = 0; x < image.width(); ++x) {
      sum += image(x, y);
      squares += image(x, y) * image(x, y);
    }
  }
  const double n = static_cast<double>(image.width()) * (y1 - y0);
  const double mean = sum / n;
  return {mean, std::sqrt(std::max(0.0, squares / n - mean * mean))};
}

// ----- The board file

// A board's sim section with a world scene; its files need not exist to be read.
const std::string kBoard = R"(sim:
  scenes:
    ground:
      world:
        rig: {height_m: 0.5, pitch_deg: 10, roll_deg: 0}
        floor: {texture: floor.png, texel_mm: 4}
        wall: {distance_m: 6, texture: wall.png, texel_mm: 6}
        boxes:
          - {at_m: [-0.35, 1.5], size_m: [0.5, 0.6, 0.4], texture: box.png, texel_mm: 1.5}
        noise: 1.5
        frames: 4
      calibration: rig.yaml
)";

// The section read as the simulated board reads it, the board file in `folder`.
std::unique_ptr<BackendSettings> read_board_sim(const std::string& text,
                                                const std::filesystem::path& folder) {
  const yaml::Fields file((folder / "board.yaml").string());
  const YAML::Node root = file.parse(text);
  return read_sim_section(root["sim"], file, {});
}

TEST(WorldScene, ReadsTheWorldOfABoardFile) {
  const TemporaryFolder folder("epipole-world-test");
  const std::unique_ptr<BackendSettings> settings = read_board_sim(kBoard, folder.path());
  const SimScene& scene = dynamic_cast<const SimSettings&>(*settings).chosen();
  ASSERT_TRUE(scene.world.has_value());
  const SimWorld& world = *scene.world;
  EXPECT_EQ(world.rig.height_m, 0.5);
  EXPECT_EQ(world.rig.pitch_deg, 10.0);
  EXPECT_EQ(world.rig.roll_deg, 0.0);
  EXPECT_EQ(world.floor.file.string(), (folder.path() / "floor.png").string());
  EXPECT_EQ(world.floor.texel_mm, 4.0);
  ASSERT_TRUE(world.wall.has_value());
  EXPECT_EQ(world.wall->distance_m, 6.0);
  EXPECT_EQ(world.wall->texture.texel_mm, 6.0);
  ASSERT_EQ(world.boxes.size(), 1u);
  const WorldBox& box = world.boxes.front();
  EXPECT_EQ(box.x_m, -0.35);
  EXPECT_EQ(box.z_m, 1.5);
  EXPECT_EQ(box.width_m, 0.5);
  EXPECT_EQ(box.height_m, 0.6);
  EXPECT_EQ(box.depth_m, 0.4);
  EXPECT_EQ(box.texture.texel_mm, 1.5);
  EXPECT_EQ(box.texture.file.string(), (folder.path() / "box.png").string());
  EXPECT_EQ(world.noise, 1.5);
  EXPECT_EQ(world.frames, 4);
  EXPECT_EQ(scene.calibration.string(), (folder.path() / "rig.yaml").string());
}

TEST(WorldScene, BoardFileErrorsNameTheKey) {
  const TemporaryFolder folder("epipole-world-test");
  // The error of kBoard with `from` replaced by `to`.
  const auto error = [&](const std::string& from, const std::string& to) {
    std::string text = kBoard;
    const std::size_t at = text.find(from);
    if (at == std::string::npos) return "(the board has no '" + from + "')";
    text.replace(at, from.size(), to);
    return test::error_of([&] { read_board_sim(text, folder.path()); });
  };
  const std::string key = "sim.scenes.ground";
  const struct {
    std::string from, to, expected;
  } cases[] = {
      {"      calibration: rig.yaml\n", "",
       key + ".calibration: a world scene needs its rig's calibration"},
      {"pitch_deg: 10", "pitch_deg: 95", key + ".world.rig.pitch_deg: 95 is outside -80..80"},
      {"roll_deg: 0", "roll_deg: -61", key + ".world.rig.roll_deg: -61 is outside -60..60"},
      {"height_m: 0.5", "height_m: 0.01", key + ".world.rig.height_m: 0.01 is outside 0.05..10"},
      {"texel_mm: 4}", "texel_mm: 4, colour: red}", "unknown key '" + key + ".world.floor.colour'"},
      {"        noise: 1.5\n", "        noise: 1.5\n        sky: blue\n",
       "unknown key '" + key + ".world.sky'"},
      {"texel_mm: 4}", "texel_mm: 0.01}", key + ".world.floor.texel_mm: 0.01 is outside 0.1..1000"},
      {"distance_m: 6", "distance_m: 0", key + ".world.wall.distance_m: 0 is outside (0, 1000]"},
      {"[0.5, 0.6, 0.4]", "[0.5, 0, 0.4]", key + ".world.boxes[0].size_m[1]: 0 is outside"},
      {"[0.5, 0.6, 0.4]", "[0.5, 0.6]", key + ".world.boxes[0].size_m: expected 3 numbers"},
      {"[-0.35, 1.5]", "[-0.35]", key + ".world.boxes[0].at_m: expected 2 numbers"},
      {"noise: 1.5", "noise: 51", key + ".world.noise: 51 is outside 0..50"},
      {"frames: 4", "frames: 65", key + ".world.frames: 65 is outside 1..64"},
      {"      world:\n", "      left: a.png\n      world:\n",
       key + ": world and left are two sources: give one"},
  };
  for (const auto& c : cases) {
    const std::string message = error(c.from, c.to);
    EXPECT_NE(message.find(c.expected), std::string::npos)
        << c.from << " -> " << c.to << ": " << message;
  }
}

// ----- The truth

TEST(WorldScene, GroundTruthIsTheRigsPose) {
  calib::StereoCalibration rig = ideal_rig();
  SimWorld world;
  world.rig.height_m = 0.7;
  const GroundTruth level = world_ground_truth(world, rig);
  EXPECT_NEAR(level.normal_down.x(), 0, 1e-12);
  EXPECT_NEAR(level.normal_down.y(), 1, 1e-12);
  EXPECT_NEAR(level.normal_down.z(), 0, 1e-12);
  EXPECT_NEAR(level.height_m, 0.7, 1e-12);
  EXPECT_NEAR(level.pitch_deg, 0, 1e-12);
  EXPECT_NEAR(level.roll_deg, 0, 1e-12);

  world.rig.pitch_deg = 10;
  world.rig.roll_deg = 5;
  const GroundTruth tilted = world_ground_truth(world, rig);
  EXPECT_NEAR(tilted.pitch_deg, 10, 1e-9);
  EXPECT_NEAR(tilted.roll_deg, 5, 1e-9);
  EXPECT_NEAR(tilted.height_m, 0.7, 1e-12);
  EXPECT_NEAR(tilted.normal_down.norm(), 1, 1e-12);
  // Looking down, the floor is below (+y) and ahead (+z); rolled right side down, to the right.
  EXPECT_GT(tilted.normal_down.y(), 0.9);
  EXPECT_GT(tilted.normal_down.z(), 0);
  EXPECT_GT(tilted.normal_down.x(), 0);

  // The truth is in the rectified frame: a level rig whose rectification turns it down by 3
  // degrees (R1 = rotation about x) sees the floor 3 degrees down.
  const double a = 3 * kDegree;
  Eigen::Matrix3d r1;
  r1 << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  rig.left.rectification = r1;
  rig.right.rectification = r1;
  world.rig.pitch_deg = 0;
  world.rig.roll_deg = 0;
  const GroundTruth rectified = world_ground_truth(world, rig);
  EXPECT_NEAR(rectified.pitch_deg, 3, 1e-9);
  EXPECT_NEAR(rectified.roll_deg, 0, 1e-9);
  EXPECT_NEAR(rectified.height_m, 0.7, 1e-12);
}

// ----- Rendering

TEST(WorldScene, RendersTheFloorAndItsTrueDisparity) {
  const WorldPhotos photos;
  const calib::StereoCalibration rig = ideal_rig();
  const SimWorld world = floor_world(photos, 10);
  const StereoImages images = render_world(world, rig, 320, 240);
  ASSERT_EQ(images.left.size(), 2u);
  ASSERT_EQ(images.right.size(), 2u);
  for (const GrayImage* image : {&images.left[0], &images.right[0]}) {
    ASSERT_EQ(image->width(), 320);
    ASSERT_EQ(image->height(), 240);
    // The horizon is at row 120 - 300 tan(10 degrees) = 67: above it nothing (black and the
    // noise), below it the floor's photo.
    const Spread sky = spread_of_rows(*image, 0, 50);
    const Spread ground = spread_of_rows(*image, 160, 240);
    EXPECT_LT(sky.mean, 3);
    EXPECT_GT(ground.mean, 60);
    EXPECT_LT(ground.mean, 200);
    EXPECT_GT(ground.deviation, 5) << "the floor's photo, not a flat grey";
  }

  // Pixel (200, 140) of the rectified left view (the raw one: an ideal rig) sees the floor.
  // Its ray (x, y, 1) in the camera's frame, whose y axis is (0, -cos p, -sin p) and z axis
  // (0, -sin p, cos p) in the world (Y up): the ray falls by y cos p + sin p per unit of depth.
  const double pitch = 10 * kDegree;
  const double y = (140 - 120) / 300.0;
  const double depth = 0.5 / (y * std::cos(pitch) + std::sin(pitch));
  const Image<float> truth = world_true_disparity(world, rig);
  ASSERT_EQ(truth.width(), 320);
  ASSERT_EQ(truth.height(), 240);
  EXPECT_NEAR(static_cast<double>(truth(200, 140)), 300 * 0.1 / depth, 1e-6);
  const TrueDepth true_depth = world_true_depth(world, world.rig, rig);
  EXPECT_NEAR(static_cast<double>(true_depth.depth_m(200, 140)), depth, 1e-6);
  // Above the horizon nothing is hit.
  EXPECT_EQ(static_cast<double>(truth(160, 10)), 0.0);
  EXPECT_EQ(static_cast<double>(true_depth.depth_m(160, 10)), 0.0);
}

TEST(WorldScene, ABoxIsWhereBothCamerasSeeIt) {
  const WorldPhotos photos;
  const calib::StereoCalibration rig = ideal_rig();
  SimWorld world = floor_world(photos, 0);
  world.noise = 0;
  world.frames = 1;
  world.boxes.push_back({0.0, 2.0, 0.6, 1.0, 0.5, {photos.file(1), 2}});
  const TrueDepth truth = world_true_depth(world, world.rig, rig);
  // The front face, 2 m ahead: disparity 300 x 0.1 / 2.
  EXPECT_NEAR(static_cast<double>(truth.depth_m(160, 120)), 2.0, 1e-6);
  EXPECT_NEAR(static_cast<double>(truth.disparity(160, 120)), 15.0, 1e-5);
  // X from -0.3 to 0.3 at 2 m: columns 115 to 205; left of it, the floor 5 m away.
  EXPECT_NEAR(static_cast<double>(truth.disparity(40, 150)), 300 * 0.1 / 5, 1e-5);

  // The front face is parallel to the image: the right camera sees each of its points 15
  // pixels to the left, through nearly the same footprint (its level of detail differs a
  // little with the angle off the axis), so the noise-free images agree there.
  const StereoImages images = render_world(world, rig, 320, 240);
  ASSERT_EQ(images.left.size(), 1u);
  EXPECT_LT(mean_abs_difference(images.left[0], images.right[0], 130, 60, 195, 180, -15), 0.5);
  // Not merely flat: the box's photo.
  EXPECT_GT(mean_abs_difference(images.left[0], images.right[0], 130, 60, 195, 180, -14), 2.0);
}

TEST(WorldScene, RendersTheSameEveryTimeFramesDifferingByTheirNoise) {
  const WorldPhotos photos;
  const calib::StereoCalibration rig = ideal_rig();
  SimWorld world = floor_world(photos, 10);
  world.wall = WorldWall{3, {photos.file(2), 5}};  // every ray meets the floor or the wall
  world.frames = 3;
  const StereoImages a = render_world(world, rig, 320, 240);
  const StereoImages b = render_world(world, rig, 320, 240);
  ASSERT_EQ(a.left.size(), 3u);
  for (std::size_t i = 0; i < a.left.size(); ++i) {
    EXPECT_TRUE(same_pixels(a.left[i], b.left[i])) << i;
    EXPECT_TRUE(same_pixels(a.right[i], b.right[i])) << i;
  }
  // Noise of sigma 2 in each frame: their difference averages 2 sigma / sqrt(pi) = 2.26.
  const double between_frames = mean_abs_difference(a.left[0], a.left[1], 0, 0, 320, 240);
  EXPECT_GT(between_frames, 1.6);
  EXPECT_LT(between_frames, 3.0);
  EXPECT_FALSE(same_pixels(a.right[0], a.right[1]));

  world.noise = 0;
  const StereoImages clean = render_world(world, rig, 320, 240);
  EXPECT_TRUE(same_pixels(clean.left[0], clean.left[2]));
  EXPECT_LT(mean_abs_difference(clean.left[0], a.left[0], 0, 0, 320, 240), 3.0);
}

TEST(WorldScene, RaysOutsideTheLensAreBlack) {
  const WorldPhotos photos;
  calib::StereoCalibration rig = ideal_rig();
  // Barrel distortion that folds at a normalised radius of 0.82 (distorted 0.54): the image's
  // corners (radius 0.67) are outside the lens's domain.
  rig.left.camera.distortion.k1 = -0.5;
  SimWorld world = floor_world(photos, 0);
  world.wall = WorldWall{3, {photos.file(2), 5}};
  world.noise = 0;
  world.frames = 1;
  const StereoImages images = render_world(world, rig, 320, 240);
  EXPECT_EQ(images.left[0](0, 0), 0);
  EXPECT_EQ(images.left[0](319, 239), 0);
  EXPECT_GT(spread_of_rows(images.left[0], 100, 140).mean, 30);
}

TEST(WorldScene, ErrorsNameTheirCause) {
  const WorldPhotos photos;
  const calib::StereoCalibration rig = ideal_rig();
  SimWorld world = floor_world(photos, 10);
  EXPECT_NE(test::error_of([&] { render_world(world, rig, 640, 480); }).find("320x240"),
            std::string::npos);
  world.floor.file = "/nonexistent/floor.png";
  EXPECT_NE(
      test::error_of([&] { render_world(world, rig, 320, 240); }).find("/nonexistent/floor.png"),
      std::string::npos);
}

TEST(WorldScene, WritesTheTruth) {
  const WorldPhotos photos;
  const TemporaryFolder folder("epipole-world-test");
  const calib::StereoCalibration rig = ideal_rig();
  SimWorld world = floor_world(photos, 10);
  world.rig.roll_deg = 5;
  world.boxes.push_back({0.0, 2.0, 0.6, 1.0, 0.5, {photos.file(1), 2}});
  const std::filesystem::path out = folder.path() / "truth";
  write_world_truth(world, rig, out);

  const YAML::Node yaml = YAML::LoadFile((out / "truth.yaml").string());
  EXPECT_NEAR(yaml["ground"]["pitch_deg"].as<double>(), 10, 1e-9);
  EXPECT_NEAR(yaml["ground"]["roll_deg"].as<double>(), 5, 1e-9);
  EXPECT_NEAR(yaml["ground"]["height_m"].as<double>(), 0.5, 1e-12);
  EXPECT_EQ(yaml["ground"]["normal_down"].size(), 3u);
  EXPECT_EQ(yaml["rig"]["pitch_deg"].as<double>(), 10.0);
  ASSERT_EQ(yaml["boxes"].size(), 1u);
  EXPECT_NEAR(yaml["boxes"][0]["front_z_m"].as<double>(), 2.0, 1e-12);
  EXPECT_NEAR(yaml["boxes"][0]["x_range_m"][0].as<double>(), -0.3, 1e-12);
  EXPECT_NEAR(yaml["boxes"][0]["x_range_m"][1].as<double>(), 0.3, 1e-12);

  const Image<std::uint16_t> png = load_gray16(out / "true_disparity.png");
  ASSERT_EQ(png.width(), 320);
  ASSERT_EQ(png.height(), 240);
  const Image<float> truth = world_true_disparity(world, rig);
  const double d = static_cast<double>(truth(160, 200));
  ASSERT_GT(d, 0);
  EXPECT_EQ(png(160, 200), static_cast<std::uint16_t>(std::lround(d * 16)));
  EXPECT_EQ(png(10, 5), 0) << "nothing is hit above the horizon (left of the box)";
}

}  // namespace
}  // namespace epipole::hal

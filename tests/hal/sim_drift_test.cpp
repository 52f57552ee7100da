// A simulated scene's right camera turned after its calibration: ramps show where each turn moves
// the picture (pitch down, roll anticlockwise, yaw left, by f tan of the angle), a lens without a
// turn leaves it as it was, and the board file's key is read and checked.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "epipole/calib/calibration.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/temporary_folder.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "error_of.hpp"
#include "ideal_rig.hpp"
#include "sim/sim_drift.hpp"
#include "sim/sim_settings.hpp"

namespace epipole::hal {
namespace {

// A pair whose right image is a ramp: its value at (x, y) is x / 2 + 10 (across) or y / 2 + 10
// (down), so a picture moved by (dx, dy) reads (x - dx) / 2 + 10.
StereoImages ramp_pair(bool across) {
  StereoImages images;
  images.left.emplace_back(320, 240);
  images.right.emplace_back(320, 240);
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      images.left.back()(x, y) = 0;
      images.right.back()(x, y) = static_cast<std::uint8_t>((across ? x : y) / 2 + 10);
    }
  }
  return images;
}

// Where the ramp's value says the picture came from (the source pixel's coordinate).
double source_of(const StereoImages& images, int x, int y) {
  return (images.right.front()(x, y) - 10) * 2.0;
}

TEST(SimDrift, EachTurnMovesThePictureByFocalLengthTimesItsTangent) {
  const calib::StereoCalibration rig = test::ideal_rig();
  const double shift = 300 * std::tan(radians(1.5));  // 7.85 pixels
  {  // pitch: the view raised, the picture lower; the centre shows what was above it
    StereoImages images = ramp_pair(false);
    drift_right_images(images, rig, {.pitch_deg = 1.5});
    EXPECT_NEAR(source_of(images, 160, 120), 120 - shift, 2.0);
    EXPECT_NEAR(source_of(images, 60, 200), 200 - shift, 2.5);
    EXPECT_EQ(images.left.front()(160, 120), 0) << "the left camera did not move";
  }
  {  // yaw: the view turned right, the picture to the left
    StereoImages images = ramp_pair(true);
    drift_right_images(images, rig, {.yaw_deg = 1.5});
    EXPECT_NEAR(source_of(images, 160, 120), 160 + shift, 2.0);
  }
  {  // roll: the centre stays, the top comes from the right, the bottom from the left
    StereoImages images = ramp_pair(true);
    drift_right_images(images, rig, {.roll_deg = 3});
    EXPECT_NEAR(source_of(images, 160, 120), 160, 2.0);
    EXPECT_NEAR(source_of(images, 160, 20), 160 + 100 * std::sin(radians(3)), 2.0);
    EXPECT_NEAR(source_of(images, 160, 220), 160 - 100 * std::sin(radians(3)), 2.0);
  }
  {  // what the old camera did not see is black
    StereoImages images = ramp_pair(false);
    drift_right_images(images, rig, {.pitch_deg = 5});
    EXPECT_EQ(images.right.front()(160, 0), 0);
  }
}

TEST(SimDrift, ALensWithoutATurnKeepsItsPicture) {
  StereoImages images = ramp_pair(true);
  const GrayImage before = images.right.front().clone();
  drift_right_images(images, test::ideal_rig(-0.2), {});
  int differ = 0;
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) differ += images.right.front()(x, y) != before(x, y) ? 1 : 0;
  }
  EXPECT_EQ(differ, 0);
}

TEST(SimDrift, ImagesOfAnotherSizeAreAnError) {
  StereoImages images;
  images.left.emplace_back(160, 120);
  images.right.emplace_back(160, 120);
  EXPECT_NE(test::error_of([&] {
              drift_right_images(images, test::ideal_rig(), {.pitch_deg = 1});
            }).find("a drift needs images of the calibration's size, 320x240; these are 160x120"),
            std::string::npos);
}

std::string drift_board_error(const std::string& scene) {
  const TemporaryFolder folder("epipole-drift-test");
  return test::error_of([&] {
    const yaml::Fields file((folder.path() / "board.yaml").string());
    const YAML::Node root = file.parse("sim:\n  scenes:\n    faces:\n" + scene);
    read_sim_section(root["sim"], file, {});
  });
}

TEST(SimDrift, TheBoardFilesKeyIsReadAndChecked) {
  const TemporaryFolder folder("epipole-drift-test");
  const yaml::Fields file((folder.path() / "board.yaml").string());
  const YAML::Node root = file.parse(
      "sim:\n  scenes:\n    faces:\n      synthesize: a.png\n      disparity: 8\n"
      "      calibration: rig.yaml\n      drift: {pitch_deg: 0.3, roll_deg: -0.2}\n");
  const auto settings = read_sim_section(root["sim"], file, {});
  const SimScene& scene = dynamic_cast<const SimSettings&>(*settings).chosen();
  ASSERT_TRUE(scene.drift.has_value());
  EXPECT_EQ(scene.drift->pitch_deg, 0.3);
  EXPECT_EQ(scene.drift->roll_deg, -0.2);
  EXPECT_EQ(scene.drift->yaw_deg, 0.0);

  const std::string source = "      synthesize: a.png\n      disparity: 8\n";
  EXPECT_NE(drift_board_error(source + "      drift: {pitch_deg: 0.3}\n")
                .find("sim.scenes.faces.drift: a drift needs the scene's calibration"),
            std::string::npos);
  const std::string calibrated = source + "      calibration: rig.yaml\n";
  EXPECT_NE(drift_board_error(calibrated + "      drift: {pitch_deg: 11}\n")
                .find("sim.scenes.faces.drift.pitch_deg: 11 is outside -10..10"),
            std::string::npos);
  EXPECT_NE(drift_board_error(calibrated + "      drift: {tilt_deg: 1}\n")
                .find("unknown key 'sim.scenes.faces.drift.tilt_deg'"),
            std::string::npos);
  EXPECT_NE(drift_board_error(calibrated + "      drift: {yaw_deg: .nan}\n").find("yaw_deg"),
            std::string::npos);
}

}  // namespace
}  // namespace epipole::hal

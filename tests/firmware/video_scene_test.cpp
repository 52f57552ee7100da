// The simulated board replaying a video (host builds: FFmpeg and the sample videos): the scene
// keys, their errors, and the frame loop running on the decoded frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/firmware/firmware.hpp"
#include "error_of.hpp"
#include "sim_rig.hpp"
#include "test_data.hpp"

namespace epipole::firmware {
namespace {

// The rig's board file with its scene replaced by `scene` (the keys of sim.scenes.test).
std::string with_scene(const test::SimRig& rig, const std::string& scene) {
  std::string text = rig.yaml();
  const std::string from = "synthesize: unused.png, disparity: 8";
  text.replace(text.find(from), from.size(), scene);
  return text;
}

using test::error_of;

struct Observer final : FrameObserver {
  std::vector<int> centre_disparity;
  Observer() { centre_disparity.reserve(64); }
  void on_frame(const FrameResult& r) override {
    centre_disparity.push_back(r.disparity(r.disparity.width() / 2, r.disparity.height() / 2));
  }
};

TEST(VideoScene, TheFrameLoopRunsOnAVideoDecodedAtStartUp) {
  test::SimRig rig;
  const std::string video = test::data_file("samples/Megamind.avi").string();
  const BoardConfig config = parse_board_config(
      with_scene(rig, "synthesize: " + video + ", disparity: 8"), rig.dir.path() / "board.yaml");
  const hal::SimScene& scene = hal::sim_settings(config.sections).chosen();
  EXPECT_EQ(scene.max_frames, 300);
  hal::StereoImages images = hal::load_scene(scene, config.width(), config.height());
  ASSERT_EQ(images.left.size(), 270u);  // every frame of the sample, fitted to 160x96
  ASSERT_EQ(images.right.size(), 270u);
  EXPECT_EQ(images.left[0].width(), 160);
  EXPECT_EQ(images.left[0].height(), 96);
  int moved = 0;  // the video moves: frames differ
  for (int y = 0; y < 96; ++y) {
    for (int x = 0; x < 160; ++x) moved += images.left[0](x, y) != images.left[200](x, y);
  }
  EXPECT_GT(moved, 500);

  Firmware fw(config);  // decodes it again, as the firmware does at start-up
  Observer observer;
  fw.frame_loop().set_observer(&observer);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(40, stop);
  EXPECT_EQ(s.frames, 40u);
  EXPECT_EQ(s.timeouts, 0u);
  ASSERT_EQ(observer.centre_disparity.size(), 40u);
  std::vector<int> d = observer.centre_disparity;
  std::nth_element(d.begin(), d.begin() + 20, d.end());
  EXPECT_NEAR(d[20], 8 * 16, 16) << "the median centre disparity is the synthesised one";
}

// A drift on a video scene turns its right camera as on an image scene: each right frame moves
// down by f tan(pitch) (the rig's f = 100 px: 2 degrees is 3.49 px), the left frames stay.
TEST(VideoScene, ADriftTurnsTheRightCameraOfEveryFrame) {
  test::SimRig rig;
  const std::string video = test::data_file("samples/Megamind.avi").string();
  const auto load = [&](const std::string& drift) {
    const BoardConfig config =
        parse_board_config(with_scene(rig, "synthesize: " + video + ", disparity: 8, " +
                                               "calibration: rig.yaml" + drift),
                           rig.dir.path() / "board.yaml");
    return hal::load_scene(hal::sim_settings(config.sections).chosen(), config.width(),
                           config.height());
  };
  const hal::StereoImages still = load("");
  const hal::StereoImages turned = load(", drift: {pitch_deg: 2}");
  ASSERT_EQ(turned.right.size(), still.right.size());
  const double expected = 100 * std::tan(2 * std::numbers::pi / 180);
  for (const std::size_t k : {std::size_t{100}, std::size_t{180}, std::size_t{260}}) {
    SCOPED_TRACE(k);
    const GrayView a = still.right[k].view(), b = turned.right[k].view();
    // The shift that matches the turned frame to the still one best, on the rows and columns
    // both keep (sum of absolute differences; a parabola through the best three).
    std::vector<double> sad;
    for (int s = 0; s <= 7; ++s) {
      double sum = 0;
      for (int y = 12; y < 84; ++y) {
        for (int x = 12; x < 148; ++x) sum += std::abs(b(x, y) - a(x, y - s));
      }
      sad.push_back(sum);
    }
    const auto best =
        static_cast<int>(std::min_element(sad.begin() + 1, sad.end() - 1) - sad.begin());
    const double l = sad[static_cast<std::size_t>(best - 1)],
                 c = sad[static_cast<std::size_t>(best)],
                 r = sad[static_cast<std::size_t>(best + 1)];
    const double shift = best + 0.5 * (l - r) / (l - 2 * c + r);
    EXPECT_NEAR(shift, expected, 0.3) << "down, by f tan(pitch)";
    EXPECT_TRUE(std::equal(still.left[k].view().row(0), still.left[k].view().row(0) + 160,
                           turned.left[k].view().row(0)))
        << "the left camera did not move";
  }
}

TEST(VideoScene, SideBySideAndStereoVideosAndTheirErrors) {
  test::SimRig rig;
  const std::string megamind = test::data_file("samples/Megamind.avi").string();
  const std::string vtest = test::data_file("samples/vtest.avi").string();
  const auto load = [&](const std::string& scene) {
    const BoardConfig config =
        parse_board_config(with_scene(rig, scene), rig.dir.path() / "board.yaml");
    return hal::load_scene(hal::sim_settings(config.sections).chosen(), config.width(),
                           config.height());
  };
  const hal::StereoImages sbs = load("side_by_side: " + megamind + ", max_frames: 270");
  ASSERT_EQ(sbs.left.size(), 270u);
  EXPECT_EQ(sbs.right[5].width(), 160);
  const hal::StereoImages pair = load("left: " + megamind + ", right: " + megamind);
  ASSERT_EQ(pair.left.size(), 270u);

  struct Case {
    std::string scene;
    std::string expected;
  };
  const Case cases[] = {
      {"side_by_side: " + megamind + ", left: " + megamind,
       "sim.scenes.test: side_by_side and left are two sources"},
      {"synthesize: " + megamind + ", disparity: 8, max_frames: 0",
       "sim.scenes.test.max_frames: 0 is outside 1..100000"},
      {"synthesize: " + megamind + ", disparity: 8, max_frames: 10",
       "sim.scenes.test.synthesize: " + megamind + ": more than 10 frames (max_frames)"},
      {"side_by_side: " + vtest + ", max_frames: 10",
       "sim.scenes.test.side_by_side: " + vtest + ": more than 10 frames"},
      {"left: " + megamind + ", right: " + vtest, "is 768x576 but"},
      {"left: " + megamind + ", right: [a.png]",
       "sim.scenes.test: left and right must each be one video file"},
      {"side_by_side: missing.mp4", "sim.scenes.test.side_by_side: "},
  };
  for (const Case& c : cases) {
    const std::string error = error_of([&] { load(c.scene); });
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.scene << ": got '" << error << "'";
  }
  EXPECT_NE(error_of([&] { load("side_by_side: missing.mp4"); }).find("missing.mp4: no such file"),
            std::string::npos);
}

}  // namespace
}  // namespace epipole::firmware

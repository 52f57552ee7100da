#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <string>

#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "sim/sim.hpp"
#include "sim/sim_files.hpp"

namespace epipole::hal {
namespace {

std::filesystem::path temp_dir() {
  const auto dir =
      std::filesystem::temp_directory_path() / ("epipole_sim_files_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(SimFiles, ReplaysPairsFromADirectory) {
  const auto dir = temp_dir();
  for (int i = 0; i < 3; ++i) {
    GrayImage l(40, 20), r(40, 20);
    for (int y = 0; y < 20; ++y) {
      for (int x = 0; x < 40; ++x) {
        l(x, y) = static_cast<std::uint8_t>(i * 10 + x);
        r(x, y) = static_cast<std::uint8_t>(i * 10 + y);
      }
    }
    save_image(dir / ("left_" + std::to_string(i) + ".png"), l.view());
    save_image(dir / ("right_" + std::to_string(i) + ".pgm"), r.view());
  }
  StereoImages images = load_stereo_directory(dir);
  ASSERT_EQ(images.left.size(), 3u);
  SimBoard board(30.0, std::move(images.left), std::move(images.right));
  CameraConfig config;
  config.device = "left";
  config.width = 40;
  config.height = 20;
  config.trigger = TriggerMode::external;
  SimCamera left(config, board.left, board.clock);
  board.trigger.connect(left);
  board.trigger.start();
  left.start();
  for (int i = 0; i < 4; ++i) {
    const AcquireResult a = left.acquire(100'000'000);
    ASSERT_EQ(a.status, AcquireStatus::ok);
    EXPECT_EQ(a.frame.gray(7, 3), (i % 3) * 10 + 7);
    left.release(a.frame);
  }
  const StereoImages synth = synthesize_stereo(dir / "left_1.png", 5);
  EXPECT_EQ(synth.right.front()(0, 0), 10 + 5);
  std::filesystem::remove_all(dir);
}

TEST(SimFiles, ErrorsNameTheFile) {
  try {
    load_stereo_pairs({"/nonexistent/left.png"}, {"/nonexistent/right.png"});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/left.png"), std::string::npos);
  }
  EXPECT_THROW(load_stereo_directory("/nonexistent-dir"), Error);
}

}  // namespace
}  // namespace epipole::hal

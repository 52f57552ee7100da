// A recording replayed as a scene reproduces what was recorded: the firmware records every pair
// (raw images, calibration, results), the board's calibration then changes, and the simulated
// board replays the recording (its raw pairs, rectified with the calibration it carries). Every
// pair the replay records is one of the first recording's, with the same rectified images,
// disparity, depth and sparse points, byte for byte.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "epipole/core/mcap_reader.hpp"
#include "epipole/firmware/firmware.hpp"
#include "error_of.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware {
namespace {

constexpr const char* kCompared[] = {"left/image_rect", "right/image_rect", "disparity",
                                     "depth",           "features",         "left/camera_info"};

// A recording's pairs: by their raw left and right images, each compared topic's message with its
// stamps zeroed (a replay runs at another time; a disparity image has its image's stamp too).
struct Pairs {
  std::map<std::string, std::map<std::string, std::string>> by_raw;
  std::size_t recorded = 0;  // pairs in the file (the same images come back)
};

Pairs read_pairs(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(folder)) files.push_back(e.path());
  EXPECT_EQ(files.size(), 1u) << folder;
  if (files.empty()) return {};
  std::map<std::uint16_t, std::string> topics;
  std::map<std::string, std::map<std::string, std::string>> by_stamp;
  mcap::Visitor visit;
  visit.channel = [&](std::uint16_t id, const mcap::Channel& c) {
    topics[id] = c.topic.substr(c.topic.find('/', 1) + 1);  // without the namespace
  };
  visit.message = [&](const mcap::Message& m) {
    if (m.data.size() < 12) return;
    const std::string stamp(m.data.begin() + 4, m.data.begin() + 12);
    std::string message(m.data.begin(), m.data.end());
    for (std::size_t at = 0; (at = message.find(stamp, at)) != std::string::npos; at += 8) {
      message.replace(at, 8, 8, '\0');
    }
    by_stamp[stamp][topics[m.channel]] = std::move(message);
  };
  EXPECT_TRUE(mcap::scan_file(files.front(), visit).complete);
  Pairs pairs;
  for (auto& [stamp, messages] : by_stamp) {
    if (!messages.contains("left/image_raw")) continue;  // the rig's transforms, health
    ++pairs.recorded;
    pairs.by_raw[messages["left/image_raw"] + messages["right/image_raw"]] = std::move(messages);
  }
  return pairs;
}

calib::StereoCalibration distorted_rig(const test::SimRig& rig) {
  calib::StereoCalibration c =
      test::ideal_rig(rig.width, rig.height, test::SimRig::kFocal, test::SimRig::kBaseline);
  c.left.camera.distortion = {-0.08, 0.01, 0, 0, 0};
  c.right.camera.distortion = {-0.06, 0.01, 0, 0, 0};
  return c;
}

TEST(Replay, ARecordingReplayedAsASceneReproducesTheRecordedResults) {
  test::SimRig rig(160, 96, 8);
  calib::save_calibration(rig.dir.path() / "rig.yaml", distorted_rig(rig));
  const std::string recording_output =
      "outputs: {mcap: {directory: %s, continuous: true, every: 1}}\n";
  const auto recording_into = [&](const std::string& folder) {
    std::string text = recording_output;
    text.replace(text.find("%s"), 2, folder);
    return text;
  };
  {
    BoardConfig config = rig.parse(recording_into("recorded"));
    config.stages |= protocol::stage_bit(protocol::Stage::sparse);
    Firmware fw(rig.replaying(config, 4));
    const std::atomic<bool> stop{false};
    const RunSummary s = fw.run(16, stop);
    ASSERT_EQ(s.outputs.at(0).failures, 0u);
  }
  const Pairs recorded = read_pairs(rig.dir.path() / "recorded");
  ASSERT_EQ(recorded.by_raw.size(), 4u) << "the four images";

  // The board's calibration changes: the replay rectifies with the recording's own.
  calib::save_calibration(rig.dir.path() / "rig.yaml",
                          test::ideal_rig(rig.width, rig.height, 90, 0.12));
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(rig.dir.path() / "recorded")) {
    files.push_back(e.path());
  }
  std::ofstream(rig.dir.path() / "board.yaml") << rig.yaml(recording_into("replayed"));
  BoardConfig config = load_board_config(
      rig.dir.path() / "board.yaml",
      std::vector<std::string>{"sim.scenes.replay.recording=" + files.at(0).string(),
                               "stages.sparse=true"},
      std::vector<hal::BackendOption>{{"scene", "replay"}});
  Firmware fw(config);
  ASSERT_TRUE(fw.calibration());
  EXPECT_DOUBLE_EQ(fw.calibration()->left.camera.distortion.k1, -0.08) << "the recording's own";
  EXPECT_EQ(hal::simulated_board(fw.board().hardware())->scene_images(), recorded.recorded);
  const std::atomic<bool> stop{false};
  fw.run(recorded.recorded, stop);

  const Pairs replayed = read_pairs(rig.dir.path() / "replayed");
  EXPECT_EQ(replayed.by_raw.size(), 4u);
  for (const auto& [raw, messages] : replayed.by_raw) {
    const auto original = recorded.by_raw.find(raw);
    ASSERT_NE(original, recorded.by_raw.end()) << "a replayed pair is a recorded pair";
    for (const char* topic : kCompared) {
      ASSERT_TRUE(messages.contains(topic)) << topic;
      EXPECT_TRUE(messages.at(topic) == original->second.at(topic)) << topic << " differs";
    }
  }
}

TEST(Replay, WhatIsNotARecordingOfPairsIsAClearError) {
  test::SimRig rig(96, 64, 6);
  std::ofstream(rig.dir.path() / "board.yaml") << rig.yaml();
  std::ofstream(rig.dir.path() / "text.mcap") << "not a recording";
  const auto error = [&](const std::string& recording) {
    return test::error_of([&] {
      Firmware fw(
          load_board_config(rig.dir.path() / "board.yaml",
                            std::vector<std::string>{"sim.scenes.replay.recording=" + recording},
                            std::vector<hal::BackendOption>{{"scene", "replay"}}));
    });
  };
  const std::string text = (rig.dir.path() / "text.mcap").string();
  EXPECT_NE(error(text).find(text + ": not an MCAP file"), std::string::npos) << error(text);
  const std::string missing = (rig.dir.path() / "missing.mcap").string();
  EXPECT_NE(error(missing).find(missing + ": cannot open"), std::string::npos) << error(missing);
  // A recording with no raw images: one whose image topics are only the rectified ones.
  {
    mcap::Writer w({{"sensor_msgs/msg/Image", "ros2msg", ""}},
                   {{1, "/epipole/left/image_rect", "cdr", {}}}, 1024, 1024);
    w.open(rig.dir.path() / "rect.mcap", "test");
    w.close();
  }
  const std::string rect = (rig.dir.path() / "rect.mcap").string();
  EXPECT_NE(
      error(rect).find("sim.scenes.replay.recording: " + rect + ": no sensor_msgs/Image topics"),
      std::string::npos)
      << error(rect);
}

}  // namespace
}  // namespace epipole::firmware

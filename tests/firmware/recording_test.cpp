// The recording output as its users read it: the firmware on the simulated board records into
// MCAP, and the MCAP project's own reader with Foxglove's ROS 2 decoder (tests/clients) reads
// every record and decodes every message from the schemas in the file. What they decode must be
// what the pipeline computed: the images, the disparity, the depth (the disparity through Q), the
// camera parameters (the calibration), the sparse points, health.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>

#include "epipole/calib/triangulation.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/vision/stereo.hpp"
#include "ros_message_checks.hpp"
#include "sim_rig.hpp"
#include "test_clients.hpp"

namespace epipole::firmware {
namespace {

using nlohmann::json;

json read_recording(const std::filesystem::path& file) {
  const test::ToolResult read = test::run_client("mcap-read.mjs", file.string() + " 6");
  EXPECT_EQ(read.exit_code, 0) << read.out;
  return json::parse(read.out);
}

std::filesystem::path only_recording(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(folder)) files.push_back(e.path());
  EXPECT_EQ(files.size(), 1u);
  return files.empty() ? std::filesystem::path() : files.front();
}

TEST(Recording, AnIndependentReaderDecodesWhatThePipelineComputed) {
  ASSERT_TRUE(test::clients_installed()) << "the test clients are not installed: scripts/setup.sh";
  test::SimRig rig(96, 64, 6);
  BoardConfig config =
      rig.parse("outputs: {mcap: {directory: recordings, continuous: true, every: 1}}\n");
  config.stages |= protocol::stage_bit(protocol::Stage::sparse);
  Firmware fw(rig.replaying(config, 3));
  Kept kept;
  fw.frame_loop().set_observer(&kept);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(45, stop);  // past the first health message
  ASSERT_EQ(s.outputs.size(), 1u);
  const OutputReport& mcap = s.outputs[0];
  EXPECT_EQ(mcap.name, "mcap");
  EXPECT_EQ(mcap.failures, 0u);
  EXPECT_EQ(mcap.delivered + mcap.dropped, 45u);
  ASSERT_GT(mcap.delivered, 0u);

  const json r = read_recording(only_recording(rig.dir.path() / "recordings"));
  EXPECT_EQ(r["profile"], "ros2");
  const json& counts = r["statistics"]["channel_message_counts"];
  for (const char* topic :
       {"/epipole/left/image_rect", "/epipole/right/image_rect", "/epipole/left/image_raw",
        "/epipole/right/image_raw", "/epipole/left/camera_info", "/epipole/right/camera_info",
        "/epipole/disparity", "/epipole/depth", "/epipole/features"}) {
    EXPECT_EQ(counts[topic], mcap.delivered) << topic;
  }
  EXPECT_EQ(counts["/tf_static"], 1);
  EXPECT_GE(counts["/diagnostics"], 1);
  EXPECT_GE(r["chunk_indexes"].get<int>(), 1);

  // The calibration rides along, whole.
  ASSERT_EQ(r["attachments"].size(), 1u);
  const calib::StereoCalibration attached =
      calib::parse_calibration(r["attachments"][0]["text"].get<std::string>(), "attached");
  const calib::StereoCalibration& rig_calibration = *fw.calibration();
  EXPECT_TRUE(attached.Q.isApprox(rig_calibration.Q));
  const RosChecks checks = check_ros_messages(r["messages"], kept, rig_calibration, rig);
  EXPECT_GT(checks.depths, 0);
  EXPECT_GT(checks.features, 0);
  EXPECT_GT(checks.calibration, 0) << "the calibration's health beside health";
  EXPECT_EQ(checks.unmatched, 0) << "a recording holds every message of each pair";
}

// A long recording is a ring of files: each closed file is whole (summary, indexes) and the
// oldest go when the folder's bound is reached; failures none, pairs all recorded or counted.
TEST(Recording, ALongRecordingIsARingOfWholeFiles) {
  ASSERT_TRUE(test::clients_installed()) << "the test clients are not installed: scripts/setup.sh";
  test::SimRig rig(320, 240, 8);
  const BoardConfig config = rig.parse(
      "outputs: {mcap: {directory: recordings, continuous: true, every: 1, file_mb: 1, "
      "total_mb: 3, "
      "min_free_mb: 0}}\n");
  Firmware fw(rig.replaying(config, 3));
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(60, stop);
  const OutputReport& mcap = s.outputs.at(0);
  EXPECT_EQ(mcap.failures, 0u);
  EXPECT_EQ(mcap.delivered + mcap.dropped, 60u);
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(rig.dir.path() / "recordings")) {
    files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 2u);
  std::uint64_t bytes = 0;
  for (const std::filesystem::path& file : files) {
    bytes += std::filesystem::file_size(file);
    const json r = read_recording(file);
    EXPECT_GT(r["statistics"]["channel_message_counts"]["/epipole/left/image_rect"], 0) << file;
    EXPECT_EQ(r["statistics"]["channel_message_counts"]["/tf_static"], 1) << "in every file";
    EXPECT_EQ(r["attachments"].size(), 1u) << "the calibration in every file";
  }
  EXPECT_LE(bytes, 3u << 20) << "the ring's bound";
  EXPECT_GT(bytes, 1u << 20) << "the oldest went only to make room";
}

}  // namespace
}  // namespace epipole::firmware

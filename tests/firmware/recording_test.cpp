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
#include "sim_rig.hpp"
#include "test_clients.hpp"

namespace epipole::firmware {
namespace {

using nlohmann::json;

std::uint32_t fnv1a(GrayView image) {
  std::uint32_t h = 0x811c9dc5u;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      h ^= image.row(y)[x];
      h *= 0x01000193u;
    }
  }
  return h;
}

// What the pipeline made of each pair, by the hash of its rectified left image.
struct Kept final : FrameObserver {
  struct Pair {
    Image<std::int16_t> disparity;
    std::vector<SparsePoint> points;
  };
  std::map<std::uint32_t, Pair> by_left;
  void on_frame(const FrameResult& r) override {
    Pair p{Image<std::int16_t>(r.disparity.width(), r.disparity.height()),
           {r.points.begin(), r.points.end()}};
    for (int y = 0; y < r.disparity.height(); ++y) {
      std::copy_n(r.disparity.row(y), r.disparity.width(), p.disparity.view().row(y));
    }
    by_left.insert_or_assign(fnv1a(r.left), std::move(p));
  }
};

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
  BoardConfig config = rig.parse("outputs: {mcap: {directory: recordings, every: 1}}\n");
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
  const calib::Triangulator q(rig_calibration);

  std::map<std::string, json> frame_of_time;  // a pair's left image_rect, by its log time
  int checked_depths = 0, checked_points = 0;
  for (const json& m : r["messages"]) {
    const std::string topic = m["topic"];
    const std::string time = m["log_time"];
    if (topic != "/diagnostics") {
      EXPECT_EQ(std::to_string(m["stamp"][0].get<std::int64_t>() * 1'000'000'000 +
                               m["stamp"][1].get<std::int64_t>()),
                time)
          << topic << ": the header's stamp is the log time";
    }
    if (topic == "/epipole/left/image_rect") {
      EXPECT_EQ(m["frame_id"], "epipole_left_optical_frame");
      EXPECT_EQ(m["encoding"], "mono8");
      ASSERT_TRUE(kept.by_left.count(m["hash"])) << "a left image the pipeline rectified";
      frame_of_time[time] = m;
    } else if (topic == "/epipole/left/camera_info" || topic == "/epipole/right/camera_info") {
      const calib::CameraCalibration& cam =
          topic == "/epipole/left/camera_info" ? rig_calibration.left : rig_calibration.right;
      for (int i = 0; i < 12; ++i) {
        EXPECT_DOUBLE_EQ(m["p"][i].get<double>(), cam.projection(i / 4, i % 4)) << topic;
      }
      EXPECT_DOUBLE_EQ(m["k"][0].get<double>(), cam.projection(0, 0));
      EXPECT_EQ(m["width"], rig.width);
    } else if (topic == "/epipole/disparity" || topic == "/epipole/depth" ||
               topic == "/epipole/features") {
      ASSERT_TRUE(frame_of_time.count(time)) << topic << " after its pair's left image";
      const Kept::Pair& pair = kept.by_left.at(frame_of_time[time]["hash"]);
      if (topic == "/epipole/features") {
        ASSERT_EQ(m["width"], pair.points.size());
        for (std::size_t i = 0; i < pair.points.size(); ++i) {
          EXPECT_FLOAT_EQ(m["points"][i][2].get<float>(), pair.points[i].z);
          ++checked_points;
        }
        continue;
      }
      const json& image = topic == "/epipole/disparity" ? m["image"] : m;
      if (topic == "/epipole/disparity") {
        EXPECT_FLOAT_EQ(m["f"].get<float>(),
                        static_cast<float>(rig_calibration.left.projection(0, 0)));
        EXPECT_NEAR(m["t"].get<double>(), test::SimRig::kBaseline, 1e-6);
        EXPECT_EQ(image["encoding"], "32FC1");
      } else {
        EXPECT_EQ(image["encoding"], "16UC1");
      }
      for (const json& sample : image["samples"]) {
        const int x = sample[0], y = sample[1];
        const std::int16_t d16 = pair.disparity(x, y);
        const bool valid = d16 != vision::kInvalidDisparity && d16 > 0;
        if (topic == "/epipole/disparity") {
          EXPECT_FLOAT_EQ(sample[2].get<float>(), valid ? d16 / 16.0f : -1.0f) << x << "," << y;
        } else {
          const double z_mm = valid ? q.point(x, y, d16 / 16.0).z() * 1000.0 : 0.0;
          EXPECT_NEAR(sample[2].get<double>(), z_mm, 0.5) << x << "," << y;
          checked_depths += valid;
        }
      }
    } else if (topic == "/diagnostics") {
      const json& status = m["status"][0];
      EXPECT_EQ(status["name"], "epipole: health");
      EXPECT_EQ(status["hardware_id"], "test-sim");
      EXPECT_GT(std::stoi(status["values"]["frames"].get<std::string>()), 0);
      EXPECT_TRUE(status["values"].contains("outputs_dropped"));
    } else if (topic == "/tf_static") {
      ASSERT_EQ(m["transforms"].size(), 2u);
      EXPECT_EQ(m["transforms"][1]["child"], "epipole_right_optical_frame");
      EXPECT_NEAR(m["transforms"][1]["translation"]["x"].get<double>(), test::SimRig::kBaseline,
                  1e-9);
    }
  }
  EXPECT_GT(checked_depths, 0);
  EXPECT_GT(checked_points, 0);
}

// A long recording is a ring of files: each closed file is whole (summary, indexes) and the
// oldest go when the folder's bound is reached; failures none, pairs all recorded or counted.
TEST(Recording, ALongRecordingIsARingOfWholeFiles) {
  ASSERT_TRUE(test::clients_installed()) << "the test clients are not installed: scripts/setup.sh";
  test::SimRig rig(320, 240, 8);
  const BoardConfig config = rig.parse(
      "outputs: {mcap: {directory: recordings, every: 1, file_mb: 1, total_mb: 3, "
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

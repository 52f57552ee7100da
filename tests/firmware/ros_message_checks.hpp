#pragma once

// What the ROS 2 messages of the firmware's outputs must hold, however they were carried (a
// recording read by the MCAP project's reader, the DDS topics a subscriber took): the messages
// as tests/clients/mcap-read.mjs and epipole-ros2-listener print them, checked against what the
// pipeline computed for each pair (kept by an observer, found by the hash of its left image).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "epipole/calib/triangulation.hpp"
#include "epipole/firmware/frame_loop.hpp"
#include "epipole/vision/stereo.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware {

using nlohmann::json;

inline std::uint32_t fnv1a(GrayView image) {
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
    std::vector<vision::Detection> detections;
    std::vector<DetectionDepth> depths;
  };
  std::map<std::uint32_t, Pair> by_left;
  void on_frame(const FrameResult& r) override {
    Pair p{Image<std::int16_t>(r.disparity.width(), r.disparity.height()),
           {r.points.begin(), r.points.end()},
           {r.detections.begin(), r.detections.end()},
           {r.detection_depths.begin(), r.detection_depths.end()}};
    for (int y = 0; y < r.disparity.height(); ++y) {
      std::copy_n(r.disparity.row(y), r.disparity.width(), p.disparity.view().row(y));
    }
    by_left.insert_or_assign(fnv1a(r.left), std::move(p));
  }
};

// What was checked, value by value.
struct RosChecks {
  int depths = 0;       // depth pixels with a disparity
  int points = 0;       // points of the organised cloud with a disparity
  int features = 0;     // sparse points
  int boxes = 0;        // detections drawn
  int health = 0;       // diagnostics statuses of health
  int calibration = 0;  // and of the calibration's health
  int unmatched = 0;    // messages of pairs whose left image is not among the messages
};

// The statuses of a DiagnosticArray: health, then the calibration's health when the sparse stage
// has measured the rig, each field of the protocol's message a key.
inline void check_diagnostics(const json& statuses, RosChecks& checks) {
  ASSERT_GE(statuses.size(), 1u);
  ASSERT_LE(statuses.size(), 2u);
  const json& health = statuses[0];
  EXPECT_EQ(health["name"], "epipole: health");
  EXPECT_EQ(health["hardware_id"], "test-sim");
  EXPECT_GT(std::stoi(health["values"]["frames"].get<std::string>()), 0);
  EXPECT_TRUE(health["values"].contains("outputs_dropped"));
  ++checks.health;
  if (statuses.size() < 2) return;
  const json& calibration = statuses[1];
  EXPECT_EQ(calibration["name"], "epipole: calibration");
  EXPECT_EQ(calibration["hardware_id"], "test-sim");
  const json& v = calibration["values"];
  for (const char* key :
       {"matches", "median_offset_centipx", "p90_offset_centipx", "flags", "window_pairs",
        "pitch_mdeg", "roll_mdeg", "pitch_sigma_mdeg", "roll_sigma_mdeg", "corrections",
        "corrected_pitch_mdeg", "corrected_roll_mdeg"}) {
    EXPECT_TRUE(v.contains(key)) << key;
  }
  if (!v.contains("matches") || !v.contains("median_offset_centipx")) return;
  EXPECT_GT(std::stoi(v["matches"].get<std::string>()), 0) << "sent only with matches";
  const int offset = std::stoi(v["median_offset_centipx"].get<std::string>());
  EXPECT_EQ(calibration["level"], std::abs(offset) >= 50 ? 1 : 0) << "WARN from half a pixel";
  char rows[48];
  std::snprintf(rows, sizeof rows, "rows %+.2f px off", offset / 100.0);
  EXPECT_TRUE(calibration["message"].get<std::string>().starts_with(rows))
      << calibration["message"];
  ++checks.calibration;
}

// Every message: the stamps, the frames, the values against the pipeline's.
inline RosChecks check_ros_messages(const json& messages, const Kept& kept,
                                    const calib::StereoCalibration& rig_calibration,
                                    const test::SimRig& rig) {
  const calib::Triangulator q(rig_calibration);

  // Each pair's left image_rect by its time: the pair's other messages carry the same.
  std::map<std::string, json> frame_of_time;
  for (const json& m : messages) {
    if (m["topic"] == "/epipole/left/image_rect" && kept.by_left.count(m["hash"])) {
      frame_of_time[m["log_time"].get<std::string>()] = m;
    }
  }
  RosChecks checks;
  for (const json& m : messages) {
    const std::string topic = m["topic"];
    const std::string time = m["log_time"];
    if (topic != "/diagnostics" && !m["stamp"].is_null()) {
      EXPECT_EQ(std::to_string(m["stamp"][0].get<std::int64_t>() * 1'000'000'000 +
                               m["stamp"][1].get<std::int64_t>()),
                time)
          << topic << ": the header's stamp is the log time";
    }
    if (topic == "/epipole/left/image_rect") {
      EXPECT_EQ(m["frame_id"], "epipole_left_optical_frame");
      EXPECT_EQ(m["encoding"], "mono8");
      EXPECT_TRUE(kept.by_left.count(m["hash"])) << "a left image the pipeline rectified";
      if (!kept.by_left.count(m["hash"])) continue;
    } else if (topic == "/epipole/left/camera_info" || topic == "/epipole/right/camera_info") {
      const calib::CameraCalibration& cam =
          topic == "/epipole/left/camera_info" ? rig_calibration.left : rig_calibration.right;
      for (int i = 0; i < 12; ++i) {
        EXPECT_DOUBLE_EQ(m["p"][i].get<double>(), cam.projection(i / 4, i % 4)) << topic;
      }
      EXPECT_DOUBLE_EQ(m["k"][0].get<double>(), cam.projection(0, 0));
      EXPECT_EQ(m["width"], rig.width);
    } else if (topic == "/epipole/points") {
      if (!frame_of_time.count(time)) {  // its pair's left image was not taken
        ++checks.unmatched;
        continue;
      }
      const Kept::Pair& pair = kept.by_left.at(frame_of_time[time]["hash"]);
      const int step = rig.width / m["width"].get<int>();
      EXPECT_EQ(m["height"], rig.height / step);
      EXPECT_FALSE(m["is_dense"].get<bool>());
      for (std::size_t i = 0; i < m["points"].size(); ++i) {
        const int x = static_cast<int>(i) % m["width"].get<int>() * step;
        const int y = static_cast<int>(i) / m["width"].get<int>() * step;
        const std::int16_t d16 = pair.disparity(x, y);
        const json& point = m["points"][i];
        if (d16 == vision::kInvalidDisparity || d16 <= 0) {
          EXPECT_TRUE(point[2].is_null()) << x << "," << y << ": no disparity, no point";
          continue;
        }
        const Eigen::Vector3d expected = q.point(x, y, d16 / 16.0);
        EXPECT_NEAR(point[0].get<double>(), expected.x(), 1e-4 * std::abs(expected.z()));
        EXPECT_NEAR(point[2].get<double>(), expected.z(), 1e-4 * std::abs(expected.z()));
        ++checks.points;
      }
    } else if (topic == "/epipole/disparity" || topic == "/epipole/depth" ||
               topic == "/epipole/features") {
      if (!frame_of_time.count(time)) {  // its pair's left image was not taken
        ++checks.unmatched;
        continue;
      }
      const Kept::Pair& pair = kept.by_left.at(frame_of_time[time]["hash"]);
      if (topic == "/epipole/features") {
        EXPECT_EQ(m["width"], pair.points.size());
        if (m["width"] != pair.points.size()) continue;
        for (std::size_t i = 0; i < pair.points.size(); ++i) {
          EXPECT_FLOAT_EQ(m["points"][i][2].get<float>(), pair.points[i].z);
          ++checks.features;
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
          checks.depths += valid;
        }
      }
    } else if (topic == "/epipole/detections") {
      if (!frame_of_time.count(time)) {
        ++checks.unmatched;
        continue;
      }
      const Kept::Pair& pair = kept.by_left.at(frame_of_time[time]["hash"]);
      EXPECT_EQ(m["circles"], 0);
      EXPECT_EQ(m["boxes"].size(), pair.detections.size());
      EXPECT_EQ(m["texts"].size(), pair.detections.size());
      if (m["boxes"].size() != pair.detections.size()) continue;
      for (std::size_t i = 0; i < pair.detections.size(); ++i) {
        const vision::Detection& d = pair.detections[i];
        const json& box = m["boxes"][i];
        EXPECT_EQ(box["type"], 2) << "LINE_LOOP";
        EXPECT_EQ(box["points"], json::parse(cat("[[", d.x, ",", d.y, "],[", d.x + d.width, ",",
                                                 d.y, "],[", d.x + d.width, ",", d.y + d.height,
                                                 "],[", d.x, ",", d.y + d.height, "]]")));
        char label[32] = "depth unknown";
        if (i < pair.depths.size() && pair.depths[i].valid) {
          std::snprintf(label, sizeof label, "%.2f m", pair.depths[i].depth);
        }
        EXPECT_EQ(m["texts"][i]["text"], label);
        ++checks.boxes;
      }
    } else if (topic == "/diagnostics") {
      check_diagnostics(m["status"], checks);
    } else if (topic == "/tf_static") {
      EXPECT_EQ(m["transforms"].size(), 2u);
      if (m["transforms"].size() != 2u) continue;
      EXPECT_EQ(m["transforms"][1]["child"], "epipole_right_optical_frame");
      EXPECT_NEAR(m["transforms"][1]["translation"]["x"].get<double>(), test::SimRig::kBaseline,
                  1e-9);
    }
  }
  return checks;
}

}  // namespace epipole::firmware

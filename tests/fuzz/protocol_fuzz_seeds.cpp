// Writes the seed corpora of the serial-protocol fuzzers, made by this build's encoders so that
// a change to the protocol never leaves the seeds stale:
//   protocol_fuzz_seeds NATIVE_DIR MAVLINK_DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "epipole/firmware/protocol/codec.hpp"
#include "epipole/firmware/protocol/mavlink.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;
namespace fs = std::filesystem;
using namespace epipole;

void append(Bytes& to, const protocol::Message& message, std::uint16_t sequence) {
  Bytes frame(protocol::kMaxFrameSize);
  frame.resize(protocol::encode_frame(message, sequence, frame));
  to.insert(to.end(), frame.begin(), frame.end());
}

void write(const fs::path& file, const Bytes& bytes) {
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

void native_seeds(const fs::path& dir) {
  protocol::Health health;
  health.uptime_ms = 1500;
  health.frames = 45;
  health.fps_centi = 3000;
  health.flags = protocol::kHealthNotCalibrated;
  Bytes one;
  append(one, health, 1);
  write(dir / "health", one);

  protocol::Detections detections;
  detections.frame = 7;
  detections.count = 2;
  detections.items[0] = {10, 20, 30, 40, 5, 1500};
  detections.items[1] = {100, 120, 50, 50, 3, protocol::kUnknownDepth};
  protocol::Obstacles obstacles;
  obstacles.frame = 7;
  obstacles.field_of_view_centideg = 9000;
  obstacles.count = 4;
  obstacles.nearest_mm = {1200, protocol::kUnknownDepth, 800, 20000};
  protocol::Points points;
  points.frame = 7;
  points.count = 2;
  points.items[0] = {160, 320, 100, -50, 2000};
  points.items[1] = {800, 640, -300, 20, 4000};
  protocol::FrameSummary summary{
      7, 233'000'000, 4100, 300, 290, 870, 2, 2, protocol::kFrameTriggerFromCapture};
  Bytes pair;
  append(pair, summary, 2);
  append(pair, detections, 3);
  append(pair, obstacles, 4);
  append(pair, points, 5);
  protocol::DepthGrid grid;
  grid.frame = 7;
  grid.field_of_view_centideg = 9000;
  grid.vertical_field_of_view_centideg = 6000;
  grid.columns = 3;
  grid.count = 6;
  grid.nearest_mm = {1200, protocol::kUnknownDepth, 800, 20000, 650, 3000};
  append(pair, grid, 6);
  protocol::Odometry odometry;
  odometry.frame = 7;
  odometry.status = protocol::OdometryStatus::tracking;
  odometry.quality = 80;
  odometry.z_mm = 1500;
  odometry.qw_e9 = 999'000'000;
  odometry.qy_e9 = 44'710'000;
  odometry.features = 400;
  odometry.tracked = 300;
  odometry.inliers = 280;
  append(pair, odometry, 7);
  write(dir / "frame_detections_obstacles_points", pair);

  Bytes commands;
  append(commands, protocol::SetTriggerRate{30'000}, 1);
  append(commands, protocol::SetExposure{5000, 120}, 2);
  append(commands, protocol::SetStages{0x3F}, 3);
  append(commands, protocol::Snapshot{}, 4);
  append(commands, protocol::CommandAck{4, protocol::AckStatus::ok}, 5);
  append(commands,
         protocol::CalibrationHealth{12, -34, 56, protocol::kDriftEstimated, 30, 300, -200, 2, 44},
         6);
  append(commands, protocol::Recalibrate{}, 7);
  append(commands, protocol::SaveCalibration{}, 8);
  write(dir / "commands", commands);

  Bytes garbage{0x13, 0x37, 0xFF, 0x00};
  append(garbage, summary, 9);
  write(dir / "garbage_then_frame", garbage);

  Bytes truncated;
  append(truncated, obstacles, 10);
  truncated.resize(truncated.size() / 2);
  append(truncated, summary, 11);
  write(dir / "truncated_then_frame", truncated);
}

void mavlink_seeds(const fs::path& dir) {
  Bytes frame(mavlink::kMaxFrameSize);
  protocol::Obstacles sectors;
  sectors.field_of_view_centideg = 9000;
  sectors.count = 8;
  sectors.nearest_mm = {1234, protocol::kUnknownDepth, 50, 60000, 995, 2000, 3000, 4000};
  const mavlink::ObstacleDistance m = mavlink::to_obstacle_distance(sectors, 99, 20, 3000);

  Bytes stream;
  const auto add = [&](std::size_t size) {
    stream.insert(stream.end(), frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size));
  };
  add(mavlink::encode_heartbeat({1, 196}, 0, frame));
  add(mavlink::encode_obstacle_distance(m, {1, 196}, 1, frame));
  write(dir / "heartbeat_obstacles", stream);

  stream.clear();
  add(mavlink::encode_named_value_float("rig_rows", -0.25f, 1234, {1, 196}, 5, frame));
  add(mavlink::encode_status_text(mavlink::Severity::notice, "epipole: rig corrected", {1, 196}, 6,
                                  frame));
  write(dir / "calibration_values_text", stream);

  stream.clear();
  mavlink::Odometry odometry;
  odometry.x = 1.5f;
  odometry.q = {0.99f, 0, 0, 0.141f};
  odometry.quality = 90;
  odometry.velocity_covariance[0] = 1e-3f;
  add(mavlink::encode_odometry(odometry, {1, 197}, 7, frame));
  add(mavlink::encode_timesync({0, 123456789, 1, 197}, {1, 1}, 8, frame));
  write(dir / "odometry_timesync", stream);

  stream = {0xFD, 0x13, 0xFD};
  const std::size_t damaged = mavlink::encode_obstacle_distance(m, {1, 196}, 2, frame);
  frame[40] ^= 0x10;
  add(damaged);
  add(mavlink::encode_heartbeat({1, 196}, 3, frame) / 2);
  add(mavlink::encode_heartbeat({1, 196}, 4, frame));
  write(dir / "garbage_damaged_truncated", stream);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: protocol_fuzz_seeds NATIVE_DIR MAVLINK_DIR\n");
    return 2;
  }
  for (const char* dir : {argv[1], argv[2]}) fs::create_directories(dir);
  native_seeds(argv[1]);
  mavlink_seeds(argv[2]);
  return 0;
}

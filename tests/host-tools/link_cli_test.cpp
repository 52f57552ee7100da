// epipole link as a user runs it: on a recorded stream file and on a kernel pseudo-terminal.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "epipole/firmware/protocol/codec.hpp"
#include "epipole/firmware/protocol/mavlink.hpp"
#include "run_tool.hpp"

namespace epipole::protocol {
namespace {

using Bytes = std::vector<std::uint8_t>;

using Result = epipole::test::ToolResult;
using epipole::test::start_tool;
Result finish(FILE* pipe) {
  return epipole::test::finish_tool(pipe);
}

std::vector<nlohmann::json> json_lines(const std::string& text) {
  std::vector<nlohmann::json> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

void append_frame(Bytes& stream, const Message& message, std::uint16_t sequence) {
  Bytes frame(kMaxFrameSize);
  frame.resize(encode_frame(message, sequence, frame));
  stream.insert(stream.end(), frame.begin(), frame.end());
}

// Writes a recorded stream into the test's temporary folder; returns its path.
std::string write_stream(const std::string& name, const Bytes& stream) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(stream.data()),
             static_cast<std::streamsize>(stream.size()));
  return path;
}

TEST(LinkCli, DecodesARecordedStreamAndCountsTheGarbage) {
  Health health;
  health.frames = 1234;
  health.stage_us[static_cast<int>(Stage::disparity)] = 8000;
  Detections detections;
  detections.frame = 7;
  detections.count = 2;
  detections.items[0] = {10, 20, 30, 40, 5, 1500};
  detections.items[1] = {100, 120, 50, 50, 3, kUnknownDepth};
  Bytes stream = {0x13, 0x37, 0x00};  // garbage first
  append_frame(stream, health, 1);
  Bytes damaged;
  append_frame(damaged, FrameSummary{}, 2);
  damaged[3] ^= 0x10;
  stream.insert(stream.end(), damaged.begin(), damaged.end());
  append_frame(stream, detections, 3);
  const std::string path = write_stream("epipole-link-stream.bin", stream);

  const Result r = finish(start_tool("link " + path + " --json"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  EXPECT_EQ(lines[0]["type"], "health");
  EXPECT_EQ(lines[0]["frames"], 1234);
  EXPECT_EQ(lines[0]["disparity_us"], 8000);
  EXPECT_EQ(lines[1]["type"], "detections");
  EXPECT_EQ(lines[1]["seq"], 3);
  ASSERT_EQ(lines[1]["boxes"].size(), 2u);
  EXPECT_EQ(lines[1]["boxes"][0]["depth_mm"], 1500);
  EXPECT_EQ(lines[2]["type"], "decoder");
  EXPECT_EQ(lines[2]["frames"], 2);
  EXPECT_EQ(lines[2]["lost"], 1);  // the damaged frame's sequence number
  EXPECT_GE(lines[2]["bad_cobs"].get<int>() + lines[2]["bad_crc"].get<int>(), 2);

  const Result text = finish(start_tool("link " + path + " --count 1"));
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("#1 health"), std::string::npos) << text.out;
  EXPECT_EQ(text.out.find("detections"), std::string::npos) << text.out;
  std::remove(path.c_str());
}

TEST(LinkCli, SendsCommandsAndReadsTheAnswerOnASerialDevice) {
  int master = -1;
  int slave = -1;
  std::array<char, 128> name{};
  ASSERT_EQ(openpty(&master, &slave, name.data(), nullptr, nullptr), 0);
  // The slave stays open here too: a pty master with no slave open reads as hung up.
  FILE* tool =
      start_tool(std::string("link ") + name.data() +
                 " --send snapshot --send stages=0x3 --send exposure=5000:6.5"
                 " --send recalibrate --send save-calibration --seconds 2 --count 1 --json");
  ASSERT_NE(tool, nullptr);

  FrameDecoder decoder;
  std::vector<Message> received;
  for (int tries = 0; tries < 300 && received.size() < 5; ++tries) {
    pollfd p{master, POLLIN, 0};
    if (::poll(&p, 1, 10) <= 0) continue;
    std::array<std::uint8_t, 256> buffer{};
    const ssize_t n = ::read(master, buffer.data(), buffer.size());
    for (ssize_t i = 0; i < n; ++i) {
      if (auto m = decoder.push(buffer[static_cast<std::size_t>(i)]))
        received.push_back(m->message);
    }
  }
  ASSERT_EQ(received.size(), 5u);
  EXPECT_EQ(received[0], Message(Snapshot{}));
  EXPECT_EQ(received[1], Message(SetStages{3}));
  EXPECT_EQ(received[2], Message(SetExposure{5000, 650}));
  EXPECT_EQ(received[3], Message(Recalibrate{}));
  EXPECT_EQ(received[4], Message(SaveCalibration{}));

  Bytes answer;
  append_frame(answer, CommandAck{0, AckStatus::ok}, 40);
  ASSERT_EQ(::write(master, answer.data(), answer.size()), static_cast<ssize_t>(answer.size()));
  const Result r = finish(tool);
  ::close(master);
  ::close(slave);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto lines = json_lines(r.out);
  ASSERT_GE(lines.size(), 1u) << r.out;
  EXPECT_EQ(lines[0]["type"], "ack");
  EXPECT_EQ(lines[0]["seq"], 40);
}

// A MAVLink board's recorded stream: HEARTBEAT and OBSTACLE_DISTANCE, with a damaged frame.
TEST(LinkCli, DecodesAMavlinkStream) {
  Bytes stream = {0x13, 0x37};
  const auto append = [&stream](std::size_t size, const Bytes& frame) {
    stream.insert(stream.end(), frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(size));
  };
  Bytes frame(mavlink::kMaxFrameSize);
  append(mavlink::encode_heartbeat({1, 196}, 0, frame), frame);
  Obstacles sectors;
  sectors.field_of_view_centideg = 9000;
  sectors.count = 4;
  sectors.nearest_mm = {1500, kUnknownDepth, 800, 30000};
  const mavlink::ObstacleDistance m = mavlink::to_obstacle_distance(sectors, 42, 20, 2000);
  const std::size_t damaged = mavlink::encode_obstacle_distance(m, {1, 196}, 1, frame);
  frame[30] ^= 0x01;
  append(damaged, frame);
  append(mavlink::encode_obstacle_distance(m, {1, 196}, 2, frame), frame);
  append(mavlink::encode_named_value_float("rig_rows", 0.25f, 1500, {1, 196}, 3, frame), frame);
  append(mavlink::encode_status_text(mavlink::Severity::notice, "epipole: rig corrected", {1, 196},
                                     4, frame),
         frame);
  const std::string path = write_stream("epipole-link-mavlink.bin", stream);

  const Result r = finish(start_tool("link " + path + " --protocol mavlink --json"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), 5u) << r.out;
  EXPECT_EQ(lines[2]["type"], "named_value_float");
  EXPECT_EQ(lines[2]["name"], "rig_rows");
  EXPECT_EQ(lines[2]["value"], 0.25);
  EXPECT_EQ(lines[2]["time_boot_ms"], 1500);
  EXPECT_EQ(lines[3]["type"], "statustext");
  EXPECT_EQ(lines[3]["severity"], 5);
  EXPECT_EQ(lines[3]["text"], "epipole: rig corrected");
  lines.erase(lines.begin() + 2, lines.begin() + 4);
  EXPECT_EQ(lines[0]["type"], "heartbeat");
  EXPECT_EQ(lines[0]["component_id"], 196);
  EXPECT_EQ(lines[1]["type"], "obstacle_distance");
  EXPECT_EQ(lines[1]["seq"], 2);
  EXPECT_EQ(lines[1]["time_usec"], 42);
  EXPECT_EQ(lines[1]["distances_cm"][0], 150);
  EXPECT_EQ(lines[1]["distances_cm"][1], 65535);
  EXPECT_EQ(lines[1]["distances_cm"][3], 2001);
  EXPECT_EQ(lines[1]["nearest_cm"], 80);
  EXPECT_EQ(lines[2]["type"], "decoder");
  EXPECT_EQ(lines[2]["protocol"], "mavlink");
  EXPECT_EQ(lines[2]["frames"], 4);
  EXPECT_EQ(lines[2]["bad_crc"], 1);
  EXPECT_EQ(lines[2]["lost"], 1);
  EXPECT_GT(lines[2]["errors"].get<int>(), 0);

  // Read as the native protocol, the same bytes are garbage: nothing is made up from them.
  const auto native = json_lines(finish(start_tool("link " + path + " --json")).out);
  ASSERT_EQ(native.size(), 1u);
  EXPECT_EQ(native[0]["frames"], 0);
  EXPECT_GT(native[0]["errors"].get<int>(), 0);

  const Result commands =
      finish(start_tool("link " + path + " --protocol mavlink --send snapshot"));
  EXPECT_NE(commands.exit_code, 0);
  EXPECT_NE(commands.out.find("MAVLink reads no commands"), std::string::npos) << commands.out;
  std::remove(path.c_str());
}

// --trajectory: the odometry's tracked poses as a TUM trajectory, native and MAVLink; pairs
// starting or lost are not poses.
TEST(LinkCli, WritesTheOdometryAsATumTrajectory) {
  const auto odometry = [](std::uint32_t frame, OdometryStatus status, std::int32_t z_mm) {
    Odometry m;
    m.frame = frame;
    m.trigger_ns = 1'500'000'000ull + frame * 66'666'667ull;
    m.status = status;
    m.z_mm = z_mm;
    m.qw_e9 = 707'106'781;
    m.qy_e9 = 707'106'781;
    return m;
  };
  Bytes stream;
  append_frame(stream, odometry(0, OdometryStatus::starting, 0), 0);
  append_frame(stream, odometry(1, OdometryStatus::tracking, 1234), 1);
  append_frame(stream, odometry(2, OdometryStatus::lost, 1234), 2);
  append_frame(stream, odometry(3, OdometryStatus::tracking, -50), 3);
  const std::string path = write_stream("epipole-link-odometry.bin", stream);
  const std::string tum = ::testing::TempDir() + "epipole-link-odometry.tum";
  const Result r = finish(start_tool("link " + path + " --trajectory " + tum));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::ifstream in(tum);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::vector<double> row;
    for (double v = 0; fields >> v;) row.push_back(v);
    EXPECT_EQ(row.size(), 8u) << line;
    rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_NEAR(rows[0][0], 1.566666667, 1e-9);
  EXPECT_NEAR(rows[0][3], 1.234, 1e-9);
  EXPECT_NEAR(rows[0][5], 0.707106781, 1e-9) << "qy";
  EXPECT_NEAR(rows[0][7], 0.707106781, 1e-9) << "qw last";
  EXPECT_NEAR(rows[1][3], -0.05, 1e-9);

  Bytes mavlink_stream;
  Bytes frame(mavlink::kMaxFrameSize);
  mavlink::Odometry m;
  m.time_usec = 2'000'000;
  m.x = 1.5f;
  m.q = {1, 0, 0, 0};
  m.quality = 80;
  std::size_t n = mavlink::encode_odometry(m, {1, 197}, 0, frame);
  mavlink_stream.insert(mavlink_stream.end(), frame.begin(), frame.begin() + n);
  m.quality = -1;  // lost
  n = mavlink::encode_odometry(m, {1, 197}, 1, frame);
  mavlink_stream.insert(mavlink_stream.end(), frame.begin(), frame.begin() + n);
  const std::string mavlink_path =
      write_stream("epipole-link-odometry-mavlink.bin", mavlink_stream);
  const Result mr =
      finish(start_tool("link " + mavlink_path + " --protocol mavlink --trajectory " + tum));
  ASSERT_EQ(mr.exit_code, 0) << mr.out;
  std::ifstream again(tum);
  std::string line;
  ASSERT_TRUE(std::getline(again, line));
  EXPECT_EQ(line.substr(0, 20), "2.000000000 1.500000");
  EXPECT_FALSE(std::getline(again, line)) << "the lost pose is no pose";

  const Result bad = finish(start_tool("link " + path + " --trajectory /no/such/dir/t.tum"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.out.find("cannot write the trajectory"), std::string::npos) << bad.out;
  for (const std::string& p : {path, mavlink_path, tum}) std::remove(p.c_str());
}

TEST(LinkCli, BadArgumentsAreOneLineErrors) {
  const std::string file = ::testing::TempDir() + "epipole-link-empty.bin";
  std::ofstream(file).put('x');
  for (const std::string& arguments : std::vector<std::string>{
           "link", "link /no/such/file", "link " + file + " --send bogus",
           "link " + file + " --send trigger-rate=fast", "link " + file + " --send snapshot",
           "link " + file + " --baud 12345", "link " + file + " --send stages=0x1ffff",
           "link " + file + " --protocol px4"}) {
    const Result r = finish(start_tool(arguments));
    EXPECT_NE(r.exit_code, 0) << arguments;
    EXPECT_FALSE(r.out.empty()) << arguments;
    EXPECT_LE(std::count(r.out.begin(), r.out.end(), '\n'), 2) << arguments << ": " << r.out;
  }
  std::remove(file.c_str());
}

}  // namespace
}  // namespace epipole::protocol

// `epipole sim`, the README's main job: the firmware on the simulated board over the real data,
// with its pictures, the decoded serial stream and the summary.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "epipole/core/image_io.hpp"
#include "run_tool.hpp"
#include "test_clients.hpp"
#include "test_data.hpp"
#include "test_paths.hpp"

namespace {

namespace fs = std::filesystem;
using epipole::test::firmware_path;
using epipole::test::run_tool;
using epipole::test::sim_output_dir;
using epipole::test::source_dir;

constexpr int kFrames = 20;

// The run is made once, before these tests, by the ctest fixture sim_cli_run (its output folder
// is sim_output_dir()); a test program started by hand makes it itself when it is missing.
fs::path out_dir() {
  return sim_output_dir();
}

std::string sim_command() {
  return "sim --board '" + std::string(source_dir()) + "/board/sim' --frames " +
         std::to_string(kFrames) + " --out '" + out_dir().string() + "'";
}

const epipole::test::ToolResult& sim_run() {
  static const epipole::test::ToolResult r = [] {
    epipole::test::data_file("samples/aloeGT.png");  // fails the test with a hint when missing
    if (fs::exists(out_dir() / "summary.json")) return epipole::test::ToolResult{0, ""};
    return run_tool(sim_command());
  }();
  return r;
}

int scene_lines(const std::string& out) {
  int n = 0;
  for (std::size_t at = out.find("sim: scene "); at != std::string::npos;
       at = out.find("sim: scene ", at + 1)) {
    ++n;
  }
  return n;
}

nlohmann::json summary() {
  std::ifstream in(out_dir() / "summary.json");
  return nlohmann::json::parse(in);
}

TEST(SimCli, RunsEverySceneOfTheSimulatedBoard) {
  const auto& r = sim_run();
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json s = summary();
  ASSERT_EQ(s["scenes"].size(), 5u) << s.dump(2);
  std::vector<std::string> names;
  for (const auto& scene : s["scenes"]) {
    names.push_back(scene["scene"]);
    // A path (the loop, cut to its first kFrames poses) ends at its last pose: the pairs the
    // loop's time skipped are not made up after it.
    const int frames = scene["frames"].get<int>();
    if (scene["scene"] == "loop") {  // fewer on a slow build (the sanitizers')
      EXPECT_GE(frames, 1) << scene.dump(2);
      EXPECT_LE(frames, kFrames) << scene.dump(2);
    } else {
      EXPECT_EQ(frames, kFrames) << scene.dump(2);
    }
    EXPECT_EQ(scene["timeouts"], 0) << scene.dump(2);
    EXPECT_EQ(scene["messages_dropped"], 0) << scene.dump(2);
    EXPECT_EQ(scene["calibration"], "yes");
    // What the robot's end of the link received and decoded.
    EXPECT_EQ(scene["received"]["frame"], frames) << scene.dump(2);
    EXPECT_EQ(scene["received"]["obstacles"], frames) << scene.dump(2);
    EXPECT_GE(scene["received"]["health"].get<int>(), 1) << scene.dump(2);
    const auto& d = scene["decoder"];
    EXPECT_EQ(d["bad_cobs"].get<int>() + d["bad_crc"].get<int>() + d["bad_body"].get<int>() +
                  d["lost"].get<int>(),
              0)
        << d.dump();
    EXPECT_GT(scene["last_health"]["fps_centi"].get<int>(), 0);
  }
  // The loop's path cut to its first kFrames poses (--frames).
  EXPECT_EQ(names, (std::vector<std::string>{"chessboard", "aloe", "faces", "ground", "loop"}));
  if (!r.out.empty()) {
    EXPECT_EQ(scene_lines(r.out), 5) << r.out;
  }
}

TEST(SimCli, WritesThePicturesAndTheStream) {
  ASSERT_EQ(sim_run().exit_code, 0) << sim_run().out;
  for (const char* scene : {"chessboard", "aloe", "faces", "ground", "loop"}) {
    const fs::path dir = out_dir() / scene;
    const epipole::GrayImage pair = epipole::load_gray(dir / "frame0-rectified-pair.png");
    EXPECT_EQ(pair.width(), 1280) << scene;
    EXPECT_EQ(pair.height(), 480) << scene;
    EXPECT_EQ(epipole::load_gray(dir / "frame0-disparity.png").height(), 480 + 40)
        << "the legend under the picture";
    EXPECT_TRUE(fs::exists(dir / "frame0-corners.png")) << scene;
    EXPECT_GT(fs::file_size(dir / "serial.bin"), 1000u) << scene;
    // Every line of the decoded stream is JSON; the last one the decoder's counts.
    std::ifstream lines(dir / "serial.jsonl");
    std::string line, last;
    int count = 0;
    while (std::getline(lines, line)) {
      last = line;
      EXPECT_TRUE(nlohmann::json::accept(line)) << line;
      ++count;
    }
    // Each pair's summary, obstacles and more (the loop's pairs: as many as it ran).
    int pairs = kFrames;
    const nlohmann::json runs = summary();
    for (const auto& ran : runs["scenes"]) {
      if (ran["scene"] == scene) pairs = ran["frames"].get<int>();
    }
    EXPECT_GT(count, 2 * pairs) << scene;
    EXPECT_EQ(nlohmann::json::parse(last)["type"], "decoder");
  }
}

// The firmware's disparity of the Aloe scene against the data set's ground truth, fitted into
// the simulated cameras' 640x480 the way the scene is (one scale, centred).
TEST(SimCli, AloeDisparityAgreesWithTheGroundTruth) {
  ASSERT_EQ(sim_run().exit_code, 0) << sim_run().out;
  const auto ours = epipole::load_gray16(out_dir() / "aloe" / "frame0-disparity16.png");
  const auto truth = epipole::load_gray(epipole::test::data_file("samples/aloeGT.png"));
  const double scale = std::min(640.0 / truth.width(), 480.0 / truth.height());
  const int w = static_cast<int>(std::lround(truth.width() * scale));
  const int h = static_cast<int>(std::lround(truth.height() * scale));
  const int x0 = (640 - w) / 2;
  const int y0 = (480 - h) / 2;
  int known = 0, valid = 0, bad2 = 0;
  for (int v = y0; v < y0 + h; ++v) {
    for (int u = x0; u < x0 + w; ++u) {
      const int sx = std::clamp(static_cast<int>((u - x0 + 0.5) / scale), 0, truth.width() - 1);
      const int sy = std::clamp(static_cast<int>((v - y0 + 0.5) / scale), 0, truth.height() - 1);
      const int gt = truth.view()(sx, sy);
      if (gt == 0) continue;
      ++known;
      const int d16 = ours.view()(u, v);
      if (d16 == 0) {
        ++bad2;
        continue;
      }
      ++valid;
      if (std::abs(d16 / 16.0 - gt * scale) > 2.0) ++bad2;
    }
  }
  const double bad2_share = static_cast<double>(bad2) / known;
  const double density = static_cast<double>(valid) / known;
  std::printf("aloe scene, 640x480: bad2 %.1f %%, density %.1f %% (%d known pixels)\n",
              100 * bad2_share, 100 * density, known);
  EXPECT_GT(known, 100'000);
  EXPECT_LT(bad2_share, 0.35);
  EXPECT_GT(density, 0.6);
}

// The faces scene's right view is its left view shifted by 32 pixels.
TEST(SimCli, FacesSceneHasItsKnownDisparity) {
  ASSERT_EQ(sim_run().exit_code, 0) << sim_run().out;
  const auto ours = epipole::load_gray16(out_dir() / "faces" / "frame0-disparity16.png");
  std::vector<int> values;
  for (int y = 0; y < ours.height(); ++y) {
    for (int x = 0; x < ours.width(); ++x) {
      if (ours.view()(x, y) != 0) values.push_back(ours.view()(x, y));
    }
  }
  ASSERT_GT(values.size(), 100'000u);
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  EXPECT_NEAR(values[values.size() / 2] / 16.0, 32.0, 0.25);
}

// The faces scene: OpenCV's face cascade (compiled by epipole sim) finds the player, and the
// box's depth is the scene's: 700 px * 0.12 m / 32 px = 2.625 m.
TEST(SimCli, FacesAreDetectedAtTheirKnownDepth) {
  ASSERT_EQ(sim_run().exit_code, 0) << sim_run().out;
  EXPECT_TRUE(fs::exists(out_dir() / "faces" / "frame0-detections.png"));
  std::ifstream lines(out_dir() / "faces" / "serial.jsonl");
  std::string line;
  int messages = 0, boxes = 0;
  while (std::getline(lines, line)) {
    const nlohmann::json m = nlohmann::json::parse(line);
    if (m["type"] != "detections") continue;
    ++messages;
    for (const auto& box : m["boxes"]) {
      ++boxes;
      EXPECT_NEAR(box["depth_mm"].get<int>(), 2625, 60) << box.dump();
      EXPECT_GE(box["width"].get<int>(), 30);
    }
  }
  EXPECT_EQ(messages, kFrames);
  EXPECT_GE(boxes, kFrames) << "a face in every frame";
}

TEST(SimCli, BadArgumentsAreOneLineErrors) {
  const auto r = run_tool("sim --board /nowhere --out '" + out_dir().string() + "-bad'");
  ASSERT_FALSE(fs::exists(out_dir().string() + "-bad/summary.json"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(epipole::test::line_count(r.out), 1) << r.out;
  const auto r2 = run_tool("sim --board '" + std::string(source_dir()) +
                           "/board/raspberrypi5-ov9281' --out '" + out_dir().string() + "-bad'");
  EXPECT_EQ(r2.exit_code, 1);
  EXPECT_NE(r2.out.find("not a simulated board"), std::string::npos) << r2.out;
  const auto r3 = run_tool("sim --board '" + std::string(source_dir()) +
                           "/board/sim' --scene moon --out '" + out_dir().string() + "-bad'");
  EXPECT_EQ(r3.exit_code, 1);
  EXPECT_NE(r3.out.find("'moon' is not a scene"), std::string::npos) << r3.out;
}

// --json: the summary (as summary.json holds it) is all of stdout, so a script can read it.
TEST(SimCli, JsonPrintsTheSummaryAlone) {
  const fs::path out = fs::path(::testing::TempDir()) / "sim-json-out";
  const auto r =
      run_tool("sim --board '" + std::string(source_dir()) +
               "/board/sim' --scene aloe -n 3 --pictures 0 --json -o '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  ASSERT_EQ(summary["scenes"].size(), 1u) << r.out;
  EXPECT_EQ(summary["scenes"][0]["scene"], "aloe");
  EXPECT_EQ(summary["scenes"][0]["frames"], 3);
  std::ifstream file(out / "summary.json");
  EXPECT_EQ(nlohmann::json::parse(file), summary);
}

// The board folder as shipped, under the firmware program itself (the cascade it names is
// compiled into the data cache by the build).
TEST(SimCli, TheFirmwareRunsTheShippedSimulatedBoard) {
  epipole::test::data_file("compiled/haarcascade_frontalface_default.bin");
  const std::string command = std::string(firmware_path()) + " --board '" + source_dir() +
                              "/board/sim' --scene faces --frames 10 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  const auto r = epipole::test::finish_tool(pipe);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("stopped after 10 pairs"), std::string::npos) << r.out;
}

// A copy of board/sim named `name` speaking MAVLink, with `extra` after its board file.
fs::path mavlink_board(const std::string& name, const std::string& extra = "") {
  const fs::path board = fs::path(::testing::TempDir()) / name;
  fs::create_directories(board);
  for (const auto& entry : fs::directory_iterator(fs::path(source_dir()) / "board" / "sim")) {
    fs::copy_file(entry.path(), board / entry.path().filename(),
                  fs::copy_options::overwrite_existing);
  }
  std::ifstream in(board / "board.yaml");
  std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string native = "protocol: epipole";
  EXPECT_NE(yaml.find(native), std::string::npos);
  if (yaml.find(native) != std::string::npos) {
    yaml.replace(yaml.find(native), native.size(), "protocol: mavlink");
  }
  std::ofstream(board / "board.yaml") << yaml << extra;
  return board;
}

// A board that speaks MAVLink to its flight controller: the robot's end of the link decodes
// MAVLink 2 (HEARTBEAT at the health interval with the calibration's NAMED_VALUE_FLOATs, an
// OBSTACLE_DISTANCE and an ODOMETRY for every pair), not the native protocol; no STATUSTEXT without
// a correction.
TEST(SimCli, AMavlinkBoardsStreamIsDecodedAsMavlink) {
  const fs::path board = mavlink_board("sim-mavlink");

  const fs::path out = fs::path(::testing::TempDir()) / "sim-mavlink-out";
  const auto r = run_tool("sim --board '" + board.string() + "' --scene aloe --frames " +
                          std::to_string(kFrames) + " --pictures 0 --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::ifstream summary_file(out / "summary.json");
  const nlohmann::json scene = nlohmann::json::parse(summary_file)["scenes"][0];
  EXPECT_EQ(scene["decoder"]["protocol"], "mavlink") << scene.dump(2);
  EXPECT_EQ(scene["decoder"]["errors"], 0) << scene.dump(2);
  EXPECT_EQ(scene["decoder"]["bad_crc"], 0) << scene.dump(2);
  EXPECT_EQ(scene["received"]["obstacle_distance"], kFrames) << scene.dump(2);
  EXPECT_GE(scene["received"]["heartbeat"].get<int>(), 1) << scene.dump(2);
  EXPECT_GE(scene["received"]["named_value_float"].get<int>(), 1) << scene.dump(2);
  // Aloe stands still: the odometry tracks from the first pair (a pose, no motion).
  EXPECT_EQ(scene["received"]["odometry"], kFrames) << scene.dump(2);
  EXPECT_EQ(scene["received"].size(), 4u) << scene.dump(2);

  std::ifstream lines(out / "aloe" / "serial.jsonl");
  std::string line;
  int obstacles = 0, near = 0;
  while (std::getline(lines, line)) {
    const nlohmann::json m = nlohmann::json::parse(line);
    if (m["type"] != "obstacle_distance") continue;
    ++obstacles;
    EXPECT_EQ(m["system_id"], 1);
    EXPECT_EQ(m["component_id"], 196);
    EXPECT_EQ(m["min_distance_cm"], 20);
    EXPECT_EQ(m["max_distance_cm"], 2000);
    // board/sim: 72 sectors over the rectified camera's field of view, centred on forward.
    ASSERT_EQ(m["distances_cm"].size(), 72u);
    const double increment = m["increment_deg"];
    EXPECT_GT(increment, 0.1);
    EXPECT_NEAR(m["angle_offset_deg"].get<double>(), -36 * increment + increment / 2, 1e-3);
    if (!m["nearest_cm"].is_null()) ++near;
  }
  EXPECT_EQ(obstacles, kFrames);
  EXPECT_EQ(near, kFrames) << "Aloe is within 20 m in every frame";
}

// The rig's drift as a flight controller and its ground station see it, read by an independent
// MAVLink decoder (node-mavlink, tests/clients/mavlink-read.mjs): the calibration's figures as
// NAMED_VALUE_FLOATs at each heartbeat, the correction said once as a STATUSTEXT. The faces scene
// with its right camera turned 0.3 degrees of pitch and 0.2 of roll, corrected online.
TEST(SimCli, AMavlinkBoardTellsTheAutopilotOfTheRigsDrift) {
  ASSERT_TRUE(epipole::test::clients_installed()) << "the test clients: scripts/setup.sh";
  const fs::path board = mavlink_board("sim-mavlink-drift", R"(
calibration_health: {online_correction: true}
)");
  // A scene of its own among the sim's.
  std::ifstream in(board / "board.yaml");
  std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string faces = "    faces:";
  ASSERT_NE(yaml.find(faces), std::string::npos);
  yaml.insert(yaml.find(faces), R"(    drifted:
      synthesize: ${EPIPOLE_DATA_DIR}/samples/messi5.jpg
      disparity: 32
      calibration: faces-rig.yaml
      drift: {pitch_deg: 0.3, roll_deg: 0.2}
)");
  std::ofstream(board / "board.yaml") << yaml;

  const int frames = 75;  // 5 s: the correction after 20 pairs, heartbeats after it
  const fs::path out = fs::path(::testing::TempDir()) / "sim-mavlink-drift-out";
  const auto r = run_tool("sim --board '" + board.string() + "' --scene drifted --frames " +
                          std::to_string(frames) + " --pictures 0 --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out;

  const auto read = epipole::test::run_client(
      "mavlink-read.mjs", "'" + (out / "drifted" / "serial.bin").string() + "'");
  ASSERT_EQ(read.exit_code, 0) << read.out;
  const nlohmann::json got = nlohmann::json::parse(read.out);
  EXPECT_EQ(got["crc_errors"], 0);
  EXPECT_EQ(got["invalid"], 0);
  EXPECT_EQ(got["unknown"], 0);
  int distances = 0, heartbeats = 0, texts = 0, heartbeats_after = 0;
  std::vector<std::map<std::string, double>> values(1);  // by heartbeat: name -> value
  bool corrected = false;
  std::map<std::string, double> before;  // the last figures before the correction was said
  for (const nlohmann::json& m : got["messages"]) {
    EXPECT_EQ(m["sysid"], 1);
    EXPECT_EQ(m["compid"], 196);
    EXPECT_EQ(m["version"], 0xFD) << "MAVLink 2";
    const nlohmann::json& f = m["fields"];
    if (m["name"] == "OBSTACLE_DISTANCE") ++distances;
    if (m["name"] == "HEARTBEAT") {
      ++heartbeats;
      values.emplace_back();
    }
    if (m["name"] == "NAMED_VALUE_FLOAT") {
      EXPECT_GT(f["time_boot_ms"].get<double>(), 0);
      values.back()[f["name"].get<std::string>()] = f["value"].get<double>();
    }
    if (m["name"] == "STATUSTEXT") {
      ++texts;
      EXPECT_EQ(f["severity"], 5) << "MAV_SEVERITY_NOTICE";
      const std::string text = f["text"];
      double pitch = 0, roll = 0;
      EXPECT_EQ(
          std::sscanf(text.c_str(), "epipole: rig corrected, pitch %lf roll %lf", &pitch, &roll), 2)
          << text;
      EXPECT_NEAR(pitch, 0.3, 0.03) << text;
      EXPECT_NEAR(roll, 0.2, 0.03) << text;
      corrected = true;
      before = values.back();
      heartbeats_after = 0;
    }
    if (m["name"] == "HEARTBEAT" && corrected) ++heartbeats_after;
  }
  EXPECT_EQ(distances, frames);
  EXPECT_GE(heartbeats, 3);
  EXPECT_EQ(texts, 1) << "said once";
  ASSERT_TRUE(corrected) << read.out;
  // Before: the rows a few pixels off, the right sign, the turn estimated.
  ASSERT_TRUE(before.count("rig_rows") && before.count("rig_pitch") && before.count("rig_roll"))
      << read.out;
  EXPECT_GE(before["rig_rows"], 1.0);
  EXPECT_NEAR(before["rig_pitch"], 0.3, 0.03);
  EXPECT_NEAR(before["rig_roll"], 0.2, 0.03);
  EXPECT_EQ(before["rig_corr"], 0);
  // After: the last heartbeat's figures say the rig is corrected and its rows are straight.
  ASSERT_GE(heartbeats_after, 1) << "a heartbeat's figures after the correction";
  std::map<std::string, double>& after = values.back();
  ASSERT_TRUE(after.count("rig_rows") && after.count("rig_corr")) << read.out;
  EXPECT_LT(std::abs(after["rig_rows"]), 0.1);
  EXPECT_EQ(after["rig_corr"], 1);
  EXPECT_NEAR(after["rig_cpitch"], 0.3, 0.03);
  EXPECT_NEAR(after["rig_croll"], 0.2, 0.03);
}

// The rig's odometry as a flight controller reads it, with an independent MAVLink decoder
// (node-mavlink): a rendered walk (2 m ahead at 1 m/s, a right turn of 90 degrees, 2 m on) on a
// MAVLink board; every ODOMETRY in LOCAL_FRD / BODY_FRD from the VIO estimator, its time rising,
// and the last one where the exact path (the sim's trajectory.tum, in the rectified camera's
// axes, turned here to FRD: x its z, y its x, z its y) says the rig is.
TEST(SimCli, AMavlinkBoardSendsItsOdometryToTheAutopilot) {
  ASSERT_TRUE(epipole::test::clients_installed()) << "the test clients: scripts/setup.sh";
  const fs::path board = mavlink_board("sim-mavlink-walk");
  std::ifstream in(board / "board.yaml");
  std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string faces = "    faces:";
  ASSERT_NE(yaml.find(faces), std::string::npos);
  // Every pose a pair, however slow the build (the sanitizers'): the virtual clock is not
  // charged with the host's time, so no pair is skipped.
  const std::string charged = "charge_compute: true";
  ASSERT_NE(yaml.find(charged), std::string::npos);
  yaml.replace(yaml.find(charged), charged.size(), "charge_compute: false");
  yaml.insert(yaml.find(faces), R"(    walk:
      world:
        rig: {height_m: 0.8, pitch_deg: 8, roll_deg: 0}
        floor:
          texture: ${EPIPOLE_DATA_DIR}/samples/baboon.jpg
          texel_mm: 4
        boxes:
          - at_m: [1, 6]
            size_m: [8, 2.5, 0.2]
            texture: ${EPIPOLE_DATA_DIR}/samples/building.jpg
            texel_mm: 5
          - at_m: [5, -2]
            size_m: [0.2, 2.5, 8]
            texture: ${EPIPOLE_DATA_DIR}/samples/fruits.jpg
            texel_mm: 5
        path: {waypoints_m: [[0, 0], [0, 2], [2, 2]], speed_mps: 1, turn_dps: 90, rate_hz: 15}
      calibration: chessboard-rig.yaml
)");
  std::ofstream(board / "board.yaml") << yaml;
  const fs::path out = fs::path(::testing::TempDir()) / "sim-mavlink-walk-out";
  const auto r = run_tool("sim --board '" + board.string() + "' --scene walk --pictures 0 --out '" +
                          out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out;

  // The exact path's last pose, turned to FRD.
  std::ifstream truth_file(out / "walk" / "trajectory.tum");
  std::string line, last_line;
  int poses = 0;
  while (std::getline(truth_file, line)) {
    last_line = line;
    ++poses;
  }
  ASSERT_EQ(poses, 76) << "5 s at 15 pairs a second, and the start";
  std::istringstream fields(last_line);
  double t = 0, tx = 0, ty = 0, tz = 0, qx = 0, qy = 0, qz = 0, qw = 0;
  ASSERT_TRUE(fields >> t >> tx >> ty >> tz >> qx >> qy >> qz >> qw) << last_line;
  const std::array<double, 3> position{tz, tx, ty};
  const std::array<double, 4> q{qw, qz, qx, qy};

  const auto read = epipole::test::run_client("mavlink-read.mjs",
                                              "'" + (out / "walk" / "serial.bin").string() + "'");
  ASSERT_EQ(read.exit_code, 0) << read.out;
  const nlohmann::json got = nlohmann::json::parse(read.out);
  EXPECT_EQ(got["crc_errors"], 0);
  EXPECT_EQ(got["invalid"], 0);
  EXPECT_EQ(got["unknown"], 0);
  int count = 0;
  double last_time = -1;
  nlohmann::json last;
  for (const nlohmann::json& m : got["messages"]) {
    if (m["name"] != "ODOMETRY") continue;
    ++count;
    const nlohmann::json& f = m["fields"];
    EXPECT_EQ(f["frame_id"], 20) << "MAV_FRAME_LOCAL_FRD";
    EXPECT_EQ(f["child_frame_id"], 12) << "MAV_FRAME_BODY_FRD";
    EXPECT_EQ(f["estimator_type"], 3) << "MAV_ESTIMATOR_TYPE_VIO";
    EXPECT_EQ(f["reset_counter"], 0);
    EXPECT_GT(f["time_usec"].get<double>(), last_time);
    last_time = f["time_usec"].get<double>();
    if (f["quality"].get<int>() >= 0) last = f;  // the last pose tracked
  }
  EXPECT_EQ(count, 76) << "a pose for every pair";
  ASSERT_FALSE(last.is_null()) << read.out;
  std::printf("walk: the last ODOMETRY (%.3f, %.3f, %.3f) m, truth (%.3f, %.3f, %.3f) m\n",
              last["x"].get<double>(), last["y"].get<double>(), last["z"].get<double>(),
              position[0], position[1], position[2]);
  EXPECT_GT(last["quality"].get<int>(), 0);
  EXPECT_GE(last["time_usec"].get<double>(), last_time - 100'000) << "tracked to the end";
  EXPECT_NEAR(last["x"].get<double>(), position[0], 0.05);
  EXPECT_NEAR(last["y"].get<double>(), position[1], 0.05);
  EXPECT_NEAR(last["z"].get<double>(), position[2], 0.05);
  double dot = 0;
  for (std::size_t i = 0; i < 4; ++i) dot += last["q"][i].get<double>() * q[i];
  EXPECT_LT(2 * std::acos(std::min(1.0, std::abs(dot))) * 180 / M_PI, 1.0) << "attitude";
  // Walking on at 1 m/s, straight ahead in the body's frame.
  EXPECT_NEAR(last["vx"].get<double>(), std::cos(8 * M_PI / 180), 0.15);
  EXPECT_NEAR(last["vy"].get<double>(), 0, 0.15);
  EXPECT_TRUE(std::isfinite(last["pose_covariance"][0].get<double>()));
  EXPECT_GT(last["pose_covariance"][0].get<double>(), 0);
}

}  // namespace

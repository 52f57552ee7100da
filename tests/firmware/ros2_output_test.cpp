// The ROS 2 output as a robot's computer takes it: the firmware on the simulated board publishes
// over DDS on the loopback interface (its board file's defaults), and a subscriber in a process
// of its own (epipole-ros2-listener, CycloneDDS configured by the loopback-only file the tests
// pass) takes every topic, and so does a subscriber of another vendor (Fast DDS). What they
// decode must be what the pipeline computed.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include <Eigen/Geometry>

#include "epipole/firmware/firmware.hpp"
#include "ros_message_checks.hpp"
#include "sim/sim_settings.hpp"
#include "sim/world_scene.hpp"
#include "sim_rig.hpp"
#include "test_clients.hpp"
#include "test_paths.hpp"

namespace epipole::firmware {
namespace {

// A domain of this test run's own (the tests run in parallel; each domain has its own ports).
int own_domain() {
  return 100 + static_cast<int>(::getpid() % 100);
}

// The firmware on the simulated board with the ROS 2 output on (its board file's network
// defaults), a subscriber started by `listener` (a command line) once its writers exist: what the
// subscriber took, and what the output did.
struct Taken {
  json messages;
  OutputReport output;
  std::map<std::string, std::uint64_t> counts;  // messages by topic
  RosChecks checks;
};

// `pairs` pairs of the firmware (its writers made: the subscriber waits for them) while the
// subscriber `listener` takes what they publish on `domain`; the messages taken (empty when the
// subscriber failed, and said).
json listen_to(Firmware& fw, const std::string& listener, int domain, int pairs,
               const std::string& name, RunSummary& s, Taken& taken) {
  FILE* pipe =
      popen((listener + " " + std::to_string(domain) + " /epipole 30 6 2>&1").c_str(), "r");
  EXPECT_NE(pipe, nullptr);
  if (pipe == nullptr) return json::array();
  std::array<char, 256> line{};
  const bool ready = std::fgets(line.data(), line.size(), pipe) != nullptr &&
                     std::string(line.data()) == "ready\n";
  // "ready" is the subscriber's readers matching the writers; the writers' side of the match
  // follows a discovery round later (a reliable writer delivers nothing written before it), which
  // under the sanitizers took longer than the first pair: a moment for it.
  if (ready) std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::atomic<bool> stop{!ready};
  s = fw.run(pairs, stop);
  const test::ToolResult got = test::finish_tool(pipe);
  EXPECT_TRUE(ready) << name << ": " << line.data() << got.out;
  EXPECT_EQ(got.exit_code, 0) << name << ": " << got.out;
  if (!ready || got.exit_code != 0 || s.outputs.size() != 1) return json::array();
  taken.output = s.outputs[0];
  EXPECT_EQ(taken.output.name, "ros2");
  EXPECT_EQ(taken.output.failures, 0u);
  EXPECT_EQ(taken.output.delivered + taken.output.dropped, static_cast<std::uint64_t>(pairs));
  taken.messages = json::parse(got.out)["messages"];
  for (const json& m : taken.messages) ++taken.counts[m["topic"].get<std::string>()];
  return taken.messages;
}

Taken take_topics(const std::string& listener, const std::string& name) {
  ::unsetenv("CYCLONEDDS_URI");  // the firmware takes the board file's network
  test::SimRig rig(96, 64, 6);
  const int domain = own_domain();
  // A writer history deep enough for the whole run: the simulated board runs far faster than
  // its trigger, and a reliable keep-last writer drops what its history cannot hold.
  BoardConfig config = rig.parse("outputs: {ros2: {domain: " + std::to_string(domain) +
                                 ", points_step: 4, depth: 100, every: {disparity: 1}}}\n");
  config.stages |= protocol::stage_bit(protocol::Stage::sparse);
  Firmware fw(rig.replaying(config, 3));  // its writers first: the subscriber waits for them
  Kept kept;
  fw.frame_loop().set_observer(&kept);
  Taken taken;
  RunSummary s;
  // Past the first health message (a second of the simulated board's clock).
  if (listen_to(fw, listener, domain, 45, name, s, taken).empty()) return taken;
  taken.checks = check_ros_messages(taken.messages, kept, *fw.calibration(), rig);
  std::printf(
      "%s: %zu messages taken (%llu pairs published, %llu dropped); checked %d depths, "
      "%d points, %d features, %d health and %d calibration statuses\n",
      name.c_str(), taken.messages.size(), static_cast<unsigned long long>(taken.output.delivered),
      static_cast<unsigned long long>(taken.output.dropped), taken.checks.depths,
      taken.checks.points, taken.checks.features, taken.checks.health, taken.checks.calibration);
  EXPECT_EQ(taken.checks.unmatched, 0) << name;
  return taken;
}

std::string with_config(const char* variable, const char* file, const char* program) {
  return std::string(variable) + "=" + (test::clients_dir() / file).string() + " " + program;
}

TEST(Ros2Output, ASubscriberInAnotherProcessGetsEveryTopicAsThePipelineComputedIt) {
  const Taken t = take_topics(
      with_config("CYCLONEDDS_URI", "cyclonedds-loopback.xml", test::ros2_listener_path()),
      "cyclonedds");
  for (const char* topic :
       {"/epipole/left/image_rect", "/epipole/right/image_rect", "/epipole/left/camera_info",
        "/epipole/right/camera_info", "/epipole/disparity", "/epipole/depth", "/epipole/points",
        "/epipole/features"}) {
    EXPECT_EQ(t.counts.count(topic) ? t.counts.at(topic) : 0, t.output.delivered)
        << topic << ": every pair the output published";
  }
  EXPECT_EQ(t.counts.count("/tf_static") ? t.counts.at("/tf_static") : 0, 1u)
      << "latched: once, though it was sent before the match";
  EXPECT_GT(t.checks.depths, 0);
  EXPECT_GT(t.checks.points, 0);
  EXPECT_GT(t.checks.features, 0);
  EXPECT_GT(t.checks.calibration, 0) << "the calibration's health on /diagnostics";
}

// Another vendor's subscriber, as ROS 2's default rmw is: Fast DDS, knowing the types by name
// only, decoding the CDR with its own library.
TEST(Ros2Output, AnotherVendorsSubscriberGetsTheSameTopics) {
  const Taken t = take_topics(with_config("FASTRTPS_DEFAULT_PROFILES_FILE", "fastdds-loopback.xml",
                                          test::fastdds_listener_path()),
                              "fastdds");
  for (const char* topic : {"/epipole/left/image_rect", "/epipole/left/camera_info",
                            "/epipole/depth", "/epipole/points"}) {
    EXPECT_EQ(t.counts.count(topic) ? t.counts.at(topic) : 0, t.output.delivered)
        << topic << ": every pair the output published";
  }
  EXPECT_GT(t.checks.depths, 0);
  EXPECT_GT(t.checks.points, 0);
  EXPECT_GT(t.checks.calibration, 0) << "the calibration's health on /diagnostics";
}

// The ground under the rig as a robot's ROS 2 graph takes it: the simulated floor's plane as the
// transform of the ground's frame on /tf, the organised cloud without the floor when the board
// asks.
TEST(Ros2Output, TheGroundIsATransformAndTheFloorLeavesThePoints) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  ::unsetenv("CYCLONEDDS_URI");
  const int domain = own_domain();
  const hal::BackendOption scene{"scene", "ground"};
  const std::vector<std::string> overrides = {
      "outputs.ros2={domain: " + std::to_string(domain) +
          ", depth: 100, points_above_ground: true, every: {depth: 0}}",
      "stages.detect=false", "stages.sparse=false"};
  const BoardConfig config = load_board_config(
      std::filesystem::path(test::source_dir()) / "board" / "sim", overrides, std::span(&scene, 1));
  Firmware fw(config);
  ASSERT_TRUE(fw.calibration().has_value());
  const hal::SimScene& world_scene = hal::sim_settings(config.sections).chosen();
  const hal::GroundTruth truth = hal::world_ground_truth(*world_scene.world, *fw.calibration());
  Taken taken;
  RunSummary s;
  const json messages = listen_to(
      fw, with_config("CYCLONEDDS_URI", "cyclonedds-loopback.xml", test::ros2_listener_path()),
      domain, 8, "ground", s, taken);
  ASSERT_FALSE(messages.empty());
  int transforms = 0, clouds = 0, kept = 0, left_out = 0;
  for (const json& m : messages) {
    if (m["topic"] == "/tf") {
      ASSERT_EQ(m["transforms"].size(), 1u);
      const json& t = m["transforms"][0];
      EXPECT_EQ(t["parent"], "epipole_left_optical_frame");
      EXPECT_EQ(t["child"], "epipole_ground");
      const Eigen::Vector3d origin(t["translation"]["x"], t["translation"]["y"],
                                   t["translation"]["z"]);
      EXPECT_NEAR(origin.norm(), truth.height_m, 0.025);
      EXPECT_LT((origin.normalized() - truth.normal_down).norm(), 0.02);
      const json& r = t["rotation"];
      const Eigen::Quaterniond q(r["w"].get<double>(), r["x"].get<double>(), r["y"].get<double>(),
                                 r["z"].get<double>());
      EXPECT_NEAR(q.norm(), 1, 1e-9);
      // The ground frame's z is up, its x the camera's heading along the ground.
      EXPECT_LT((q * Eigen::Vector3d::UnitZ() + truth.normal_down).norm(), 0.02);
      EXPECT_NEAR((q * Eigen::Vector3d::UnitX()).dot(truth.normal_down), 0, 0.02);
      EXPECT_GT((q * Eigen::Vector3d::UnitX()).z(), 0.9);
      ++transforms;
    } else if (m["topic"] == "/epipole/points") {
      ++clouds;
      for (const json& p : m["points"]) {
        if (p[2].is_null()) {
          ++left_out;
          continue;
        }
        ++kept;
        const Eigen::Vector3d point(p[0], p[1], p[2]);
        // Clear of the floor by the board's ground.clearance_m (0.1 m), but for the ground's
        // error and the depth's far off (0.2 px of disparity at 5 m is 0.1 m of depth).
        EXPECT_GT(truth.height_m - truth.normal_down.dot(point), 0.05)
            << point.transpose() << " stands on the floor";
      }
    }
  }
  EXPECT_EQ(transforms, static_cast<int>(taken.output.delivered));
  EXPECT_EQ(clouds, static_cast<int>(taken.output.delivered));
  EXPECT_GT(kept, 0) << "the boxes and the wall stay";
  EXPECT_GT(left_out, kept) << "the floor is most of the view";
  std::printf("ground: %d transforms, %d clouds: %d points kept, %d left out\n", transforms, clouds,
              kept, left_out);
}

}  // namespace
}  // namespace epipole::firmware

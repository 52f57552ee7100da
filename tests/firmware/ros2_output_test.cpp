// The ROS 2 output as a robot's computer takes it: the firmware on the simulated board publishes
// over DDS on the loopback interface (its board file's defaults), and a subscriber in a process
// of its own (epipole-ros2-listener, CycloneDDS configured by the loopback-only file the tests
// pass) takes every topic. What it decodes must be what the pipeline computed.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "epipole/firmware/firmware.hpp"
#include "ros_message_checks.hpp"
#include "sim_rig.hpp"
#include "test_clients.hpp"
#include "test_paths.hpp"

namespace epipole::firmware {
namespace {

// A domain of this test run's own (the tests run in parallel; each domain has its own ports).
int own_domain() {
  return 100 + static_cast<int>(::getpid() % 100);
}

TEST(Ros2Output, ASubscriberInAnotherProcessGetsEveryTopicAsThePipelineComputedIt) {
  ::unsetenv("CYCLONEDDS_URI");  // the firmware takes the board file's network
  test::SimRig rig(96, 64, 6);
  const int domain = own_domain();
  // A writer history deep enough for the whole run: the simulated board runs far faster than
  // its trigger, and a reliable keep-last writer drops what its history cannot hold.
  BoardConfig config = rig.parse("outputs: {ros2: {domain: " + std::to_string(domain) +
                                 ", points_step: 4, depth: 100, every: {disparity: 1}}}\n");
  config.stages |= protocol::stage_bit(protocol::Stage::sparse);
  Firmware fw(rig.replaying(config, 3));  // its writers first: the listener waits for them
  Kept kept;
  fw.frame_loop().set_observer(&kept);

  const std::string command =
      "CYCLONEDDS_URI=file://" + (test::clients_dir() / "cyclonedds-loopback.xml").string() + " " +
      test::ros2_listener_path() + " " + std::to_string(domain) + " /epipole 30 6 2>&1";
  FILE* listener = popen(command.c_str(), "r");
  ASSERT_NE(listener, nullptr);
  std::array<char, 256> line{};
  const bool ready = std::fgets(line.data(), line.size(), listener) != nullptr &&
                     std::string(line.data()) == "ready\n";
  std::atomic<bool> stop{!ready};
  const RunSummary s = fw.run(30, stop);
  const test::ToolResult got = test::finish_tool(listener);
  ASSERT_TRUE(ready) << line.data() << got.out;
  ASSERT_EQ(got.exit_code, 0) << got.out;
  const OutputReport& ros2 = s.outputs.at(0);
  EXPECT_EQ(ros2.name, "ros2");
  EXPECT_EQ(ros2.failures, 0u);
  EXPECT_EQ(ros2.delivered + ros2.dropped, 30u);

  const json r = json::parse(got.out);
  std::map<std::string, std::uint64_t> counts;
  for (const json& m : r["messages"]) ++counts[m["topic"].get<std::string>()];
  for (const char* topic :
       {"/epipole/left/image_rect", "/epipole/right/image_rect", "/epipole/left/camera_info",
        "/epipole/right/camera_info", "/epipole/disparity", "/epipole/depth", "/epipole/points",
        "/epipole/features"}) {
    EXPECT_EQ(counts[topic], ros2.delivered) << topic << ": every pair the output published";
  }
  EXPECT_EQ(counts["/tf_static"], 1u) << "latched: once, though it was sent before the match";
  const RosChecks checks = check_ros_messages(r["messages"], kept, *fw.calibration(), rig);
  std::printf(
      "ros2: %zu messages taken (%llu pairs published, %llu dropped); checked %d depths, "
      "%d points, %d features\n",
      r["messages"].size(), static_cast<unsigned long long>(ros2.delivered),
      static_cast<unsigned long long>(ros2.dropped), checks.depths, checks.points, checks.features);
  EXPECT_GT(checks.depths, 0);
  EXPECT_GT(checks.points, 0);
  EXPECT_GT(checks.features, 0);
  EXPECT_EQ(checks.unmatched, 0);
}

}  // namespace
}  // namespace epipole::firmware

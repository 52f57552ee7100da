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

// The firmware on the simulated board with the ROS 2 output on (its board file's network
// defaults), a subscriber started by `listener` (a command line) once its writers exist: what the
// subscriber took, and what the output did.
struct Taken {
  json messages;
  OutputReport output;
  std::map<std::string, std::uint64_t> counts;  // messages by topic
  RosChecks checks;
};

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
  FILE* pipe =
      popen((listener + " " + std::to_string(domain) + " /epipole 30 6 2>&1").c_str(), "r");
  EXPECT_NE(pipe, nullptr);
  if (pipe == nullptr) return taken;
  std::array<char, 256> line{};
  const bool ready = std::fgets(line.data(), line.size(), pipe) != nullptr &&
                     std::string(line.data()) == "ready\n";
  // "ready" is the subscriber's readers matching the writers; the writers' side of the match
  // follows a discovery round later (a reliable writer delivers nothing written before it), which
  // under the sanitizers took longer than the first pair: a moment for it.
  if (ready) std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::atomic<bool> stop{!ready};
  const RunSummary s = fw.run(30, stop);
  const test::ToolResult got = test::finish_tool(pipe);
  EXPECT_TRUE(ready) << name << ": " << line.data() << got.out;
  EXPECT_EQ(got.exit_code, 0) << name << ": " << got.out;
  if (!ready || got.exit_code != 0 || s.outputs.size() != 1) return taken;
  taken.output = s.outputs[0];
  EXPECT_EQ(taken.output.name, "ros2");
  EXPECT_EQ(taken.output.failures, 0u);
  EXPECT_EQ(taken.output.delivered + taken.output.dropped, 30u);
  taken.messages = json::parse(got.out)["messages"];
  for (const json& m : taken.messages) ++taken.counts[m["topic"].get<std::string>()];
  taken.checks = check_ros_messages(taken.messages, kept, *fw.calibration(), rig);
  std::printf(
      "%s: %zu messages taken (%llu pairs published, %llu dropped); checked %d depths, "
      "%d points, %d features\n",
      name.c_str(), taken.messages.size(), static_cast<unsigned long long>(taken.output.delivered),
      static_cast<unsigned long long>(taken.output.dropped), taken.checks.depths,
      taken.checks.points, taken.checks.features);
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
}

}  // namespace
}  // namespace epipole::firmware

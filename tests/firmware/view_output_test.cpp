// The live view as Foxglove and Lichtblick take it: the firmware on the simulated board serves
// the Foxglove WebSocket protocol on the loopback interface, and Foxglove's own client library
// (tests/clients/foxglove-view.mjs: @foxglove/ws-protocol, @foxglove/rosmsg2-serialization)
// subscribes to every channel it advertises. What it decodes must be what the pipeline computed;
// a client that stops reading costs it messages, never the frame loop a wait.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include "epipole/firmware/firmware.hpp"
#include "error_of.hpp"
#include "loopback.hpp"
#include "ros_message_checks.hpp"
#include "sim_rig.hpp"
#include "test_clients.hpp"

namespace epipole::firmware {
namespace {

using test::free_port;
using test::listening;
using test::loopback;

// Keeps each pair's results and counts the pairs.
struct Counted final : FrameObserver {
  Kept kept;
  std::atomic<std::uint64_t> pairs{0};
  void on_frame(const FrameResult& r) override {
    kept.on_frame(r);
    ++pairs;
  }
};

// The firmware on the simulated board with the view on a free port, running in a thread of its
// own until the test stops it.
struct Served {
  test::SimRig rig{96, 64, 6};
  int port = free_port();
  std::unique_ptr<Firmware> fw;
  Counted observed;
  std::atomic<bool> stop{false};
  RunSummary summary;
  std::thread loop;

  explicit Served(const std::string& settings = "") {
    BoardConfig config =
        rig.parse("outputs: {view: {port: " + std::to_string(port) + settings + "}}\n");
    config.stages |= protocol::stage_bit(protocol::Stage::sparse);
    rig.add_cascade(config);
    fw = std::make_unique<Firmware>(rig.replaying(config, 3));
    fw->frame_loop().set_observer(&observed);
    loop = std::thread([this] { summary = fw->run(0, stop); });
  }
  ~Served() {
    stop = true;
    if (loop.joinable()) loop.join();
  }
  std::string url() const { return "ws://127.0.0.1:" + std::to_string(port) + "/"; }
  const OutputReport* view() const {
    for (const OutputReport& o : summary.outputs) {
      if (o.name == "view") return &o;
    }
    return nullptr;
  }
};

TEST(ViewOutput, FoxglovesClientGetsEveryChannelAsThePipelineComputedIt) {
  ASSERT_TRUE(test::clients_installed()) << "the test clients are not installed: scripts/setup.sh";
  Served served;
  ASSERT_NE(served.port, 0);
  ASSERT_TRUE(listening(served.port));
  const test::ToolResult got = test::run_client("foxglove-view.mjs", served.url() + " 5 6");
  served.stop = true;
  served.loop.join();
  ASSERT_EQ(got.exit_code, 0) << got.out;
  const json out = json::parse(got.out);
  EXPECT_EQ(out["protocol"], "foxglove.websocket.v1");
  EXPECT_EQ(out["server_info"]["name"], "epipole test-sim");
  std::map<std::string, int> counts;
  for (const json& m : out["messages"]) ++counts[m["topic"].get<std::string>()];
  ASSERT_EQ(out["channels"].size(), 11u);
  for (const json& c : out["channels"]) {
    const std::string topic = c["topic"];
    EXPECT_GE(counts[topic], topic == "/tf_static" || topic == "/diagnostics" ? 1 : 5) << topic;
  }
  EXPECT_EQ(counts["/tf_static"], 1) << "latched: sent once, when subscribed";
  const RosChecks checks = check_ros_messages(out["messages"], served.observed.kept,
                                              *served.fw->calibration(), served.rig);
  EXPECT_GT(checks.depths, 0);
  EXPECT_GT(checks.points, 0);
  EXPECT_GT(checks.features, 0);
  EXPECT_GT(checks.boxes, 0) << "the detections, drawn and labelled";
  ASSERT_NE(served.view(), nullptr);
  EXPECT_EQ(served.view()->failures, 0u);
  // Each channel keeps its freshest message for a client that is behind: a pair's image can be
  // replaced by the next pair's while the pair's depth already went out (a loaded machine). A
  // message without its pair's image only then.
  EXPECT_LE(static_cast<std::uint64_t>(checks.unmatched), served.view()->dropped)
      << "messages of pairs whose image never came, with no message replaced";
}

// A client that subscribes to everything and then stops reading: the frame loop goes on, 600
// pairs and more (were it waiting for the client, it would not), and the messages the client did
// not take are counted as dropped.
TEST(ViewOutput, AClientThatStopsReadingCostsMessagesNotTheLoop) {
  ASSERT_TRUE(test::clients_installed()) << "the test clients are not installed: scripts/setup.sh";
  Served served;
  ASSERT_NE(served.port, 0);
  ASSERT_TRUE(listening(served.port));
  FILE* client = popen(("node " + (test::clients_dir() / "foxglove-view.mjs").string() + " " +
                        served.url() + " 1000000 2 --stall 3600 2>&1")
                           .c_str(),
                       "r");
  ASSERT_NE(client, nullptr);
  std::array<char, 256> line{};
  const bool subscribed = std::fgets(line.data(), line.size(), client) != nullptr &&
                          std::string(line.data()).rfind("subscribed ", 0) == 0;
  EXPECT_TRUE(subscribed) << line.data();
  const std::uint64_t before = served.observed.pairs;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (served.observed.pairs < before + 600 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const std::uint64_t during = served.observed.pairs - before;
  if (subscribed) ::kill(std::stoi(std::string(line.data()).substr(11)), SIGTERM);
  test::finish_tool(client);
  served.stop = true;
  served.loop.join();
  EXPECT_GE(during, 600u) << "pairs while the client was not reading";
  ASSERT_NE(served.view(), nullptr);
  EXPECT_GT(served.view()->dropped, 0u) << "what the stalled client could not take";
  EXPECT_EQ(served.view()->failures, 0u);
}

// Every request it does not serve gets a status message and changes nothing; a client without
// the protocol's subprotocol, or one more than the board's `clients`, is refused at the
// handshake; a closed client's slot is free again.
TEST(ViewOutput, WhatItDoesNotServeIsRefusedAndSaidAndChangesNothing) {
  ASSERT_TRUE(test::clients_installed()) << "the test clients are not installed: scripts/setup.sh";
  Served served(", clients: 3");
  ASSERT_TRUE(listening(served.port));
  const test::ToolResult got = test::run_client("foxglove-misbehave.mjs", served.url() + " 3");
  served.stop = true;
  served.loop.join();
  ASSERT_EQ(got.exit_code, 0) << got.out;
  const json out = json::parse(got.out);
  EXPECT_FALSE(out["without_subprotocol"]);
  ASSERT_TRUE(out["connected"]);
  EXPECT_EQ(out["protocol"], "foxglove.websocket.v1");
  std::vector<std::string> said;
  for (const json& s : out["statuses"]) said.push_back(s["message"]);
  const auto has = [&](const std::string& text) {
    return std::any_of(said.begin(), said.end(),
                       [&](const std::string& s) { return s.find(text) != std::string::npos; });
  };
  EXPECT_EQ(said.size(), 7u) << got.out;
  EXPECT_TRUE(has("not a JSON object")) << got.out;
  EXPECT_TRUE(has("'setParameters' is not served")) << got.out;
  EXPECT_TRUE(has("no channel 999")) << got.out;
  EXPECT_TRUE(has("subscribe: its list is missing")) << got.out;
  EXPECT_TRUE(has("unsubscribe: no subscription 42")) << got.out;
  EXPECT_TRUE(has("read-only")) << got.out;
  EXPECT_TRUE(has("id 7 or channel")) << got.out;
  EXPECT_GT(out["messages_after"], 0) << "a proper subscription works after all that";
  EXPECT_EQ(out["subscription_of_first"], 7);
  EXPECT_EQ(out["messages_after_unsubscribe"], 0);
  EXPECT_EQ(out["others_connected"], 2);
  EXPECT_FALSE(out["one_too_many"]);
  EXPECT_TRUE(out["after_closing"]);
}

// A port another program holds: the firmware does not start, and says which port.
TEST(ViewOutput, APortInUseStopsTheStartNamingIt) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a = loopback(0);
  socklen_t size = sizeof a;
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(fd, 1), 0);
  ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &size), 0);
  const int port = ntohs(a.sin_port);
  const test::SimRig rig(96, 64, 6);
  const BoardConfig config = rig.parse("outputs: {view: {port: " + std::to_string(port) + "}}\n");
  const std::string error = test::error_of([&] {
    Firmware fw(rig.replaying(config, 1));
    const std::atomic<bool> stop{false};
    fw.run(1, stop);
  });
  ::close(fd);
  EXPECT_NE(error.find("outputs.view: cannot listen on 127.0.0.1:" + std::to_string(port)),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace epipole::firmware

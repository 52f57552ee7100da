// Fixed memory: over more than a thousand frame pairs of the simulated board, in the steady
// state, the firmware allocates nothing in any of its threads (frame loop, stereo workers, the
// link's thread).
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "allocation_counter.hpp"
#include "board_scene.hpp"
#include "epipole/firmware/firmware.hpp"
#include "foxglove_socket.hpp"
#include "maps_thread_wait.hpp"
#include "sim_rig.hpp"
#include "termios/termios_serial.hpp"

namespace epipole::firmware {
namespace {

// Reads the program's allocation count at two frames of the run; `each` (made before the run)
// sees every frame.
struct Sampler final : FrameObserver {
  std::uint32_t first, last;
  std::size_t at_first = 0, at_last = 0;
  std::size_t detections = 0, points = 0;  // the stages did work
  std::function<void(std::uint32_t)> each;
  Sampler(std::uint32_t a, std::uint32_t b) : first(a), last(b) {}
  void on_frame(const FrameResult& r) override {
    detections += r.detections.size();
    points += r.points.size();
    if (r.frame == first) at_first = test::allocations_in_all_threads();
    if (r.frame == last) at_last = test::allocations_in_all_threads();
    if (each) each(r.frame);
  }
};

TEST(FirmwareAllocations, CounterSeesAllocationsOfOtherThreads) {
  const std::size_t before = test::allocations_in_all_threads();
  std::thread([] { auto p = std::make_unique<int>(1); }).join();
  EXPECT_GE(test::allocations_in_all_threads(), before + 1)
      << "the counter must see other threads, or the test below proves nothing";
}

// The memory report is what the firmware really keeps: the heap it holds once made, less the
// small objects (configuration, strings, the parts' own objects) it does not list.
TEST(FirmwareAllocations, TheMemoryReportIsTheHeapTheFirmwareHolds) {
  test::SimRig rig(320, 240, 8);
  BoardConfig config = rig.parse(
      "threads: {count: 2}\nsnapshot_directory: snapshots\n"
      "outputs: {mcap: {directory: recordings, continuous: true}}\n");
  config.stages |= protocol::stage_bit(protocol::Stage::sparse);
  rig.add_cascade(config);
  const std::size_t before = test::live_bytes_in_all_threads();
  std::size_t held = 0;
  MemoryReport report;
  {
    const Firmware fw(rig.replaying(config, 2));
    held = test::live_bytes_in_all_threads() - before;
    report = fw.memory_report();
  }
  std::size_t listed = 0;
  std::vector<std::string> names;
  for (const MemoryReport::Part& p : report.parts()) {
    EXPECT_GT(p.bytes, 0u) << p.name;
    listed += p.bytes;
    names.push_back(p.name);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"rectify", "corners", "disparity", "sparse", "detect",
                                             "ground", "odometry", "link", "frame loop",
                                             "snapshots", "output mcap", Firmware::kCameras}));
  EXPECT_EQ(listed, report.total());
  std::printf("memory report %zu B, heap held %zu B\n", report.total(), held);
  EXPECT_LE(report.total(), held) << "nothing listed that was not allocated";
  EXPECT_GE(report.total(), held - held / 10) << "at least 90 % of what it holds is listed";
  EXPECT_LE(test::live_bytes_in_all_threads(), before + 64 * 1024) << "and given back";
}

class SteadyState : public testing::TestWithParam<BoardConfig::LinkProtocol> {};

TEST_P(SteadyState, NoAllocationOverAThousandFrames) {
  // Small images keep a thousand frames quick under qemu too; every stage, the link and every
  // output run (the recording's thread allocates nothing per pair either, once its file is
  // open).
  test::SimRig rig(128, 64, 6);
  // Every output: the recording, ROS 2 over DDS on loopback in a domain of this run's own (no
  // subscriber: DDS serialises and drops every sample all the same), and the live view with a
  // client subscribed to every channel (connected at pair 5, before the count starts).
  const int view_port = test::free_port();
  BoardConfig config = rig.parse(
      "threads: {count: 2}\n"
      "outputs: {mcap: {directory: recordings, continuous: true, every: 1, file_mb: 64,\n"
      "                 total_mb: 64},\n"
      "          ros2: {domain: " +
      std::to_string(100 + ::getpid() % 100) +
      "},\n"
      "          view: {port: " +
      std::to_string(view_port) + "}}\n");
  config.stereo.max_disparity = 16;
  config.stereo.hole_fill = 32;  // the post-filters too
  config.stereo.temporal_percent = 40;
  config.stereo.spatial_percent = 50;
  config.stereo.fill_occlusions = true;
  config.obstacles.min_confidence = 64;  // and the confidence
  config.stages |= protocol::stage_bit(protocol::Stage::sparse);
  rig.add_cascade(config);
  config.serial.backend = "pty";
  config.serial.protocol = GetParam();
  config.serial.port.baud = 4'000'000;
  Firmware fw(rig.replaying(config, 3));
  hal::TermiosSerialPort robot({fw.board().serial_peer(), 115200});
  std::atomic<bool> reading{true};
  std::thread reader([&] {  // the robot reads, so the link never fills up
    std::array<std::byte, 4096> buffer{};
    while (reading) robot.read(buffer, 10'000'000);
  });
  Sampler sampler(20, 1020);
  std::unique_ptr<test::FoxgloveSocket> viewer;
  // The viewer connects on the loop's thread at pair 5 (or the first after it), which waits until
  // it is subscribed (the latched transforms came): its connection's allocations are not the steady
  // state's.
  const auto connect_viewer = [&](std::uint32_t frame) {
    if (frame < 5 || viewer != nullptr) return;
    viewer = std::make_unique<test::FoxgloveSocket>(view_port);
    for (int i = 0; i < 3000 && viewer->ok() && viewer->frames() == 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  };
  sampler.each = connect_viewer;
  if (GetParam() == BoardConfig::LinkProtocol::epipole) {
    // The robot's run-time commands, applied on the way: the trigger rate and the exposure.
    sampler.each = [&robot, &fw, connect_viewer](std::uint32_t frame) {
      connect_viewer(frame);
      // Each command is with the link's thread before the loop goes on (a loaded machine can
      // hold that thread back past the run's end).
      const auto send = [&](const protocol::Message& m, std::uint16_t sequence) {
        std::array<std::uint8_t, protocol::kMaxFrameSize> bytes{};
        const std::size_t n = protocol::encode_frame(m, sequence, bytes);
        const std::uint64_t received = fw.link().counters().commands;
        robot.write(std::as_bytes(std::span(bytes.data(), n)), 100'000'000);
        for (int i = 0; i < 2500 && fw.link().counters().commands == received; ++i) {
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
      };
      if (frame == 300) send(protocol::SetTriggerRate{20'000}, 1);
      if (frame == 400) send(protocol::SetExposure{3000, 600}, 2);
      if (frame == 700) send(protocol::SetTriggerRate{30'000}, 3);
      if (frame == 800) send(protocol::SetExposure{0, 0}, 4);
    };
  }
  fw.frame_loop().set_observer(&sampler);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(1030, stop);
  reading = false;
  reader.join();
  ASSERT_EQ(s.frames, 1030u);
  EXPECT_GT(s.health_messages, 30u);
  // The virtual clock lets the loop outrun the link thread: some messages may be dropped.
  EXPECT_GT(s.link.messages_sent, 100u);
  EXPECT_GE(s.link.messages_sent + s.link.messages_dropped, 1030u);
  EXPECT_GT(sampler.at_first, 0u);
  EXPECT_GT(sampler.detections, 0u);
  EXPECT_GT(sampler.points, 0u);
  ASSERT_NE(viewer, nullptr);
  EXPECT_TRUE(viewer->ok()) << "the viewer connected and subscribed";
  EXPECT_GT(viewer->frames(), 100u) << "and took messages";
  ASSERT_EQ(s.outputs.size(), 3u);
  for (const OutputReport& o : s.outputs) {
    EXPECT_GT(o.delivered, 100u) << o.name << " did its work";
    EXPECT_EQ(o.failures, 0u) << o.name;
  }
  EXPECT_EQ(sampler.at_last - sampler.at_first, 0u)
      << "operator new calls between frames 20 and 1020";
  if (GetParam() == BoardConfig::LinkProtocol::epipole) {
    EXPECT_EQ(s.commands, 4u) << "the commands were applied within the counted frames";
    EXPECT_EQ(s.faults.bad_commands, 0u);
    EXPECT_EQ(fw.board().trigger()->config().rate_hz, 30.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Protocols, SteadyState,
                         testing::Values(BoardConfig::LinkProtocol::epipole,
                                         BoardConfig::LinkProtocol::mavlink),
                         [](const auto& param_info) {
                           return param_info.param == BoardConfig::LinkProtocol::epipole
                                      ? "epipole"
                                      : "mavlink";
                         });

// A correction while running allocates nothing either: the faces scene with its right camera
// turned, online correction on and a short window; from the third pair on, the estimates, a map
// rebuilt on its own thread and put in place, and the window started again.
TEST(FirmwareAllocations, CorrectingADriftedRigAllocatesNothing) {
  if (!hal::can_load_scenes()) GTEST_SKIP() << "this build replays no image files";
  const test::BoardScene scene = test::board_scene(
      "faces", {"sim.scenes.faces.drift={pitch_deg: 0.3, roll_deg: 0.2}",
                "calibration_health.online_correction=true", "calibration_health.window_pairs=5"});
  const BoardConfig& config = scene.config;
  const hal::StereoImages& images = scene.images;
  Pipeline pipeline(config, scene.rig);
  RigCorrection& correction = *pipeline.rig_correction();
  std::size_t before = 0;
  // A correction comes after the 5-pair window; qemu's pairs are slow.
  const std::uint32_t pairs = EPIPOLE_UNDER_QEMU ? 16 : 30;
  for (std::uint32_t i = 0; i < pairs; ++i) {
    if (i == 3) before = test::allocations_in_all_threads();
    const FrameResult& r =
        pipeline.process(images.left[0].view(), images.right[0].view(), i, 0, config.stages);
    if (r.drift) correction.consider(*r.drift);
    EXPECT_TRUE(test::wait_for_maps_thread(correction));
  }
  EXPECT_GE(correction.corrections(), 1);
  EXPECT_EQ(test::allocations_in_all_threads() - before, 0u);
}

}  // namespace
}  // namespace epipole::firmware

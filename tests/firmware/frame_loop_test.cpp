// The frame loop on a small simulated board: the whole pipeline, what it publishes, health,
// faults and recovery, the robot's commands.
#include "epipole/firmware/frame_loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

#include "epipole/firmware/firmware.hpp"
#include "epipole/hal/serial_port.hpp"
#include "sim_rig.hpp"

namespace epipole::firmware {
namespace {

using protocol::Stage;

// What the loop did, frame by frame, and every message it published.
struct Recorder final : FrameObserver {
  struct Seen {
    std::uint32_t frame;
    hal::Nanoseconds trigger_ns;
    StageMask stages;
    int centre_disparity;  // x16, at the image centre; -1 without disparity
    std::size_t corners;
    std::uint16_t nearest_mm;  // of the middle sector; 0 without obstacles
  };
  std::vector<Seen> frames;
  std::vector<protocol::Message> messages;
  std::function<void(const FrameResult&)> also;

  Recorder() {
    frames.reserve(4096);
    messages.reserve(16384);
  }
  void on_frame(const FrameResult& r) override {
    Seen s{r.frame, r.trigger_ns, r.stages, -1, r.corners_left.size(), 0};
    if (!r.disparity.empty()) {
      s.centre_disparity = r.disparity(r.disparity.width() / 2, r.disparity.height() / 2);
    }
    if (r.obstacles != nullptr) s.nearest_mm = r.obstacles->nearest_mm[r.obstacles->count / 2];
    frames.push_back(s);
    if (also) also(r);
  }
  void on_message(const protocol::Message& m) override { messages.push_back(m); }

  template <typename T>
  std::vector<T> all() const {
    std::vector<T> out;
    for (const auto& m : messages) {
      if (const T* t = std::get_if<T>(&m)) out.push_back(*t);
    }
    return out;
  }
};

TEST(FrameLoop, RunsEveryStageOnEveryPairAndPublishesIt) {
  test::SimRig rig;
  Firmware fw(rig.config, rig.images());
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(90, stop);  // 3 s at 30 Hz

  EXPECT_EQ(s.frames, 90u);
  EXPECT_EQ(s.timeouts, 0u);
  ASSERT_EQ(recorder.frames.size(), 90u);
  const hal::Nanoseconds period = rig.config.pairing.trigger_period;
  for (std::size_t i = 0; i < recorder.frames.size(); ++i) {
    const auto& f = recorder.frames[i];
    EXPECT_EQ(f.frame, i) << "every trigger, in order (no faults, no backlog)";
    EXPECT_EQ(f.trigger_ns, static_cast<hal::Nanoseconds>(f.frame) * period)
        << "results carry the trigger edge's time";
    EXPECT_EQ(f.stages, stage_bit(Stage::capture) | stage_bit(Stage::rectify) |
                            stage_bit(Stage::corners) | stage_bit(Stage::disparity));
    EXPECT_NEAR(f.centre_disparity, rig.disparity * 16, 8) << "frame " << f.frame;
    EXPECT_GT(f.corners, 20u);
    EXPECT_NEAR(f.nearest_mm, rig.depth() * 1000, 0.05 * rig.depth() * 1000);
  }
  const auto summaries = recorder.all<protocol::FrameSummary>();
  ASSERT_EQ(summaries.size(), 90u);
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    EXPECT_EQ(summaries[i].frame, i);
    EXPECT_GT(summaries[i].valid_disparity_permille, 500);
    EXPECT_GT(summaries[i].corners_right, 20);
  }
  EXPECT_EQ(recorder.all<protocol::Obstacles>().size(), 90u);
  // Health once per second of the board's (virtual) clock: at 1 s and 2 s of the 3 s run.
  const auto health = recorder.all<protocol::Health>();
  ASSERT_GE(health.size(), 2u);
  EXPECT_EQ(health[0].fps_centi, 3000);
  EXPECT_EQ(health[0].dropped, 0u);
  EXPECT_EQ(health[0].unpaired_frames, 0);
  // Without charging compute time to the virtual clock, latency is the cameras' own: exposure
  // delay + readout of the simulated sensor (5 + 2 ms).
  EXPECT_EQ(health[0].latency_p50_us, 7000u);
  EXPECT_GT(health[0].stage_us[static_cast<std::size_t>(Stage::disparity)], 0u);
  EXPECT_EQ(s.health_messages, health.size());
}

TEST(FrameLoop, PublishesSparsePointsAtTheRigsDepthAndTheCalibrationHealth) {
  test::SimRig rig;
  BoardConfig config = rig.config;
  config.stages.sparse = true;
  config.sparse.max_points = 20;
  Firmware fw(config, rig.images());
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  fw.run(45, stop);
  const auto summaries = recorder.all<protocol::FrameSummary>();
  const auto points = recorder.all<protocol::Points>();
  ASSERT_EQ(points.size(), summaries.size()) << "every frame has points";
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(points[i].frame, summaries[i].frame);
    EXPECT_EQ(points[i].count, summaries[i].points);
    EXPECT_EQ(points[i].count, 20) << "the textured images have far more matches than 20";
    for (int k = 0; k < points[i].count; ++k) {
      const protocol::Point& p = points[i].items[static_cast<std::size_t>(k)];
      EXPECT_NEAR(p.z_mm, rig.depth() * 1000, 0.03 * rig.depth() * 1000)
          << "frame " << points[i].frame << " point " << k;
      // X from the image position: (u - cx) * Z / f.
      const double u = p.u_x16 / 16.0;
      EXPECT_NEAR(p.x_mm, (u - (rig.width - 1) / 2.0) * p.z_mm / test::SimRig::kFocal, 3.0);
    }
  }
  const auto health = recorder.all<protocol::CalibrationHealth>();
  ASSERT_GE(health.size(), 1u) << "with each health message";
  EXPECT_GT(health[0].matches, 20);
  EXPECT_EQ(health[0].median_offset_centipx, 0) << "an ideal rig: matches on the same rows";
}

TEST(FrameLoop, ChargingComputeTimeSkipsStalePairs) {
  // A trigger far faster than the host can process: the loop takes the freshest pair and
  // counts the ones it skipped; latency stays bounded instead of growing.
  test::SimRig rig(160, 96, 8, "");
  BoardConfig config = rig.parse("");
  config.trigger.line.rate_hz = 1000;
  config.trigger.line.pulse_width = 100'000;
  config.pairing.trigger_period = 1'000'000;
  config.pairing.tolerance = 200'000;
  config.pairing.edge_tolerance = 200'000;
  config.sim.charge_compute = true;
  Firmware fw(config, rig.images());
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(40, stop);
  EXPECT_EQ(s.frames, 40u);
  EXPECT_GT(s.stale + s.pairing.unpaired_left + s.pairing.unpaired_right, 0u);
  for (std::size_t i = 1; i < recorder.frames.size(); ++i) {
    EXPECT_GT(recorder.frames[i].frame, recorder.frames[i - 1].frame);
  }
}

TEST(FrameLoop, DroppedFramesAreCountedAndNeverMispaired) {
  test::SimRig rig;
  BoardConfig config = rig.config;
  config.sim.drop_rate = 0.1;
  config.sim.seed = 5;
  Firmware fw(config, rig.images());
  Recorder recorder;
  // Both halves of every pair must come from one trigger: the right view is the left one
  // shifted, so a mispaired pair would not have the rig's disparity... and the sequences agree.
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(150, stop);
  EXPECT_EQ(s.frames, 150u);
  const hal::PairingCounters& p = s.pairing;
  EXPECT_GT(p.unpaired_left + p.unpaired_right, 5u) << "10 % of frames dropped on each side";
  EXPECT_GT(s.faults.dropped_pairs, 5u);
  for (const auto& f : recorder.frames) {
    EXPECT_NEAR(f.centre_disparity, rig.disparity * 16, 8) << "frame " << f.frame;
  }
  const auto health = recorder.all<protocol::Health>();
  ASSERT_FALSE(health.empty());
  EXPECT_GT(health.back().unpaired_frames, 0);
  EXPECT_GT(health.back().dropped, 0u);
}

TEST(FrameLoop, RecoversFromALostCameraWithoutRestarting) {
  test::SimRig rig;
  Firmware fw(rig.config, rig.images());
  hal::SimFault gone;
  gone.kind = hal::SimFaultKind::disconnect;
  gone.sequence = 30;
  gone.count = 2;  // two reopen attempts fail before the camera is back
  fw.board().sim_camera(hal::Side::left)->inject(gone);
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(120, stop);
  EXPECT_EQ(s.frames, 120u) << "the loop kept going";
  EXPECT_GE(s.faults.camera_reopens, 1u);
  EXPECT_GT(recorder.frames.back().frame, 30u);
  // There is a gap where the camera was gone, and frames after it.
  bool gap = false;
  for (std::size_t i = 1; i < recorder.frames.size(); ++i) {
    gap = gap || recorder.frames[i].frame > recorder.frames[i - 1].frame + 1;
  }
  EXPECT_TRUE(gap);
  const auto health = recorder.all<protocol::Health>();
  ASSERT_FALSE(health.empty());
  EXPECT_GE(health.back().camera_reopens, 1);
}

// A board with a link on a pseudo-terminal, and the robot at its other end.
struct LinkedRig {
  test::SimRig rig;
  BoardConfig config;
  std::unique_ptr<Firmware> fw;
  std::unique_ptr<hal::TermiosSerialPort> robot;
  protocol::FrameDecoder decoder;
  explicit LinkedRig(const std::string& extra = "",
                     BoardConfig::LinkProtocol protocol = BoardConfig::LinkProtocol::epipole) {
    config = rig.parse(extra);
    config.serial.backend = "pty";
    config.serial.protocol = protocol;
    fw = std::make_unique<Firmware>(config, rig.images());
    robot = std::make_unique<hal::TermiosSerialPort>(
        hal::SerialConfig{fw->board().serial_peer(), 115200});
  }
  void send(const protocol::Message& m, std::uint16_t sequence) {
    std::array<std::uint8_t, protocol::kMaxFrameSize> frame{};
    const std::size_t n = protocol::encode_frame(m, sequence, frame);
    ASSERT_EQ(robot->write(std::as_bytes(std::span(frame.data(), n)), 1'000'000'000).status,
              hal::IoStatus::ok);
  }
  std::vector<protocol::DecodedMessage> receive() {
    std::vector<protocol::DecodedMessage> out;
    std::array<std::byte, 4096> buffer{};
    for (;;) {
      const hal::IoResult r = robot->read(buffer, 200'000'000);
      if (r.status != hal::IoStatus::ok) return out;
      for (std::size_t i = 0; i < r.bytes; ++i) {
        if (auto m = decoder.push(static_cast<std::uint8_t>(buffer[i]))) out.push_back(*m);
      }
    }
  }
};

TEST(FrameLoop, AppliesTheRobotsCommandsAndAcknowledgesThem) {
  LinkedRig linked("snapshot_directory: snapshots\n");
  Recorder recorder;
  // The commands go out once the loop runs; the loop is slowed to real time a little, so
  // that the link thread has read them before the run is over.
  bool sent = false;
  recorder.also = [&](const FrameResult& r) {
    if (r.frame == 5 && !sent) {
      sent = true;
      linked.send(protocol::SetStages{static_cast<std::uint16_t>(stage_bit(Stage::rectify) |
                                                                 stage_bit(Stage::corners))},
                  100);
      linked.send(protocol::Snapshot{}, 101);
      linked.send(protocol::SetStages{0x8000}, 102);  // an unknown stage: rejected
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(200, stop);
  const auto received = linked.receive();
  EXPECT_EQ(s.commands, 3u);

  // Disparity stops after the command, and never comes back.
  std::size_t first_off = recorder.frames.size();
  for (std::size_t i = 0; i < recorder.frames.size(); ++i) {
    if ((recorder.frames[i].stages & stage_bit(Stage::disparity)) == 0) {
      first_off = i;
      break;
    }
  }
  ASSERT_LT(first_off, recorder.frames.size()) << "the stages command took effect";
  EXPECT_GT(first_off, 5u);
  for (std::size_t i = first_off; i < recorder.frames.size(); ++i) {
    EXPECT_EQ(recorder.frames[i].centre_disparity, -1) << i;
    EXPECT_NE(recorder.frames[i].stages & stage_bit(Stage::corners), 0) << i;
  }
  std::vector<protocol::CommandAck> acks;
  for (const auto& m : received) {
    if (const auto* a = std::get_if<protocol::CommandAck>(&m.message)) acks.push_back(*a);
  }
  ASSERT_EQ(acks.size(), 3u);
  std::sort(acks.begin(), acks.end(),
            [](const auto& a, const auto& b) { return a.command_sequence < b.command_sequence; });
  EXPECT_EQ(acks[0].status, protocol::AckStatus::ok);
  EXPECT_EQ(acks[1].status, protocol::AckStatus::ok) << "the snapshot was taken";
  EXPECT_EQ(acks[2].status, protocol::AckStatus::rejected);
  // The snapshot's files.
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(linked.rig.dir.path() / "snapshots")) {
    files += e.path().extension() == ".pgm" && std::filesystem::file_size(e.path()) > 1000 ? 1 : 0;
  }
  EXPECT_GE(files, 4u) << "raw and rectified left and right";
  // Everything the robot received was valid, with increasing sequence numbers.
  EXPECT_EQ(linked.decoder.stats().bad_crc + linked.decoder.stats().bad_cobs, 0u);
  EXPECT_EQ(linked.decoder.stats().lost, 0u);
}

TEST(FrameLoop, StopsWhenAskedAndDrainsTheLink) {
  LinkedRig linked;
  std::atomic<bool> stop{false};
  Recorder recorder;
  recorder.also = [&](const FrameResult& r) {
    if (r.frame == 20) stop = true;
  };
  linked.fw->frame_loop().set_observer(&recorder);
  const RunSummary s = linked.fw->run(0, stop);
  EXPECT_EQ(s.frames, 21u);
  const auto received = linked.receive();
  std::size_t summaries = 0;
  for (const auto& m : received) {
    summaries += std::holds_alternative<protocol::FrameSummary>(m.message) ? 1 : 0;
  }
  EXPECT_EQ(summaries, 21u) << "everything published before the stop reached the robot";
}

TEST(FrameLoop, MavlinkModeSendsObstacleDistanceEveryFrame) {
  LinkedRig linked("", BoardConfig::LinkProtocol::mavlink);
  const std::atomic<bool> stop{false};
  linked.fw->run(30, stop);
  std::vector<std::uint8_t> bytes;
  std::array<std::byte, 4096> buffer{};
  for (;;) {
    const hal::IoResult r = linked.robot->read(buffer, 200'000'000);
    if (r.status != hal::IoStatus::ok) break;
    for (std::size_t i = 0; i < r.bytes; ++i) bytes.push_back(static_cast<std::uint8_t>(buffer[i]));
  }
  int heartbeats = 0;
  int distances = 0;
  for (std::size_t at = 0; at < bytes.size();) {
    const auto f = mavlink::parse_frame(std::span(bytes.data() + at, bytes.size() - at));
    ASSERT_TRUE(f) << "a valid MAVLink 2 frame at byte " << at;
    heartbeats += f->message_id == mavlink::kHeartbeatId ? 1 : 0;
    distances += f->message_id == mavlink::kObstacleDistanceId ? 1 : 0;
    at += mavlink::kHeaderSize + f->length + mavlink::kChecksumSize;
  }
  EXPECT_EQ(distances, 30);
  EXPECT_GE(heartbeats, 1);
}

TEST(FrameLoop, CalibrationOfAnotherSizeIsAnError) {
  test::SimRig rig;
  calib::save_calibration(rig.dir.path() / "rig.yaml", test::ideal_rig(320, 240, 100, 0.1));
  try {
    Firmware fw(rig.config, rig.images());
    FAIL() << "the calibration does not fit";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is for 320x240 images but the cameras deliver 160x96"),
              std::string::npos)
        << e.what();
  }
}

TEST(FrameLoop, MemoryBudgetIsEnforced) {
  test::SimRig rig(160, 96, 8, "memory_budget_mb: 0.01\n");
  EXPECT_THROW(Firmware(rig.config, rig.images()), Error);
}

}  // namespace
}  // namespace epipole::firmware

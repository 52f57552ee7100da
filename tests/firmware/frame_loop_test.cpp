// The frame loop on a small simulated board: the whole pipeline, what it publishes, health,
// faults and recovery, the robot's commands.
#include "epipole/firmware/frame_loop.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include "board_scene.hpp"
#include "epipole/firmware/cascade_file.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/hal/serial_port.hpp"
#include "error_of.hpp"
#include "maps_thread_wait.hpp"
#include "sim_rig.hpp"
#include "termios/termios_serial.hpp"
#include "test_paths.hpp"
#include "trigger_accounting.hpp"

namespace epipole::firmware {
namespace {

using protocol::Stage;

// What the loop did, frame by frame, and every message it published.
// How often `what` occurs in `text` (journal lines).
std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = 0; (at = text.find(what, at)) != std::string::npos; ++at) ++n;
  return n;
}

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
  // Set once `health_to_stop` health messages came (0: never).
  std::atomic<bool> stop{false};
  int health_to_stop = 0;
  int health_seen = 0;

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
  void on_message(const protocol::Message& m) override {
    messages.push_back(m);
    if (std::holds_alternative<protocol::Health>(m) && ++health_seen == health_to_stop) {
      stop.store(true, std::memory_order_relaxed);
    }
  }

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
  Firmware fw(rig.replaying(rig.config));
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
                            stage_bit(Stage::corners) | stage_bit(Stage::disparity) |
                            stage_bit(Stage::ground));
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
    EXPECT_EQ(summaries[i].flags, 0) << "trigger_ns is the recorded edge";
  }
  EXPECT_EQ(recorder.all<protocol::Obstacles>().size(), 90u);
  EXPECT_EQ(recorder.all<protocol::DepthGrid>().size(), 0u) << "the board has no depth_grid";
  // Health once per second of the board's (virtual) clock: at 1 s and 2 s of the 3 s run.
  const auto health = recorder.all<protocol::Health>();
  ASSERT_GE(health.size(), 2u);
  EXPECT_EQ(health[0].fps_centi, 3000);
  EXPECT_EQ(health[0].dropped, 0u);
  EXPECT_EQ(health[0].unpaired_frames, 0);
  // Without charging compute time to the virtual clock, latency is the cameras' own: exposure
  // delay + readout of the simulated sensor (5 + 2 ms).
  EXPECT_EQ(health[0].latency_p50_us, 7000u);
  // The simulated sensor stamps a frame at the end of its exposure: a pair the loop takes at once
  // has waited its readout.
  EXPECT_EQ(health[0].wait_p50_us, 2000u);
  EXPECT_EQ(health[0].wait_p99_us, 2000u);
  // The busy share compares the host's time with the virtual clock's (compute not charged).
  EXPECT_LE(health[0].busy_permille, 1000);
  EXPECT_GT(health[0].stage_us[static_cast<std::size_t>(Stage::disparity)], 0u);
  EXPECT_EQ(health[0].flags, 0) << "calibrated";
  EXPECT_EQ(s.health_messages, health.size());
}

// With the board's depth grid, every pair's grid follows its summary: the rig's plane fills
// every cell at its depth. Without the board key there is none (the test above).
TEST(FrameLoop, TheDepthGridGoesWithEachPair) {
  test::SimRig rig;
  BoardConfig config = rig.parse("depth_grid: {columns: 8, rows: 6}\n");
  Firmware fw(rig.replaying(config));
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  EXPECT_EQ(fw.run(20, stop).frames, 20u);
  const auto grids = recorder.all<protocol::DepthGrid>();
  ASSERT_EQ(grids.size(), 20u);
  for (std::size_t i = 0; i < grids.size(); ++i) {
    const protocol::DepthGrid& g = grids[i];
    EXPECT_EQ(g.frame, i);
    EXPECT_EQ(g.columns, 8);
    ASSERT_EQ(g.count, 48);
    EXPECT_GT(g.field_of_view_centideg, g.vertical_field_of_view_centideg) << "a wide view";
    int near_the_plane = 0;
    for (int c = 0; c < g.count; ++c) {
      const double mm = g.nearest_mm[static_cast<std::size_t>(c)];
      near_the_plane += std::abs(mm - rig.depth() * 1000) < 0.05 * rig.depth() * 1000 ? 1 : 0;
    }
    // The left border's columns have no disparity (nothing to their left in the right image).
    EXPECT_GE(near_the_plane, 40) << "frame " << i;
  }
}

// A board fresh from its package names a calibration file that `epipole calibrate` has not made
// yet: the firmware runs without it, and every health message says so.
TEST(FrameLoop, RunsUncalibratedUntilTheCalibrationFileIsMade) {
  test::SimRig rig;
  std::filesystem::remove(rig.dir.path() / "rig.yaml");
  Firmware fw(rig.replaying(rig.config));
  EXPECT_FALSE(fw.calibration());
  EXPECT_EQ(fw.missing_calibration(), rig.dir.path() / "rig.yaml");
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  EXPECT_EQ(fw.run(90, stop).frames, 90u);
  // What runs without a calibration runs: corners and disparity on the images as they come.
  for (const auto& f : recorder.frames) {
    EXPECT_EQ(f.stages,
              stage_bit(Stage::capture) | stage_bit(Stage::corners) | stage_bit(Stage::disparity));
    EXPECT_NEAR(f.centre_disparity, rig.disparity * 16, 8);
  }
  EXPECT_EQ(recorder.all<protocol::Obstacles>().size(), 0u) << "no depth without calibration";
  const auto health = recorder.all<protocol::Health>();
  ASSERT_GE(health.size(), 2u);
  for (const auto& h : health) EXPECT_EQ(h.flags, protocol::kHealthNotCalibrated);

  // A file that is there but does not read is a configuration error, not a missing one; so is
  // a simulated scene's calibration that is not there (a mistake in the board file, not a board
  // waiting for its calibration).
  std::ofstream(rig.dir.path() / "rig.yaml") << "version: [\n";
  EXPECT_NE(test::error_of([&] { Firmware broken(rig.replaying(rig.config)); }).find("rig.yaml"),
            std::string::npos);
  BoardConfig scene = rig.config;
  test::sim(scene).scenes[0].calibration = rig.dir.path() / "scene-rig.yaml";
  EXPECT_NE(test::error_of([&] { Firmware missing(rig.replaying(scene)); }).find("scene-rig.yaml"),
            std::string::npos);
}

TEST(FrameLoop, PublishesSparsePointsAtTheRigsDepthAndTheCalibrationHealth) {
  test::SimRig rig;
  BoardConfig config = rig.config;
  config.stages |= protocol::stage_bit(protocol::Stage::sparse);
  config.sparse.max_points = 20;
  Firmware fw(rig.replaying(config));
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

TEST(FrameLoop, DetectionsCarryTheirDepth) {
  test::SimRig rig;
  BoardConfig config = rig.config;
  rig.add_cascade(config);
  Firmware fw(rig.replaying(config));
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  fw.run(30, stop);
  const auto summaries = recorder.all<protocol::FrameSummary>();
  const auto detections = recorder.all<protocol::Detections>();
  ASSERT_EQ(detections.size(), summaries.size()) << "a detections message every frame";
  int boxes = 0;
  int with_depth = 0;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    EXPECT_EQ(detections[i].frame, summaries[i].frame);
    EXPECT_EQ(detections[i].count, summaries[i].detections);
    for (int k = 0; k < detections[i].count; ++k) {
      const protocol::Detection& d = detections[i].items[static_cast<std::size_t>(k)];
      ++boxes;
      EXPECT_LE(d.x + d.width, rig.width);
      EXPECT_LE(d.y + d.height, rig.height);
      EXPECT_GE(d.width, 20);
      if (d.depth_mm == protocol::kUnknownDepth) continue;
      ++with_depth;
      // The scene is one plane at the rig's depth.
      EXPECT_NEAR(d.depth_mm, rig.depth() * 1000, 0.03 * rig.depth() * 1000);
    }
  }
  EXPECT_GT(boxes, 0) << "the random cascade fires on the textured images";
  EXPECT_GT(with_depth, boxes / 2);
}

TEST(FrameLoop, AnXmlCascadeIsRefusedWithTheCommandToCompileIt) {
  test::SimRig rig;
  BoardConfig config = rig.config;
  config.stages |= protocol::stage_bit(protocol::Stage::detect);
  config.detector.cascade = rig.dir.path() / "faces.xml";
  try {
    Firmware fw(rig.replaying(config));
    FAIL() << "the firmware reads compiled cascades only";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("epipole cascade-compile"), std::string::npos) << e.what();
  }
}

// A board naming a compiled cascade that was never made (a board fresh from its package, or
// board/sim before the host build has compiled OpenCV's face cascade) runs without detection,
// says so in every health message, and is told the one command that makes the cascade.
TEST(FrameLoop, RunsWithoutDetectionUntilTheCompiledCascadeIsMade) {
  test::SimRig rig;
  const test::TempDir data;
  std::filesystem::create_directories(data.path() / "cascades" / "haarcascades");
  const std::filesystem::path xml =
      data.path() / "cascades" / "haarcascades" / "haarcascade_frontalface_default.xml";
  std::ofstream(xml) << "<opencv_storage/>\n";
  ::setenv("EPIPOLE_DATA_DIR", data.path().c_str(), 1);
  BoardConfig config = rig.config;
  config.stages |= protocol::stage_bit(protocol::Stage::detect);
  config.detector.cascade = data.path() / "compiled" / "haarcascade_frontalface_default.bin";
  const std::string command = cascade_compile_command(config.detector.cascade);
  ::unsetenv("EPIPOLE_DATA_DIR");
  EXPECT_EQ(command,
            "epipole cascade-compile " + xml.string() + " " + config.detector.cascade.string());

  Firmware fw(rig.replaying(config));
  EXPECT_EQ(fw.pipeline().missing_cascade(), config.detector.cascade);
  EXPECT_EQ(fw.pipeline().available() & stage_bit(Stage::detect), 0u);
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  EXPECT_EQ(fw.run(40, stop).frames, 40u);
  for (const auto& f : recorder.frames) EXPECT_EQ(f.stages & stage_bit(Stage::detect), 0u);
  EXPECT_EQ(recorder.all<protocol::Detections>().size(), 0u);
  const auto health = recorder.all<protocol::Health>();
  ASSERT_GE(health.size(), 1u);
  for (const auto& h : health) EXPECT_EQ(h.flags, protocol::kHealthNoCascade);
}

// A trigger far faster than the host can process, the compute time charged to the virtual
// clock. At 320x240 a pair takes several of the 1 kHz trigger's periods (at 160x96 some runs
// took less than one): make `rig` that size.
BoardConfig outrun_by_the_trigger(const test::SimRig& rig) {
  BoardConfig config = rig.parse("");
  config.trigger.line.rate_hz = 1000;
  config.trigger.line.pulse_width = 100'000;
  config.pairing.trigger_period = 1'000'000;
  config.pairing.tolerance = 200'000;
  config.pairing.edge_tolerance = 200'000;
  test::sim(config).charge_compute = true;
  return config;
}

TEST(FrameLoop, ChargingComputeTimeSkipsStalePairs) {
  // The loop takes the freshest pair and counts the ones it skipped; latency stays bounded
  // instead of growing.
  test::SimRig rig(320, 240, 8, "");
  Firmware fw(rig.replaying(outrun_by_the_trigger(rig)));
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(40, stop);
  EXPECT_EQ(s.frames, 40u);
  // Skipped as stale, or (the slower the build, the likelier) overrun in the cameras' queues.
  const hal::TriggerAccount& t = s.faults.triggers;
  EXPECT_GT(t.stale + t.both_sides + t.one_side, 0u);
  EXPECT_EQ(t.published + t.dropped(), recorder.frames.back().frame + 1u);
  for (std::size_t i = 1; i < recorder.frames.size(); ++i) {
    EXPECT_GT(recorder.frames[i].frame, recorder.frames[i - 1].frame);
  }
}

// Pairs come faster than the loop follows (free-running cameras at 1000 fps: no trigger thread
// whose record the pairs wait for, the compute time charged to the virtual clock): the pair that
// came while one was processed is taken and rectified then, and every pair, rectified ahead or
// not, shows the rig's disparity.
TEST(FrameLoop, APairThatComesDuringTheOneBeforeIsRectifiedAhead) {
  test::SimRig rig(320, 240, 8, "");
  BoardConfig config = rig.parse_free_running("pairing: {tolerance_us: 400}\n");
  config.cameras.left.fps = config.cameras.right.fps = 1000;
  test::sim(config).charge_compute = true;
  Firmware fw(rig.replaying(config));
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(30, stop);
  ASSERT_EQ(s.frames, 30u);
  EXPECT_GT(s.rectified_ahead, 0u);
  EXPECT_LE(s.used_ahead, s.rectified_ahead);
  for (const auto& f : recorder.frames) {
    EXPECT_NEAR(f.centre_disparity, rig.disparity * 16, 8) << "frame " << f.frame;
    EXPECT_NEAR(f.nearest_mm, rig.depth() * 1000, 0.05 * rig.depth() * 1000) << f.frame;
  }
}

TEST(FrameLoop, HealthSaysHowBusyTheLoopIsAndHowLongPairsWaitedForIt) {
  // The trigger outruns the loop, the compute time charged to the virtual clock. The busy share
  // is the window's pairs times their mean total; a pair waits at least its readout. (How long
  // beyond that is the simulation's: its cameras catch up with a clock that jumped by a pair's
  // compute time only after the jump, so the loop sometimes takes a pair that is not the
  // freshest one a real camera would have by then.)
  // Three health windows, or 400 pairs: with the compute time charged, a slow build (the
  // sanitizers) gets its windows in fewer pairs.
  test::SimRig rig(320, 240, 8, "");
  Firmware fw(rig.replaying(outrun_by_the_trigger(rig)));
  Recorder recorder;
  recorder.health_to_stop = 3;
  fw.frame_loop().set_observer(&recorder);
  fw.run(400, recorder.stop);
  const auto health = recorder.all<protocol::Health>();
  ASSERT_GE(health.size(), 1u);
  for (const protocol::Health& h : health) {
    const double total_us = h.stage_us[static_cast<std::size_t>(Stage::total)];
    const double busy = h.fps_centi / 100.0 * total_us / 1000.0;
    EXPECT_GT(h.busy_permille, 0);
    EXPECT_NEAR(h.busy_permille, std::min(busy, 1000.0), 2.0) << h.fps_centi << " " << total_us;
    EXPECT_GE(h.wait_p50_us, 2000u) << "the simulated sensor's readout";
    EXPECT_GE(h.wait_p99_us, h.wait_p50_us);
  }
}

TEST(FrameLoop, DroppedFramesAreCountedAndNeverMispaired) {
  test::SimRig rig;
  BoardConfig config = rig.config;
  test::sim(config).drop_rate = 0.1;
  test::sim(config).seed = 5;
  Firmware fw(rig.replaying(config));
  Recorder recorder;
  // Both halves of every pair must come from one trigger: the right view is the left one
  // shifted, so a mispaired pair would not have the rig's disparity... and the sequences agree.
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(150, stop);
  EXPECT_EQ(s.frames, 150u);
  const hal::PairingCounters& p = s.pairing;
  EXPECT_GT(p.left().unpaired + p.right().unpaired, 5u) << "10 % of frames dropped on each side";
  EXPECT_GT(s.faults.triggers.dropped(), 5u);
  for (const auto& f : recorder.frames) {
    EXPECT_NEAR(f.centre_disparity, rig.disparity * 16, 8) << "frame " << f.frame;
  }
  const auto health = recorder.all<protocol::Health>();
  ASSERT_FALSE(health.empty());
  EXPECT_GT(health.back().unpaired_frames, 0);
  EXPECT_GT(health.back().dropped, 0u);
}

// Every trigger accounted for at each health message the loop sent.
int expect_every_trigger_accounted(const Recorder& recorder) {
  return test::expect_triggers_accounted(
      recorder.messages, [](const protocol::Message& m) -> const auto& { return m; });
}

TEST(FrameLoop, EachLostTriggerIsCountedOnceUnderItsCause) {
  test::SimRig rig;
  Firmware fw(rig.replaying(rig.config));
  const auto inject = [&](hal::Side side, hal::SimFaultKind kind, std::uint32_t sequence) {
    hal::SimFault f;
    f.kind = kind;
    f.sequence = sequence;
    test::sim_board(fw.board()).camera(side)->inject(f);
  };
  inject(hal::Side::left, hal::SimFaultKind::drop, 10);   // one side
  inject(hal::Side::right, hal::SimFaultKind::drop, 11);  // the other side, the next trigger
  inject(hal::Side::left, hal::SimFaultKind::drop, 20);   // both sides
  inject(hal::Side::right, hal::SimFaultKind::drop, 20);
  inject(hal::Side::left, hal::SimFaultKind::damaged, 30);  // the driver says damaged
  inject(hal::Side::right, hal::SimFaultKind::drop, 40);    // a damaged frame and a lost one
  inject(hal::Side::left, hal::SimFaultKind::damaged, 40);
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(60, stop);
  ASSERT_EQ(s.frames, 60u);
  const hal::TriggerAccount& t = s.faults.triggers;
  EXPECT_EQ(t.published, 60u);
  EXPECT_EQ(t.one_side, 2u) << "10 and 11: counted once each, whichever side lost them";
  EXPECT_EQ(t.both_sides, 1u) << "20";
  EXPECT_EQ(t.corrupt, 2u) << "30, and 40 (damaged on one side, lost on the other)";
  EXPECT_EQ(t.stale, 0u) << "the loop keeps up at the board's rate";
  EXPECT_EQ(t.published + t.dropped(), recorder.frames.back().frame + 1u);
  EXPECT_EQ(recorder.frames.back().frame, 64u);
  EXPECT_GT(expect_every_trigger_accounted(recorder), 0);
}

// Trigger glitches reach health (protocol version 5): a bounce 10 us after edge 20 is ignored
// and counted; edge 40, which the record missed, costs its own pair only, counted off trigger.
TEST(FrameLoop, HealthCountsTheTriggersGlitches) {
  test::SimRig rig;
  Firmware fw(rig.replaying(rig.config));
  hal::SimBoard& board = test::sim_board(fw.board());
  board.trigger.inject({hal::SimTriggerGlitchKind::extra_edge, 20, 10'000});
  board.trigger.inject({hal::SimTriggerGlitchKind::unrecorded, 40, 0});
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(100, stop);
  const auto health = recorder.all<protocol::Health>();
  ASSERT_GE(health.size(), 3u);
  EXPECT_EQ(health.back().trigger_bounces, 1u);
  EXPECT_EQ(health.back().pairs_off_trigger, 1u);
  EXPECT_EQ(s.faults.trigger_bounces, 1u);
  EXPECT_EQ(s.faults.pairs_off_trigger, 1u);
  // The firmware numbers the edges it sees: edge 41 of the schedule is its 40th.
  const auto at = [&](std::uint32_t edge) {
    return std::find_if(recorder.frames.begin(), recorder.frames.end(), [&](const auto& f) {
      return f.trigger_ns == board.trigger.edge_time(edge);
    });
  };
  EXPECT_EQ(at(40), recorder.frames.end()) << "the pair of the missed edge is not published";
  ASSERT_NE(at(39), recorder.frames.end());
  ASSERT_NE(at(41), recorder.frames.end()) << "the next carries its own edge";
  EXPECT_EQ(at(41)->frame, at(39)->frame + 1);
}

// The trigger stops for 10 s (an autopilot that disarmed) and comes back. The triggered cameras
// wait for it: no camera is reopened, health says it is waiting for the trigger (and nothing
// else changes), and every pair after it carries its own edge, its number following on.
TEST(FrameLoop, AStoppedTriggerIsWaitedForNotReopenedFor) {
  test::SimRig rig;
  Firmware fw(rig.replaying(rig.config));
  hal::SimBoard& board = test::sim_board(fw.board());
  const hal::Nanoseconds period = hal::period_of(30);
  board.trigger.inject({hal::SimTriggerGlitchKind::pause, 30, 300 * period});  // 10 s
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  ::testing::internal::CaptureStderr();
  const RunSummary s = fw.run(90, stop);
  const std::string journal = ::testing::internal::GetCapturedStderr();
  const auto lines = [&](const std::string& what) { return occurrences(journal, what); };
  EXPECT_EQ(lines("trigger sim: no edge for 100 ms, waiting for it"), 1u) << journal;
  EXPECT_EQ(lines("trigger sim: edges again"), 1u) << journal;
  EXPECT_EQ(lines("camera"), 0u) << journal;
  ASSERT_EQ(s.frames, 90u);
  EXPECT_EQ(s.faults.camera_reopens, 0u);
  EXPECT_GE(s.timeouts, 90u) << "10 s of 100 ms waits";
  EXPECT_EQ(fw.board().left_recovery().counters().losses, 0u);
  EXPECT_GE(fw.board().left_recovery().counters().trigger_waits, 90u);
  const auto health = recorder.all<protocol::Health>();
  std::size_t waiting = 0;
  for (const auto& h : health) {
    if ((h.flags & protocol::kHealthWaitingForTrigger) != 0) ++waiting;
    EXPECT_EQ(h.camera_reopens, 0);
  }
  EXPECT_GE(waiting, 8u) << "about one health a second of the 10 s";
  EXPECT_EQ(health.back().flags & protocol::kHealthWaitingForTrigger, 0) << "edges again";
  // The pairs: 30 before the pause, then the edges after it, numbered on without a gap.
  for (std::size_t i = 1; i < recorder.frames.size(); ++i) {
    const auto& f = recorder.frames[i];
    EXPECT_EQ(f.frame, recorder.frames[i - 1].frame + 1) << i;
    const hal::Nanoseconds step = f.trigger_ns - recorder.frames[i - 1].trigger_ns;
    EXPECT_EQ(step,
              i == 30 ? board.trigger.edge_time(30 + 300) - board.trigger.edge_time(29) : period)
        << i;
  }
  EXPECT_GT(expect_every_trigger_accounted(recorder), 0);
}

TEST(FrameLoop, EveryTriggerIsAccountedForWithRandomDropsOnBothSides) {
  test::SimRig rig;
  BoardConfig config = rig.config;
  test::sim(config).drop_rate = 0.1;  // on each side, independently
  test::sim(config).seed = 11;
  Firmware fw(rig.replaying(config));
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(400, stop);
  ASSERT_EQ(s.frames, 400u);
  EXPECT_GE(expect_every_trigger_accounted(recorder), 10);
  const hal::TriggerAccount& t = s.faults.triggers;
  EXPECT_EQ(t.published + t.dropped(), recorder.frames.back().frame + 1u);
  // About 18 % of the triggers lose one side and 1 % both: of some 490 triggers.
  EXPECT_GT(t.one_side, 50u);
  EXPECT_LT(t.one_side, 130u);
  EXPECT_GE(t.both_sides, 1u);
  EXPECT_EQ(t.corrupt, 0u);
  // One unpaired frame per one-sided loss.
  EXPECT_EQ(s.pairing.left().unpaired + s.pairing.right().unpaired, t.one_side);
}

TEST(FrameLoop, EveryTriggerIsAccountedForWhenTheTriggerOutrunsTheLoop) {
  // With drops: pairs go stale, the simulated cameras overrun (both sides lose the frame), and
  // one side drops at random.
  test::SimRig rig(320, 240, 8, "");
  BoardConfig config = outrun_by_the_trigger(rig);
  test::sim(config).drop_rate = 0.1;
  test::sim(config).seed = 4;
  Firmware fw(rig.replaying(config));
  Recorder recorder;
  recorder.health_to_stop = 3;  // as above: three windows, or 300 pairs
  fw.frame_loop().set_observer(&recorder);
  const RunSummary s = fw.run(300, recorder.stop);
  ASSERT_GE(s.frames, 1u);
  expect_every_trigger_accounted(recorder);
  const hal::TriggerAccount& t = s.faults.triggers;
  EXPECT_EQ(t.published + t.dropped(), recorder.frames.back().frame + 1u);
  EXPECT_GT(t.stale + t.both_sides, 0u) << "the loop could not follow 1 kHz";
  EXPECT_GT(t.one_side, 0u);
}

TEST(FrameLoop, RecoversFromALostCameraWithoutRestarting) {
  test::SimRig rig;
  Firmware fw(rig.replaying(rig.config));
  hal::SimFault gone;
  gone.kind = hal::SimFaultKind::disconnect;
  gone.sequence = 30;
  gone.value = 2;  // two reopen attempts fail before the camera is back
  test::sim_board(fw.board()).camera(hal::Side::left)->inject(gone);
  Recorder recorder;
  fw.frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = fw.run(120, stop);
  EXPECT_EQ(s.frames, 120u) << "the loop kept going";
  // Two attempts fail, the third brings it back: one reopen, and no other.
  const hal::RecoveryCounters& left = fw.board().left_recovery().counters();
  EXPECT_EQ(left.reopen_attempts, 3u);
  EXPECT_EQ(left.reopen_failures, 2u);
  EXPECT_EQ(s.faults.camera_reopens, 1u);
  EXPECT_GT(recorder.frames.back().frame, 30u);
  // There is a gap where the camera was gone, and frames after it.
  bool gap = false;
  for (std::size_t i = 1; i < recorder.frames.size(); ++i) {
    gap = gap || recorder.frames[i].frame > recorder.frames[i - 1].frame + 1;
  }
  EXPECT_TRUE(gap);
  const auto health = recorder.all<protocol::Health>();
  ASSERT_FALSE(health.empty());
  EXPECT_EQ(health.back().camera_reopens, 1u);
}

// A camera that comes and goes (a loose connector): each loss is counted in health, but the
// journal says one loss and its return in 10 s; the next loss said counts those left out.
TEST(FrameLoop, ACameraThatFlapsIsSaidOnceInTenSeconds) {
  test::SimRig rig;
  Firmware fw(rig.replaying(rig.config));
  for (const std::uint32_t at : {30u, 60u, 90u, 420u}) {  // 1, 2, 3 and 14 s
    hal::SimFault gone;
    gone.kind = hal::SimFaultKind::disconnect;
    gone.sequence = at;
    gone.count = 1;
    test::sim_board(fw.board()).camera(hal::Side::left)->inject(gone);
  }
  const std::atomic<bool> stop{false};
  ::testing::internal::CaptureStderr();
  const RunSummary s = fw.run(440, stop);
  const std::string journal = ::testing::internal::GetCapturedStderr();
  const auto lines = [&](const std::string& what) { return occurrences(journal, what); };
  EXPECT_EQ(s.faults.camera_reopens, 4u) << "every loss is counted";
  EXPECT_EQ(lines("lost, reopening"), 2u) << journal;
  EXPECT_EQ(lines("recovered"), 2u) << journal;
  EXPECT_EQ(lines("(2 losses not said since the last)"), 1u) << journal;
}

// A board with a link on a pseudo-terminal, and the robot at its other end.
struct LinkedRig {
  using Make = std::function<BoardConfig(const test::SimRig&)>;
  test::SimRig rig;
  BoardConfig config;
  std::unique_ptr<Firmware> fw;
  std::unique_ptr<hal::TermiosSerialPort> robot;
  protocol::FrameDecoder decoder;
  explicit LinkedRig(const std::string& extra = "",
                     BoardConfig::LinkProtocol protocol = BoardConfig::LinkProtocol::epipole)
      : LinkedRig([&](const test::SimRig& r) {
          BoardConfig c = r.parse(extra);
          c.serial.protocol = protocol;
          return c;
        }) {}
  // The board `make` makes of the rig; the cameras replay `images` pairs (0: the board's own
  // scene, as `make` chose it).
  explicit LinkedRig(const Make& make, int images = 2) {
    config = make(rig);
    config.serial.backend = "pty";
    fw = std::make_unique<Firmware>(images > 0 ? rig.replaying(config, images) : config);
    robot = std::make_unique<hal::TermiosSerialPort>(
        hal::SerialConfig{fw->board().serial_peer(), 115200});
  }
  // The acknowledgements the robot received, in command order (or as they came).
  std::vector<protocol::CommandAck> acks(bool sorted = true) {
    std::vector<protocol::CommandAck> out;
    for (const auto& m : receive()) {
      if (const auto* a = std::get_if<protocol::CommandAck>(&m.message)) out.push_back(*a);
    }
    if (!sorted) return out;
    std::sort(out.begin(), out.end(),
              [](const auto& a, const auto& b) { return a.command_sequence < b.command_sequence; });
    return out;
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
  const std::vector<protocol::CommandAck> acks = linked.acks();
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
  ASSERT_EQ(acks.size(), 3u);
  EXPECT_EQ(acks[0].status, protocol::AckStatus::ok);
  EXPECT_EQ(acks[1].status, protocol::AckStatus::ok) << "the snapshot was written";
  EXPECT_EQ(acks[2].status, protocol::AckStatus::rejected);
  EXPECT_EQ(acks[2].reason, protocol::AckReason::out_of_range);
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

// Sends `commands` (sequence numbers from `first`) once, when the loop is at frame `at`, and
// slows the loop a little so that the link thread reads them during the run.
void send_at(Recorder& recorder, LinkedRig& linked, std::uint32_t at,
             std::vector<protocol::Message> commands, std::uint16_t first) {
  auto before = std::move(recorder.also);
  recorder.also = [&linked, at, first, commands = std::move(commands), before,
                   sent = false](const FrameResult& r) mutable {
    if (before) before(r);
    if (r.frame < at || sent) return;
    sent = true;
    const std::uint64_t received = linked.fw->link().counters().commands;
    for (std::size_t i = 0; i < commands.size(); ++i) {
      linked.send(commands[i], static_cast<std::uint16_t>(first + i));
    }
    // The link's thread has them before the loop goes on (a loaded machine can hold that thread
    // back for longer than the loop takes for the pairs left).
    for (int i = 0; i < 2500 && linked.fw->link().counters().commands < received + commands.size();
         ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  };
}

std::vector<protocol::AckStatus> statuses(const std::vector<protocol::CommandAck>& acks) {
  std::vector<protocol::AckStatus> out;
  for (const auto& a : acks) out.push_back(a.status);
  return out;
}

std::vector<protocol::AckReason> reasons(const std::vector<protocol::CommandAck>& acks) {
  std::vector<protocol::AckReason> out;
  for (const auto& a : acks) out.push_back(a.reason);
  return out;
}

TEST(FrameLoop, SetTriggerRateChangesThePeriodOfTheTriggers) {
  using protocol::AckStatus;
  LinkedRig linked;
  Recorder recorder;
  recorder.also = [](const FrameResult&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  };
  send_at(recorder, linked, 40,
          {protocol::SetTriggerRate{15'000},     // 15 Hz
           protocol::SetTriggerRate{0},          // impossible
           protocol::SetTriggerRate{2'000'000},  // 2 kHz: impossible
           protocol::SetTriggerRate{400'000},    // 400 Hz: 2.5 ms < twice the 2 ms tolerance
           protocol::SetTriggerRate{4'000}},     // 4 Hz: a frame every 250 ms, timeout 100 ms
          200);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(150, stop);
  using protocol::AckReason;
  const std::vector<protocol::CommandAck> acks = linked.acks();
  EXPECT_EQ(statuses(acks),
            (std::vector<AckStatus>{AckStatus::ok, AckStatus::rejected, AckStatus::rejected,
                                    AckStatus::rejected, AckStatus::rejected}));
  EXPECT_EQ(reasons(acks), (std::vector<AckReason>{AckReason::none, AckReason::out_of_range,
                                                   AckReason::out_of_range, AckReason::timing,
                                                   AckReason::timing}));
  EXPECT_EQ(s.faults.bad_commands, 4u);
  EXPECT_EQ(linked.fw->board().trigger()->config().rate_hz, 15.0);
  EXPECT_NO_THROW(hal::with_rate(linked.fw->board().trigger()->config(), 400.0))
      << "the line could run at 400 Hz: the pairing tolerance is what refused it";
  // Every trigger, in order; the edges step at 30 Hz, then, from the last edge the cameras had
  // been told of when the command came, at 15 Hz.
  ASSERT_EQ(recorder.frames.size(), 150u);
  std::size_t switched = 0;
  for (std::size_t i = 1; i < recorder.frames.size(); ++i) {
    EXPECT_EQ(recorder.frames[i].frame, recorder.frames[i - 1].frame + 1);
    const hal::Nanoseconds step = recorder.frames[i].trigger_ns - recorder.frames[i - 1].trigger_ns;
    if (switched == 0 && step != hal::period_of(30)) switched = i;
    EXPECT_EQ(step, switched == 0 ? hal::period_of(30) : hal::period_of(15)) << "frame " << i;
  }
  EXPECT_GT(switched, 40u);
  EXPECT_LT(switched, 50u);
  const auto summaries = recorder.all<protocol::FrameSummary>();
  ASSERT_EQ(summaries.size(), 150u);
  EXPECT_EQ(summaries.back().trigger_ns - summaries[summaries.size() - 2].trigger_ns,
            static_cast<std::uint64_t>(hal::period_of(15)))
      << "the robot sees the new period";
  const auto health = recorder.all<protocol::Health>();
  ASSERT_GE(health.size(), 5u);
  EXPECT_EQ(health[0].fps_centi, 3000);
  EXPECT_NEAR(health.back().fps_centi, 1500, 100) << "health follows the new rate";
  EXPECT_EQ(health.back().latency_p50_us, 7000u) << "the cameras' own delay, as before";
}

// A resend (same number, same content, its ack lost) is answered with the first result and not
// applied again; a robot that rebooted starts again at 0 and is answered; one whose first frame
// after the reboot was lost reuses a number with other content: applied.
// A rate the sensors cannot follow is refused before anything changes: the simulated sensor
// reads a frame out in 2 ms, so 500 Hz at most.
TEST(FrameLoop, ATriggerRateTheSensorsCannotFollowIsRefused) {
  using protocol::AckStatus;
  LinkedRig linked;
  Recorder recorder;
  send_at(recorder, linked, 5, {protocol::SetTriggerRate{600'000}}, 40);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  ::testing::internal::CaptureStderr();
  linked.fw->run(20, stop);
  const std::string journal = ::testing::internal::GetCapturedStderr();
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].status, AckStatus::rejected);
  EXPECT_EQ(acks[0].reason, protocol::AckReason::out_of_range);
  EXPECT_NE(journal.find("can follow at most 500 Hz"), std::string::npos) << journal;
  EXPECT_EQ(linked.fw->board().trigger()->config().rate_hz, 30.0);
}

// A baud rate that carries the summaries (the board file's check) but not every point and depth
// grid: every pair's summary and each health arrive, the rest is dropped, counted and said once;
// once the robot turns those stages off and nothing was dropped for 10 s, that is said once too.
TEST(FrameLoop, ALinkTooSlowForEveryMessageKeepsTheSummariesAndSaysSoOnce) {
  LinkedRig linked([](const test::SimRig& r) {
    BoardConfig c = r.parse("");
    c.stages |= protocol::stage_bit(protocol::Stage::sparse);
    c.sparse.max_points = protocol::kMaxPoints;  // some 800 bytes a pair
    c.serial.port.baud = 57600;                  // 192 bytes a pair at 30 pairs a second
    return c;
  });
  Recorder recorder;
  send_at(recorder, linked, 60, {protocol::SetStages{stage_bit(Stage::rectify)}}, 1);
  linked.fw->frame_loop().set_observer(&recorder);
  // The robot reads as the firmware sends (the simulated board runs faster than the clock the
  // budget counts on: nothing may wait in the pseudo-terminal).
  std::atomic<bool> done{false};
  std::vector<protocol::DecodedMessage> received;
  std::thread robot([&] {
    while (!done) {
      const std::vector<protocol::DecodedMessage> got = linked.receive();
      received.insert(received.end(), got.begin(), got.end());
    }
  });
  const std::atomic<bool> stop{false};
  ::testing::internal::CaptureStderr();
  const RunSummary s = linked.fw->run(420, stop);  // 14 s at 30 pairs a second
  const std::string journal = ::testing::internal::GetCapturedStderr();
  done = true;
  robot.join();
  std::size_t summaries = 0, health = 0, points = 0, acks = 0;
  for (const protocol::DecodedMessage& m : received) {
    summaries += std::holds_alternative<protocol::FrameSummary>(m.message) ? 1 : 0;
    health += std::holds_alternative<protocol::Health>(m.message) ? 1 : 0;
    points += std::holds_alternative<protocol::Points>(m.message) ? 1 : 0;
    acks += std::holds_alternative<protocol::CommandAck>(m.message) ? 1 : 0;
  }
  EXPECT_EQ(summaries, s.frames) << "every pair's summary";
  EXPECT_EQ(health, s.health_messages);
  EXPECT_EQ(acks, 1u);
  EXPECT_GT(points, 0u);
  EXPECT_LT(points, 60u) << "the points of the first 60 pairs do not all fit";
  EXPECT_GT(s.link.over_budget, 0u);
  EXPECT_EQ(s.link.messages_dropped, s.link.over_budget);
  const auto lines = [&](const std::string& what) { return occurrences(journal, what); };
  EXPECT_EQ(lines("serial link: 57600 baud cannot carry every message at 30.0 pairs/s"), 1u)
      << journal;
  EXPECT_EQ(lines("serial link: every message fits again"), 1u) << journal;
}

// A rate whose summaries the link's baud rate cannot carry is refused, and nothing changes.
TEST(FrameLoop, ATriggerRateTheLinkCannotCarryIsRefused) {
  using protocol::AckStatus;
  LinkedRig linked([](const test::SimRig& r) {
    BoardConfig c = r.parse("");
    c.serial.port.baud = 19200;  // the summaries of some 45 pairs a second
    c.stages &= static_cast<StageMask>(~protocol::stage_bit(protocol::Stage::odometry));
    return c;
  });
  Recorder recorder;
  send_at(recorder, linked, 5, {protocol::SetTriggerRate{60'000}, protocol::SetTriggerRate{40'000}},
          7);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  ::testing::internal::CaptureStderr();
  linked.fw->run(40, stop);
  const std::string journal = ::testing::internal::GetCapturedStderr();
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 2u);
  EXPECT_EQ(acks[0].status, AckStatus::rejected);
  EXPECT_EQ(acks[0].reason, protocol::AckReason::out_of_range);
  EXPECT_NE(journal.find("19200 baud carries 1920 bytes/s"), std::string::npos) << journal;
  EXPECT_EQ(acks[1].status, AckStatus::ok) << "40 pairs a second fit";
  EXPECT_EQ(linked.fw->board().trigger()->config().rate_hz, 40.0);
}

TEST(FrameLoop, ARobotThatRestartsItsSequenceIsAnsweredAndAResendIsNotAppliedTwice) {
  using protocol::AckStatus;
  LinkedRig linked;
  Recorder recorder;
  const auto stages = [](StageMask mask) { return protocol::SetStages{mask}; };
  const StageMask some = stage_bit(Stage::rectify) | stage_bit(Stage::corners);
  const StageMask other = stage_bit(Stage::rectify);
  send_at(recorder, linked, 5, {stages(some), stages(some)}, 300);
  send_at(recorder, linked, 15, {stages(some)}, 301);  // 301 again: its ack was lost, say
  // The robot rebooted: its numbers start again at 0 (before, 0..299 were taken for replays).
  send_at(recorder, linked, 25, {stages(some), stages(0x8000)}, 0);
  // It rebooted again, and its frame 0 was lost: 1 comes with other content than the 1 before.
  send_at(recorder, linked, 35, {stages(other)}, 1);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(50, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks(false);
  std::vector<std::uint16_t> sequences;
  for (const auto& a : acks) sequences.push_back(a.command_sequence);
  EXPECT_EQ(sequences, (std::vector<std::uint16_t>{300, 301, 301, 0, 1, 1}));
  EXPECT_EQ(statuses(acks),
            (std::vector<AckStatus>{AckStatus::ok, AckStatus::ok, AckStatus::ok, AckStatus::ok,
                                    AckStatus::rejected, AckStatus::ok}));
  EXPECT_EQ(s.commands, 6u);
  EXPECT_EQ(s.resent_commands, 1u);
  EXPECT_EQ(s.faults.bad_commands, 1u) << "the unknown stage";
  EXPECT_EQ(s.stages, other | protocol::kAlwaysOnStages) << "the last 1 was applied";
}

// Snapshots: a resend is never a second snapshot; one answered busy and sent again is taken.
TEST(FrameLoop, AResentSnapshotIsTakenOnceAndOneAnsweredBusyIsTakenWhenSentAgain) {
  using protocol::AckStatus;
  LinkedRig linked("snapshot_directory: snapshots\n");
  Recorder recorder;
  recorder.also = [](const FrameResult&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  // 20 is taken; 21, with it, finds 20 pending: busy.
  send_at(recorder, linked, 5, {protocol::Snapshot{}, protocol::Snapshot{}}, 20);
  send_at(recorder, linked, 30, {protocol::Snapshot{}}, 20);  // a resend: not a second snapshot
  send_at(recorder, linked, 40, {protocol::Snapshot{}}, 21);  // sent again after busy: taken
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(80, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  std::vector<std::uint16_t> ok;
  for (const auto& a : acks) {
    if (a.status == AckStatus::ok) ok.push_back(a.command_sequence);
    if (a.status != AckStatus::ok) {
      EXPECT_EQ(a.command_sequence, 21);
      EXPECT_EQ(a.reason, protocol::AckReason::busy);
    }
  }
  // 20's resend is answered again (or, still being written, once with the first).
  EXPECT_TRUE(ok == (std::vector<std::uint16_t>{20, 20, 21}) ||
              ok == (std::vector<std::uint16_t>{20, 21}))
      << ::testing::PrintToString(ok);
  EXPECT_EQ(s.resent_commands, 1u);
  std::set<std::string> snapshots;  // snapshot-FRAME-what.pgm: one FRAME a snapshot
  for (const auto& entry :
       std::filesystem::directory_iterator(linked.rig.dir.path() / "snapshots")) {
    snapshots.insert(entry.path().filename().string().substr(0, 15));
  }
  EXPECT_EQ(snapshots.size(), 2u) << "20 once, and 21";
}

TEST(FrameLoop, SnapshotsAreAnsweredOnceWrittenAndStopAtTheirLimit) {
  using protocol::AckStatus;
  LinkedRig linked("snapshot_directory: snapshots\nsnapshot_limit: 1\n");
  Recorder recorder;
  recorder.also = [](const FrameResult&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  send_at(recorder, linked, 5, {protocol::Snapshot{}, protocol::Snapshot{}}, 10);
  send_at(recorder, linked, 40, {protocol::Snapshot{}}, 12);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  linked.fw->run(60, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 3u);
  EXPECT_EQ(acks[0].status, AckStatus::ok);
  // The second came with the first: it is refused as busy (the first is still pending), or, if
  // the link thread read it only once the first was on disk, for the limit.
  EXPECT_EQ(acks[1].status, AckStatus::rejected);
  EXPECT_TRUE(acks[1].reason == protocol::AckReason::busy ||
              acks[1].reason == protocol::AckReason::storage)
      << static_cast<int>(acks[1].reason);
  EXPECT_EQ(acks[2].status, AckStatus::rejected);
  EXPECT_EQ(acks[2].reason, protocol::AckReason::storage) << "snapshot_limit: 1";
}

// Files may grow to `bytes` while it lives (a full card, as root too); EFBIG, not SIGXFSZ.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &before_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = before_;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &before_);
    std::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit before_{};
  void (*old_handler_)(int) = SIG_DFL;
};

TEST(FrameLoop, ASnapshotThatCannotBeWrittenIsRejectedAndCountedInHealth) {
  using protocol::AckStatus;
  LinkedRig linked("snapshot_directory: snapshots\n");
  // Every file stops growing after its header: the writes fail once the snapshot was accepted.
  const FileSizeLimit full(64);
  Recorder recorder;
  recorder.also = [](const FrameResult&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  send_at(recorder, linked, 5, {protocol::Snapshot{}}, 7);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(150, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].status, AckStatus::rejected);
  EXPECT_EQ(acks[0].reason, protocol::AckReason::failed);
  EXPECT_EQ(s.faults.snapshot_failures, 1u);
  const auto health = recorder.all<protocol::Health>();
  ASSERT_FALSE(health.empty());
  EXPECT_EQ(health.back().snapshot_failures, 1u);
}

// A folder that cannot be listed (here a file took its place) is refused at once, for storage:
// neither counted as empty nor numbered from 0.
TEST(FrameLoop, ASnapshotFolderThatCannotBeListedIsRefusedForStorage) {
  using protocol::AckStatus;
  LinkedRig linked("snapshot_directory: snapshots\n");
  const std::filesystem::path folder = linked.rig.dir.path() / "snapshots";
  std::filesystem::remove_all(folder);
  std::FILE* file = std::fopen(folder.c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fclose(file);
  Recorder recorder;
  send_at(recorder, linked, 5, {protocol::Snapshot{}}, 7);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(30, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].status, AckStatus::rejected);
  EXPECT_EQ(acks[0].reason, protocol::AckReason::storage);
  EXPECT_EQ(s.faults.snapshot_failures, 0u) << "nothing was tried";
}

// A snapshot asked for just before a camera goes for good gets its answer all the same: refused
// (no_pairs) once no pair came for 2 s, never left unanswered until the camera returns.
TEST(FrameLoop, ASnapshotNoPairCameForIsAnsweredWithinABound) {
  using protocol::AckStatus;
  LinkedRig linked("snapshot_directory: snapshots\n");
  hal::SimFault gone;
  gone.kind = hal::SimFaultKind::disconnect;
  gone.sequence = 11;
  gone.value = 1'000'000;  // every reopen fails
  test::sim_board(linked.fw->board()).camera(hal::Side::right)->inject(gone);
  Recorder recorder;
  recorder.also = [](const FrameResult&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  send_at(recorder, linked, 10, {protocol::Snapshot{}}, 5);
  linked.fw->frame_loop().set_observer(&recorder);
  std::atomic<bool> stop{false};
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    stop = true;
  });
  const RunSummary s = linked.fw->run(0, stop);
  stopper.join();
  EXPECT_EQ(s.frames, 11u) << "pairs 0..10, then the right camera is gone";
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].command_sequence, 5);
  EXPECT_EQ(acks[0].status, AckStatus::rejected);
  EXPECT_EQ(acks[0].reason, protocol::AckReason::no_pairs);
  EXPECT_TRUE(std::filesystem::is_empty(linked.rig.dir.path() / "snapshots"));
}

TEST(FrameLoop, ASnapshotThatWouldLeaveTooLittleFreeSpaceIsRefused) {
  using protocol::AckStatus;
  // 10 TB to be kept free: no disk here has that, so the reserve refuses every snapshot.
  LinkedRig linked("snapshot_directory: snapshots\nsnapshot_min_free_mb: 10000000\n");
  Recorder recorder;
  send_at(recorder, linked, 5, {protocol::Snapshot{}}, 9);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(30, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].command_sequence, 9);
  EXPECT_EQ(acks[0].status, AckStatus::rejected);
  EXPECT_EQ(acks[0].reason, protocol::AckReason::storage);
  EXPECT_EQ(s.faults.bad_commands, 1u);
  EXPECT_EQ(s.faults.snapshot_failures, 0u) << "refused before anything was written";
  const std::filesystem::path folder = linked.rig.dir.path() / "snapshots";
  ASSERT_TRUE(std::filesystem::is_directory(folder));
  EXPECT_TRUE(std::filesystem::is_empty(folder));
}

// Whether an MCAP file was closed whole: it ends with the format's magic (after its footer).
bool ends_whole(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(-8, std::ios::end);
  char magic[8] = {};
  in.read(magic, 8);
  return in && std::string(magic, 8) == std::string("\x89MCAP0\r\n", 8);
}

TEST(FrameLoop, TheRobotStartsAndStopsTheRecording) {
  LinkedRig linked("outputs: {mcap: {directory: recordings, every: 1}}\n");
  Recorder recorder;
  send_at(recorder, linked, 10, {protocol::Record{protocol::RecordAction::start, 0}}, 300);
  send_at(recorder, linked, 30, {protocol::Record{protocol::RecordAction::stop, 0}}, 301);
  // One second of the board's clock: 30 pairs at its 30 Hz trigger.
  send_at(recorder, linked, 60, {protocol::Record{protocol::RecordAction::start, 1}}, 302);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(150, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  EXPECT_EQ(statuses(acks), (std::vector<protocol::AckStatus>(3, protocol::AckStatus::ok)));
  ASSERT_EQ(s.outputs.size(), 1u);
  const OutputReport& mcap = s.outputs[0];
  // Recorded: from about pair 10 to 30 and 60 to 90 (a command is applied once the link's
  // thread has read it: a few pairs later).
  EXPECT_GE(mcap.delivered + mcap.dropped, 40u);
  EXPECT_LE(mcap.delivered + mcap.dropped, 60u) << "nothing before the start, after the stops";
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(linked.rig.dir.path() / "recordings")) {
    files.push_back(e.path());
  }
  EXPECT_EQ(files.size(), 2u) << "a file a start";
  for (const auto& file : files) EXPECT_TRUE(ends_whole(file)) << file << " closed whole";
}

// recalibrate and save_calibration, on the rig's ideal calibration: before any window there is
// no estimate; then nothing to correct (ok); the calibration in use written beside the board's,
// which is kept.
TEST(FrameLoop, RecalibrateAndSaveCalibrationAreAnsweredWithTheirResult) {
  using protocol::AckReason;
  using protocol::AckStatus;
  LinkedRig linked([](const test::SimRig& r) {
    BoardConfig c = r.parse();
    c.stages |= protocol::stage_bit(protocol::Stage::sparse);
    return c;
  });
  Recorder recorder;
  recorder.also = [&](const FrameResult&) {  // the file written (threads.maps: idle here)
    EXPECT_TRUE(test::wait_for_maps_thread(*linked.fw->pipeline().rig_correction()));
  };
  send_at(recorder, linked, 0, {protocol::Recalibrate{}}, 1);
  send_at(recorder, linked, 20, {protocol::Recalibrate{}, protocol::SaveCalibration{}}, 2);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  linked.fw->run(50, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  ASSERT_EQ(acks.size(), 3u);
  EXPECT_EQ(acks[0].status, AckStatus::rejected);
  EXPECT_EQ(acks[0].reason, AckReason::no_pairs) << "no window yet";
  EXPECT_EQ(acks[1].status, AckStatus::ok) << "an ideal rig: nothing to correct";
  EXPECT_EQ(acks[2].status, AckStatus::ok);
  const std::filesystem::path original = linked.config.calibration;
  const std::filesystem::path corrected =
      original.parent_path() / (original.stem().string() + "-corrected.yaml");
  ASSERT_TRUE(std::filesystem::exists(corrected));
  EXPECT_TRUE(std::filesystem::exists(original)) << "kept";
  const calib::StereoCalibration was = calib::load_calibration(original);
  const calib::StereoCalibration is = calib::load_calibration(corrected);
  EXPECT_EQ(is.R, was.R) << "nothing was corrected";
  EXPECT_EQ(is.right.rectification, was.right.rectification);
  EXPECT_NE(is.source.find("corrected while running"), std::string::npos) << is.source;
}

// The faces scene of board/sim, its right camera turned 0.3 degrees of pitch and 0.2 of roll,
// online correction off, a window of 10 pairs.
BoardConfig drifted_faces(const test::SimRig&) {
  return test::board_scene("faces",
                           {"sim.scenes.faces.drift={pitch_deg: 0.3, roll_deg: 0.2}",
                            "calibration_health.window_pairs=10", "stages.detect=false"},
                           false)
      .config;
}

// The acknowledgements the loop sent, in command order (as the loop sent them: this scene's
// messages fill a pseudo-terminal nobody reads during the run).
std::vector<protocol::CommandAck> sent_acks(const Recorder& recorder) {
  std::vector<protocol::CommandAck> acks = recorder.all<protocol::CommandAck>();
  std::sort(acks.begin(), acks.end(),
            [](const auto& a, const auto& b) { return a.command_sequence < b.command_sequence; });
  return acks;
}

// recalibrate on a drifted rig: answered ok once the corrected map is in place, and the
// calibration messages after it say so, their rows straight again; one sent again while the
// first is pending is busy.
TEST(FrameLoop, RecalibrateCorrectsADriftedRigAndIsAnsweredOnceInPlace) {
  using protocol::AckReason;
  using protocol::AckStatus;
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: 640x480 pairs take long under qemu";
  LinkedRig linked(drifted_faces, 0);
  Recorder recorder;
  recorder.also = [&](const FrameResult&) {
    EXPECT_TRUE(test::wait_for_maps_thread(*linked.fw->pipeline().rig_correction()));
  };
  // After the first health message (15 pairs a second).
  send_at(recorder, linked, 20, {protocol::Recalibrate{}, protocol::Recalibrate{}}, 1);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  linked.fw->run(60, stop);
  const std::vector<protocol::CommandAck> acks = sent_acks(recorder);
  ASSERT_EQ(acks.size(), 2u);
  EXPECT_EQ(acks[0].status, AckStatus::ok) << "answered once in place";
  EXPECT_EQ(acks[1].status, AckStatus::rejected);
  EXPECT_EQ(acks[1].reason, AckReason::busy) << "the first is being done";
  const auto health = recorder.all<protocol::CalibrationHealth>();
  ASSERT_GE(health.size(), 3u);
  EXPECT_EQ(health.front().corrections, 0);
  EXPECT_GE(health.front().median_offset_centipx, 100) << "the drift, the right way";
  const protocol::CalibrationHealth& last = health.back();
  EXPECT_EQ(last.corrections, 1);
  EXPECT_NEAR(last.corrected_pitch_mdeg, 300, 20);
  EXPECT_NEAR(last.corrected_roll_mdeg, 200, 20);
  EXPECT_LT(std::abs(last.median_offset_centipx), 10);
  const auto healths = recorder.all<protocol::Health>();
  ASSERT_FALSE(healths.empty());
  EXPECT_NE(healths.back().flags & protocol::kHealthRigCorrected, 0);
}

// A recalibrate still pending when the firmware stops is answered all the same: once, ok when
// the map made it in place before the stop, else failed.
TEST(FrameLoop, ARecalibratePendingAtTheStopIsAnsweredOnce) {
  using protocol::AckReason;
  using protocol::AckStatus;
  if (EPIPOLE_UNDER_QEMU) GTEST_SKIP() << "left to the host: 640x480 pairs take long under qemu";
  LinkedRig linked(drifted_faces, 0);
  Recorder recorder;
  send_at(recorder, linked, 14, {protocol::Recalibrate{}}, 1);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  linked.fw->run(16, stop);
  const std::vector<protocol::CommandAck> acks = sent_acks(recorder);
  ASSERT_EQ(acks.size(), 1u);
  const bool in_place = acks[0].status == AckStatus::ok;
  const bool failed = acks[0].status == AckStatus::rejected && acks[0].reason == AckReason::failed;
  EXPECT_TRUE(in_place || failed) << static_cast<int>(acks[0].status) << " "
                                  << static_cast<int>(acks[0].reason);
}

TEST(FrameLoop, RecordIsUnsupportedWithoutARecording) {
  LinkedRig linked;
  Recorder recorder;
  send_at(recorder, linked, 5, {protocol::Record{protocol::RecordAction::start, 0}}, 400);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  linked.fw->run(30, stop);
  EXPECT_EQ(statuses(linked.acks()),
            (std::vector<protocol::AckStatus>{protocol::AckStatus::unsupported}));
}

TEST(FrameLoop, SetExposureReachesBothCameras) {
  using protocol::AckStatus;
  // The cameras start at 2 ms and unity gain; the simulated ones scale what they replay by the
  // exposure and gain relative to that.
  LinkedRig linked(
      [](const test::SimRig& r) {
        BoardConfig c = r.parse();
        for (hal::CameraConfig* camera : {&c.cameras.left, &c.cameras.right}) {
          camera->exposure = 2'000'000;
          camera->gain = 1.0;
        }
        return c;
      },
      1);
  Recorder recorder;
  std::vector<std::pair<int, int>> pixels;  // a dark pixel of each raw image, frame by frame
  std::pair<int, int> lp{-1, -1}, rp{-1, -1};
  recorder.also = [&](const FrameResult& r) {
    const auto dark = [](GrayView v) {
      for (int y = 0; y < v.height(); ++y) {
        for (int x = 0; x < v.width(); ++x) {
          if (v(x, y) >= 10 && v(x, y) <= 40) return std::pair{x, y};
        }
      }
      return std::pair{-1, -1};
    };
    if (lp.first < 0) lp = dark(r.left_raw);
    if (rp.first < 0) rp = dark(r.right_raw);
    if (lp.first >= 0 && rp.first >= 0) {
      pixels.emplace_back(r.left_raw(lp.first, lp.second), r.right_raw(rp.first, rp.second));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  };
  send_at(recorder, linked, 5, {protocol::SetExposure{4000, 0}}, 300);  // twice the light
  send_at(recorder, linked, 40,
          {protocol::SetExposure{6000, 602},      // 3 x the exposure, 6.02 dB: 6 x the light
           protocol::SetExposure{20'000'000, 0},  // 20 s: impossible
           protocol::SetExposure{1000, 6100}},    // 61 dB: 1122 x, beyond the gain's 1000
          301);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  linked.fw->run(80, stop);
  const std::vector<protocol::CommandAck> acks = linked.acks();
  EXPECT_EQ(statuses(acks), (std::vector<AckStatus>{AckStatus::ok, AckStatus::ok,
                                                    AckStatus::rejected, AckStatus::rejected}));
  ASSERT_EQ(acks.size(), 4u);
  EXPECT_EQ(acks[2].reason, protocol::AckReason::timing)
      << "20 s does not fit in the trigger's period";
  EXPECT_EQ(acks[3].reason, protocol::AckReason::out_of_range);
  for (const hal::Side side : {hal::Side::left, hal::Side::right}) {
    const hal::CameraConfig& c = test::sim_board(linked.fw->board()).camera(side)->config();
    EXPECT_EQ(c.exposure, 6'000'000);
    EXPECT_NEAR(c.gain, 2.0, 0.001) << "6.02 dB";
  }
  // Each camera's pixel: v, then 2 v, then 6 v, never going back.
  ASSERT_EQ(pixels.size(), 80u) << "a pixel of 10..40 in both images";
  const auto [l0, r0] = pixels.front();
  int stage = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const int scale[3] = {1, 2, 6};
    while (stage < 2 && pixels[i].first == l0 * scale[stage + 1]) ++stage;
    EXPECT_EQ(pixels[i].first, l0 * scale[stage]) << "frame " << i;
    EXPECT_EQ(pixels[i].second, r0 * scale[stage]) << "frame " << i << ": both cameras alike";
  }
  EXPECT_EQ(stage, 2);
}

TEST(FrameLoop, FreeRunningCamerasWithoutATriggerPairByTime) {
  using protocol::AckStatus;
  // Two free-running cameras (trigger.backend none, as on the usb-stereo board), the right one's
  // clock 1 % fast, 5 % of the frames dropped on each side: their frame counters drift apart,
  // and their exposures drift through every phase, so pairing by sequence would stop within
  // seconds. One image: a pair of any two frames shows the rig's disparity.
  LinkedRig linked(
      [](const test::SimRig& r) {
        BoardConfig c = r.parse_free_running("pairing: {tolerance_us: 15000}\n");
        c.cameras.right.fps = 30.3;
        test::sim(c).drop_rate = 0.05;
        test::sim(c).seed = 3;
        return c;
      },
      1);
  EXPECT_EQ(linked.fw->board().trigger(), nullptr);
  Recorder recorder;
  send_at(recorder, linked, 5, {protocol::SetTriggerRate{15'000}, protocol::SetExposure{3000, 0}},
          400);
  linked.fw->frame_loop().set_observer(&recorder);
  const std::atomic<bool> stop{false};
  const RunSummary s = linked.fw->run(240, stop);
  EXPECT_EQ(statuses(linked.acks()),
            (std::vector<AckStatus>{AckStatus::unsupported, AckStatus::ok}))
      << "no trigger line to set; the cameras' exposure still is";
  EXPECT_EQ(s.faults.bad_commands, 1u) << "the unsupported command is counted";
  ASSERT_EQ(s.frames, 240u);
  std::uint32_t longest_gap = 0;
  for (std::size_t i = 0; i < recorder.frames.size(); ++i) {
    const auto& f = recorder.frames[i];
    // The pair's number and time are the left frame's: frame n at n periods + 5 ms exposure.
    EXPECT_EQ(f.trigger_ns,
              static_cast<hal::Nanoseconds>(f.frame) * hal::period_of(30) + 5'000'000);
    EXPECT_NEAR(f.centre_disparity, linked.rig.disparity * 16, 8) << "frame " << f.frame;
    if (i > 0) {
      EXPECT_GT(f.frame, recorder.frames[i - 1].frame);
      longest_gap = std::max(longest_gap, f.frame - recorder.frames[i - 1].frame);
    }
  }
  // ... and the frame messages say so.
  const auto summaries = recorder.all<protocol::FrameSummary>();
  ASSERT_FALSE(summaries.empty());
  for (const auto& m : summaries) EXPECT_EQ(m.flags, protocol::kFrameTriggerFromCapture);
  // Pairs keep coming: no frame is within 15 ms while the phase crosses the 3.3 ms band in the
  // middle (33.3 - 2 x 15), at 0.33 ms a frame: about 10 frames, a few more with drops beside.
  EXPECT_LE(longest_gap, 16u);
  EXPECT_GE(longest_gap, 8u) << "the phase went through the band";
  // By sequence, left and right frame n are 0.33 n ms apart: beyond the 15 ms from frame 46 on.
  EXPECT_GT(recorder.frames.back().frame, 240u);
  const hal::SimCamera& left = *test::sim_board(linked.fw->board()).camera(hal::Side::left);
  const hal::SimCamera& right = *test::sim_board(linked.fw->board()).camera(hal::Side::right);
  const hal::PairingCounters& p = s.pairing;
  EXPECT_EQ(p.pairs, 240u + s.stale);
  EXPECT_GT(p.left().unpaired + p.right().unpaired, 20u);
  EXPECT_EQ(p.left().mismatched + p.right().mismatched + p.left().off_trigger, 0u);
  const std::uint64_t accounted_left =
      p.pairs + p.left().unpaired + p.left().mismatched + p.left().out_of_order;
  const std::uint64_t accounted_right =
      p.pairs + p.right().unpaired + p.right().mismatched + p.right().out_of_order;
  EXPECT_LE(accounted_left, p.left().pushed);
  EXPECT_LE(p.left().pushed - accounted_left, 4u) << "what still waits in the pairer";
  EXPECT_LE(accounted_right, p.right().pushed);
  EXPECT_LE(p.right().pushed - accounted_right, 4u);
  EXPECT_EQ(left.config().exposure, 3'000'000);
  EXPECT_EQ(right.config().exposure, 3'000'000);
}

TEST(FrameLoop, PairingFollowsTheBoardsTrigger) {
  const BoardConfig usb =
      load_board_config(std::filesystem::path(test::source_dir()) / "board" / "usb-stereo");
  const hal::PairingConfig p = pairing_config(usb);
  EXPECT_FALSE(usb.has_trigger()) << "two free-running UVC cameras: by time alone";
  EXPECT_EQ(p.tolerance, 16'000'000);
  EXPECT_EQ(p.trigger_period, hal::period_of(30)) << "the cameras' frame period";
  const BoardConfig pi = load_board_config(std::filesystem::path(test::source_dir()) / "board" /
                                           "raspberrypi5-ov9281");
  EXPECT_TRUE(pi.has_trigger()) << "one trigger for both: each pair takes its edge";
  EXPECT_FALSE(pairing_config(pi).edge_delay.has_value()) << "the Pi's delay is learned";
  EXPECT_EQ(pairing_config(pi).trigger_period, hal::period_of(30));
  // Without a trigger the tolerance must stay below half the cameras' frame period.
  const test::SimRig rig;
  try {
    rig.parse_free_running("pairing: {tolerance_us: 17000}\n");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pairing.tolerance_us: 17000 us is not below half the "
                                         "cameras' frame period (33333 us at 30 fps)"),
              std::string::npos)
        << e.what();
  }
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

// Everything the robot's end of a MAVLink board's link received, frame by frame.
std::vector<mavlink::Frame> mavlink_frames(LinkedRig& linked) {
  mavlink::StreamDecoder decoder;
  std::vector<mavlink::Frame> frames;
  std::array<std::byte, 4096> buffer{};
  for (;;) {
    const hal::IoResult r = linked.robot->read(buffer, 200'000'000);
    if (r.status != hal::IoStatus::ok) break;
    for (std::size_t i = 0; i < r.bytes; ++i) {
      for (auto f = decoder.push(static_cast<std::uint8_t>(buffer[i])); f; f = decoder.next()) {
        frames.push_back(*f);
      }
    }
  }
  EXPECT_EQ(decoder.stats().skipped_bytes + decoder.stats().bad_crc + decoder.stats().lost, 0u)
      << "every byte in a valid frame";
  return frames;
}

TEST(FrameLoop, MavlinkModeSendsObstacleDistanceEveryFrame) {
  LinkedRig linked("", BoardConfig::LinkProtocol::mavlink);
  const std::atomic<bool> stop{false};
  linked.fw->run(30, stop);
  int heartbeats = 0;
  int distances = 0;
  for (const mavlink::Frame& f : mavlink_frames(linked)) {
    if (const auto h = mavlink::decode_heartbeat(f)) {
      ++heartbeats;
      EXPECT_EQ(h->system_status, mavlink::kMavStateActive);
    }
    distances += mavlink::decode_obstacle_distance(f) ? 1 : 0;
  }
  EXPECT_EQ(distances, 30);
  EXPECT_GE(heartbeats, 1);
}

// Uncalibrated, a MAVLink board tells the flight controller it is not ready (and has no
// obstacle distances to send: nothing gets a depth).
TEST(FrameLoop, AnUncalibratedMavlinkBoardSaysItIsCalibrating) {
  LinkedRig linked([](const test::SimRig& r) {
    std::filesystem::remove(r.dir.path() / "rig.yaml");
    BoardConfig c = r.parse("");
    c.serial.protocol = BoardConfig::LinkProtocol::mavlink;
    return c;
  });
  const std::atomic<bool> stop{false};
  linked.fw->run(60, stop);
  const std::vector<mavlink::Frame> frames = mavlink_frames(linked);
  ASSERT_GE(frames.size(), 2u) << "the start-up heartbeat and one a second";
  for (const mavlink::Frame& f : frames) {
    const auto h = mavlink::decode_heartbeat(f);
    ASSERT_TRUE(h) << "only heartbeats: message " << f.message_id;
    EXPECT_EQ(h->system_status, mavlink::kMavStateCalibrating);
  }
}

TEST(FrameLoop, CalibrationOfAnotherSizeIsAnError) {
  test::SimRig rig;
  calib::save_calibration(rig.dir.path() / "rig.yaml", test::ideal_rig(320, 240, 100, 0.1));
  try {
    Firmware fw(rig.replaying(rig.config));
    FAIL() << "the calibration does not fit";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is for 320x240 images but the cameras deliver 160x96"),
              std::string::npos)
        << e.what();
  }
}

TEST(FrameLoop, MemoryBudgetIsEnforced) {
  test::SimRig rig(160, 96, 8, "memory_budget_mb: 0.01\n");
  EXPECT_THROW(Firmware(rig.replaying(rig.config)), Error);
}

}  // namespace
}  // namespace epipole::firmware

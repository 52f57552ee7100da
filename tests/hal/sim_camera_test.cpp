#include <gtest/gtest.h>

#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "epipole/core/error.hpp"
#include "sim/sim.hpp"
#include "sim/sim_scene.hpp"

namespace epipole::hal {
namespace {

constexpr int kW = 64;
constexpr int kH = 48;
constexpr Nanoseconds kMs = 1'000'000;

// Image i has every pixel of row y equal to (i * 16 + y) & 0xff.
std::vector<GrayImage> make_images(int count) {
  std::vector<GrayImage> images;
  for (int i = 0; i < count; ++i) {
    GrayImage image(kW, kH);
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) image(x, y) = static_cast<std::uint8_t>((i * 16 + y) & 0xff);
    }
    images.push_back(std::move(image));
  }
  return images;
}

CameraConfig config_for(const std::string& device) {
  CameraConfig c;
  c.device = device;
  c.width = kW;
  c.height = kH;
  c.trigger = TriggerMode::external;
  return c;
}

struct Rig {
  explicit Rig(SimCameraTiming timing = {})
      : board(50.0, make_images(3), make_images(3), timing),
        left(config_for("left"), board.left, board.clock, timing),
        right(config_for("right"), board.right, board.clock, timing) {
    board.trigger.connect(left);
    board.trigger.connect(right);
    board.trigger.start();
    left.start();
    right.start();
  }
  SimBoard board;
  SimCamera left;
  SimCamera right;
};

TEST(SimTrigger, EdgesAtTheRateOnTheVirtualClock) {
  VirtualClock clock(1000);
  TriggerConfig config{
      .line = "sim", .chip = {}, .role = TriggerRole::master, .rate_hz = 100.0, .pulse_width = kMs};
  SimTrigger trigger(config, clock);
  EXPECT_EQ(trigger.wait_edge(kMs).status, EdgeStatus::lost) << "not started";
  trigger.start();
  for (std::uint32_t i = 0; i < 5; ++i) {
    const EdgeResult r = trigger.wait_edge(20 * kMs);
    ASSERT_EQ(r.status, EdgeStatus::ok);
    EXPECT_EQ(r.edge.sequence, i);
    EXPECT_EQ(r.edge.timestamp, 1000 + static_cast<Nanoseconds>(i) * 10 * kMs);
    EXPECT_EQ(r.edge.clock, ClockId::virtual_clock);
    EXPECT_EQ(clock.now(), r.edge.timestamp);
  }
  EXPECT_EQ(trigger.wait_edge(kMs).status, EdgeStatus::timeout);
  EXPECT_EQ(clock.now(), 1000 + 41 * kMs);
}

TEST(SimTrigger, SetRateReanchorsAtTheLastEdge) {
  VirtualClock clock(1000);
  TriggerConfig config{
      .line = "sim", .chip = {}, .role = TriggerRole::master, .rate_hz = 100.0, .pulse_width = kMs};
  SimTrigger trigger(config, clock);
  trigger.set_rate(50.0);  // before start: the schedule starts at the new rate
  EXPECT_EQ(trigger.period(), 20 * kMs);
  trigger.start();
  EXPECT_EQ(trigger.wait_edge(kMs).edge.timestamp, 1000);
  EXPECT_EQ(trigger.wait_edge(30 * kMs).edge.timestamp, 1000 + 20 * kMs);
  trigger.set_rate(100.0);
  EXPECT_EQ(trigger.config().rate_hz, 100.0);
  EXPECT_EQ(trigger.period(), 10 * kMs);
  std::vector<TriggerEdge> edges;
  for (int i = 0; i < 4; ++i) {
    const EdgeResult r = trigger.wait_edge(30 * kMs);
    ASSERT_EQ(r.status, EdgeStatus::ok);
    edges.push_back(r.edge);
  }
  // Edge 1 (20 ms) was the last one fired: 2, 3, ... come 10 ms apart from it.
  for (std::size_t i = 0; i < edges.size(); ++i) {
    EXPECT_EQ(edges[i].sequence, 2 + i);
    EXPECT_EQ(edges[i].timestamp, 1000 + 20 * kMs + static_cast<Nanoseconds>(i + 1) * 10 * kMs);
  }
  // Impossible rates change nothing.
  for (const double bad : {0.0, -5.0, 2000.0, 1000.0}) {  // 1000 Hz: the 1 ms pulse does not fit
    try {
      trigger.set_rate(bad);
      FAIL() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("trigger sim: "), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(trigger.config().rate_hz, 100.0);
  EXPECT_EQ(trigger.wait_edge(30 * kMs).edge.timestamp, edges.back().timestamp + 10 * kMs);
}

TEST(SimTrigger, SetRateWhileCamerasHoldEdgesAheadKeepsEveryEdgeOnce) {
  // The cameras are told of edges up to their acquire deadline, ahead of the clock, and the
  // record lags behind it: a change must not renumber, repeat or move any of those edges.
  Rig rig;  // 50 Hz, no jitter: a frame's timestamp is its edge + 5 ms
  TriggerRecord record;
  rig.board.trigger.record_edges_to(&record);
  std::vector<Nanoseconds> left, right;
  const auto take = [&](SimCamera& camera, std::vector<Nanoseconds>& times, int frames) {
    for (int i = 0; i < frames; ++i) {
      const AcquireResult r = camera.acquire(200 * kMs);
      ASSERT_EQ(r.status, AcquireStatus::ok);
      EXPECT_EQ(r.frame.sequence, times.size()) << "every edge once, in order";
      times.push_back(r.frame.timestamp - 5 * kMs);
      camera.release(r.frame);
    }
  };
  take(rig.left, left, 4);
  take(rig.right, right, 2);
  const Nanoseconds changed_at = rig.board.clock.now();
  rig.board.trigger.set_rate(20.0);
  for (int i = 0; i < 21; ++i) {  // in turn, so that neither camera's queue overflows
    take(rig.left, left, 1);
    take(rig.right, right, 1);
  }
  take(rig.right, right, 2);
  ASSERT_EQ(left, right) << "both cameras saw the same edges";
  EXPECT_EQ(rig.left.overruns() + rig.right.overruns(), 0u);
  std::size_t first_new = 0;
  for (std::size_t i = 1; i < left.size(); ++i) {
    const Nanoseconds step = left[i] - left[i - 1];
    if (first_new == 0 && step != 20 * kMs) first_new = i;
    EXPECT_EQ(step, first_new == 0 ? 20 * kMs : 50 * kMs) << "edge " << i;
  }
  ASSERT_GT(first_new, 4u) << "edges already given to the cameras keep their time";
  // The anchor is the last edge that existed at the change: ahead of the clock (the cameras were
  // told of edges up to their deadline), by at most one acquire timeout.
  EXPECT_GE(left[first_new - 1], changed_at);
  EXPECT_LE(left[first_new - 1], changed_at + 200 * kMs);
  for (std::uint32_t s = 0; s < 25; ++s) {
    const auto edge = record.find(s);
    ASSERT_TRUE(edge.has_value()) << s;
    EXPECT_EQ(edge->timestamp, left[s]) << "the record holds the same edges";
  }
}

TEST(SimTrigger, BadConfigurationNamesTheLine) {
  VirtualClock clock;
  TriggerConfig config{
      .line = "TRIG0", .chip = {}, .role = TriggerRole::master, .rate_hz = 0.0, .pulse_width = kMs};
  try {
    SimTrigger trigger(config, clock);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("TRIG0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rate"), std::string::npos) << e.what();
  }
  config.rate_hz = 100.0;
  config.pulse_width = 20 * kMs;
  EXPECT_THROW(SimTrigger(config, clock), Error);
}

TEST(SimCamera, EachEdgeMakesBothCamerasDeliverAFrame) {
  SimCameraTiming timing;
  timing.exposure_delay = 3 * kMs;
  timing.jitter = 100'000;
  timing.readout = kMs;
  Rig rig(timing);
  for (std::uint32_t i = 0; i < 30; ++i) {
    for (SimCamera* camera : {&rig.left, &rig.right}) {
      const AcquireResult r = camera->acquire(100 * kMs);
      ASSERT_EQ(r.status, AcquireStatus::ok) << i;
      EXPECT_EQ(r.frame.sequence, i);
      EXPECT_EQ(r.frame.clock, ClockId::virtual_clock);
      const Nanoseconds edge = static_cast<Nanoseconds>(i) * 20 * kMs;
      EXPECT_GE(r.frame.timestamp, edge + 3 * kMs - 100'000);
      EXPECT_LE(r.frame.timestamp, edge + 3 * kMs + 100'000);
      EXPECT_EQ(r.frame.gray.width(), kW);
      EXPECT_EQ(r.frame.gray(5, 7), static_cast<std::uint8_t>((i % 3) * 16 + 7));
      EXPECT_EQ(camera->true_sequence(r.frame), i);
      camera->release(r.frame);
    }
  }
  EXPECT_EQ(rig.left.overruns(), 0u);
}

TEST(SimCamera, FreeRunningWithoutATrigger) {
  VirtualClock clock;
  CameraConfig config = config_for("solo");
  config.trigger = TriggerMode::free_running;
  config.fps = 10.0;
  SimCamera camera(config, std::make_shared<const std::vector<GrayImage>>(make_images(1)), clock);
  EXPECT_EQ(camera.name(), "sim:solo");
  camera.start();
  for (std::uint32_t i = 0; i < 3; ++i) {
    const AcquireResult r = camera.acquire(200 * kMs);
    ASSERT_EQ(r.status, AcquireStatus::ok);
    EXPECT_EQ(r.frame.sequence, i);
    camera.release(r.frame);
  }
}

TEST(SimCamera, SetExposureScalesTheReplayedBrightness) {
  VirtualClock clock;
  CameraConfig config = config_for("solo");
  config.trigger = TriggerMode::free_running;
  config.exposure = 4 * kMs;
  config.gain = 2.0;
  SimCamera camera(config, std::make_shared<const std::vector<GrayImage>>(make_images(1)), clock);
  camera.start();
  // Row y of image 0 is y everywhere: 0..47.
  const auto row_value = [&](int y) {
    const AcquireResult r = camera.acquire(100 * kMs);
    EXPECT_EQ(r.status, AcquireStatus::ok);
    const int v = r.frame.gray(3, y);
    camera.release(r.frame);
    return v;
  };
  EXPECT_EQ(row_value(40), 40);
  camera.set_exposure(8 * kMs, 2.0);  // twice the light
  EXPECT_EQ(camera.config().exposure, 8 * kMs);
  EXPECT_EQ(row_value(40), 80);
  camera.set_exposure(8 * kMs, 6.0);  // six times: 40 * 6 saturates
  EXPECT_EQ(row_value(40), 240);
  EXPECT_EQ(row_value(45), 255);
  camera.set_exposure(2 * kMs, 0.0);  // half, gain automatic (not scaled)
  EXPECT_EQ(camera.config().gain, 0.0);
  EXPECT_EQ(row_value(41), 21);
  for (const auto& [exposure, gain] : {std::pair<Nanoseconds, double>{-1, 1.0},
                                       {11'000 * kMs, 1.0},
                                       {kMs, -1.0},
                                       {kMs, 1e6},
                                       {kMs, std::numeric_limits<double>::quiet_NaN()}}) {
    try {
      camera.set_exposure(exposure, gain);
      FAIL() << exposure << " " << gain;
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("camera sim:solo: "), std::string::npos) << m;
      EXPECT_NE(m.find(exposure < 0 || exposure > kMaxExposure ? "exposure" : "gain"),
                std::string::npos)
          << m;
    }
  }
  EXPECT_EQ(camera.config().exposure, 2 * kMs) << "a refused value changes nothing";
  EXPECT_EQ(row_value(41), 21);
}

TEST(SimCamera, BadInputNamesDeviceAndSetting) {
  VirtualClock clock;
  auto images = std::make_shared<const std::vector<GrayImage>>(make_images(1));
  auto message = [&](const CameraConfig& config) {
    try {
      SimCamera camera(config, images, clock);
      camera.start();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CameraConfig c = config_for("cam7");
  c.width = 100;
  EXPECT_NE(message(c).find("size setting is 100x48"), std::string::npos) << message(c);
  c = config_for("cam7");
  c.format = PixelFormat::yuyv;
  EXPECT_NE(message(c).find("yuyv"), std::string::npos) << message(c);
  c = config_for("cam7");
  c.width = -3;
  EXPECT_NE(message(c).find("cam7: size -3x48"), std::string::npos) << message(c);
  c = config_for("cam7");
  c.buffer_count = 1;
  EXPECT_NE(message(c).find("buffer count"), std::string::npos) << message(c);
  c = config_for("cam7");
  c.fps = -1;
  EXPECT_NE(message(c).find("frame rate"), std::string::npos) << message(c);
  c = config_for("cam7");  // external trigger, nothing connected
  EXPECT_NE(message(c).find("cam7: trigger mode external"), std::string::npos) << message(c);
  EXPECT_FALSE(parse_pixel_format("rgb24").has_value());
  EXPECT_EQ(parse_pixel_format("NV12"), PixelFormat::nv12);
}

TEST(SimCamera, DropDelayStallFaults) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::drop, .sequence = 2, .count = 2});
  rig.left.inject({.kind = SimFaultKind::delay, .sequence = 5, .duration = 30 * kMs});
  rig.left.inject({.kind = SimFaultKind::stall, .sequence = 8, .duration = 50 * kMs});
  std::vector<std::uint32_t> seen;
  std::vector<Nanoseconds> arrival;
  for (int i = 0; i < 14; ++i) {
    const AcquireResult r = rig.left.acquire(200 * kMs);
    ASSERT_EQ(r.status, AcquireStatus::ok);
    seen.push_back(r.frame.sequence);
    arrival.push_back(rig.board.clock.now());
    rig.left.release(r.frame);
  }
  // 2, 3 dropped; 8, 9, 10 fall into the 50 ms stall (edges 160, 180, 200 ms; stall to 210 ms).
  const std::vector<std::uint32_t> expected = {0, 1, 4, 5, 6, 7, 11, 12, 13, 14, 15, 16, 17, 18};
  EXPECT_EQ(seen, expected);
  // Frame 5 (edge 100 ms) arrives 30 ms late, and 6 queues behind it.
  EXPECT_EQ(arrival[3], 100 * kMs + 5 * kMs + 2 * kMs + 30 * kMs);
  EXPECT_EQ(arrival[4], arrival[3]);
  const AcquireResult none = rig.left.acquire(kMs);
  EXPECT_EQ(none.status, AcquireStatus::timeout);
}

TEST(SimCamera, CorruptAndWrongSequenceFaults) {
  Rig rig;
  rig.right.inject({.kind = SimFaultKind::corrupt_pixels, .sequence = 1});
  rig.right.inject({.kind = SimFaultKind::wrong_sequence, .sequence = 2, .value = 1});
  for (std::uint32_t i = 0; i < 3; ++i) {
    const AcquireResult r = rig.right.acquire(100 * kMs);
    ASSERT_EQ(r.status, AcquireStatus::ok);
    EXPECT_EQ(rig.right.true_sequence(r.frame), i);
    if (i == 1) {
      int differing = 0;
      for (int x = 0; x < kW; ++x) differing += r.frame.gray(x, 3) != (16 + 3) ? 1 : 0;
      EXPECT_GT(differing, kW / 2);
    }
    EXPECT_EQ(r.frame.sequence, i == 2 ? 1u : i);
    rig.right.release(r.frame);
  }
}

TEST(SimCamera, DamagedFramesAreReportedCorruptWithoutABuffer) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::damaged, .sequence = 1});
  std::vector<AcquireStatus> statuses;
  for (int i = 0; i < 3; ++i) {
    const AcquireResult r = rig.left.acquire(100 * kMs);
    statuses.push_back(r.status);
    EXPECT_TRUE(r.status != AcquireStatus::corrupt || !r.frame.valid());
    if (r.status != AcquireStatus::ok) continue;
    EXPECT_EQ(rig.left.true_sequence(r.frame), i == 0 ? 0u : 2u);
    rig.left.release(r.frame);
  }
  EXPECT_EQ(statuses, (std::vector<AcquireStatus>{AcquireStatus::ok, AcquireStatus::corrupt,
                                                  AcquireStatus::ok}));
  EXPECT_EQ(rig.left.delivered(), 2u);
  EXPECT_STREQ(to_string(AcquireStatus::corrupt), "corrupt frame");
}

TEST(SimCamera, DisconnectUntilReopen) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::disconnect, .sequence = 3, .value = 1});
  for (int i = 0; i < 3; ++i) {
    const AcquireResult r = rig.left.acquire(100 * kMs);
    ASSERT_EQ(r.status, AcquireStatus::ok);
    rig.left.release(r.frame);
  }
  const AcquireResult held = rig.left.acquire(100 * kMs);
  EXPECT_EQ(held.status, AcquireStatus::device_lost);
  EXPECT_EQ(rig.left.acquire(100 * kMs).status, AcquireStatus::device_lost);
  try {
    rig.left.reopen();
    FAIL() << "the first reopen was to fail";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sim:left"), std::string::npos);
  }
  rig.left.reopen();
  const AcquireResult r = rig.left.acquire(100 * kMs);
  ASSERT_EQ(r.status, AcquireStatus::ok);
  EXPECT_GT(r.frame.sequence, 3u);
  rig.left.release(r.frame);
}

TEST(SimCamera, BuffersAreAFixedRing) {
  Rig rig;
  std::vector<Frame> held;
  for (int i = 0; i < 4; ++i) {
    const AcquireResult r = rig.left.acquire(100 * kMs);
    ASSERT_EQ(r.status, AcquireStatus::ok);
    held.push_back(r.frame);
  }
  EXPECT_EQ(rig.left.acquire(100 * kMs).status, AcquireStatus::timeout) << "all buffers lent";
  EXPECT_GE(rig.left.overruns(), 1u);
  rig.left.release(held[0]);
  EXPECT_THROW(rig.left.release(held[0]), Error) << "released twice";
  EXPECT_EQ(rig.left.acquire(100 * kMs).status, AcquireStatus::ok);
}

TEST(SynthesizeRight, ShiftsByTheDisparity) {
  GrayImage left(20, 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 20; ++x) left(x, y) = static_cast<std::uint8_t>(x * 10 + y);
  }
  const GrayImage right = synthesize_right(left.view(), 4);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 20; ++x) EXPECT_EQ(right(x, y), left(std::min(x + 4, 19), y));
  }
  EXPECT_THROW(synthesize_right(left.view(), 20), Error);
  EXPECT_THROW(synthesize_right(left.view(), -1), Error);
}

}  // namespace
}  // namespace epipole::hal

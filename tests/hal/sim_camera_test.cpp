#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/hal/sim.hpp"

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
    EXPECT_EQ(clock.now(), r.edge.timestamp);
  }
  EXPECT_EQ(trigger.wait_edge(kMs).status, EdgeStatus::timeout);
  EXPECT_EQ(clock.now(), 1000 + 41 * kMs);
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

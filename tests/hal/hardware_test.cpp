// hal::Hardware: a board's devices made from its parts' backends, the simulation kept inside.
#include "epipole/hal/hardware.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "epipole/core/error.hpp"
#include "sim/sim.hpp"

namespace epipole::hal {
namespace {

constexpr int kSceneWidth = 32;
constexpr int kSceneHeight = 16;

HardwareConfig simulated(int images) {
  HardwareConfig c;
  c.camera_backend = "sim";
  for (auto [camera, name] : {std::pair{&c.left, "left"}, std::pair{&c.right, "right"}}) {
    camera->device = name;
    camera->width = kSceneWidth;
    camera->height = kSceneHeight;
    camera->trigger = TriggerMode::external;
  }
  c.trigger_backend = "sim";
  c.trigger.line = "sim";
  c.trigger.rate_hz = 50;
  for (int i = 0; i < images; ++i) {
    c.sim.left.emplace_back(kSceneWidth, kSceneHeight);
    c.sim.right.emplace_back(kSceneWidth, kSceneHeight);
  }
  return c;
}

TEST(Hardware, ASimulatedBoardRunsOnItsVirtualClockWithItsScene) {
  HardwareConfig c = simulated(3);
  c.sim.drop_rate = 0.25;
  Hardware hw(std::move(c));
  EXPECT_EQ(hw.clock().id(), ClockId::virtual_clock);
  EXPECT_EQ(hw.scene_images(), 3u);
  EXPECT_EQ(hw.scene_bytes(), 2u * 3u * GrayImage(kSceneWidth, kSceneHeight).size_bytes())
      << "rows padded as allocated";
  ASSERT_NE(hw.trigger(), nullptr);
  EXPECT_EQ(hw.serial(), nullptr) << "no link asked for";
  ASSERT_NE(hw.sim(), nullptr);
  EXPECT_EQ(hw.sim()->camera(Side::left), &hw.camera(Side::left));
  EXPECT_EQ(hw.sim()->camera(Side::right), &hw.camera(Side::right));

  // Each edge of the trigger reaches both cameras (a frame 7 ms later); about a quarter of the
  // frames are dropped on each side.
  hw.camera(Side::left).start();
  hw.camera(Side::right).start();
  hw.trigger()->start();
  int delivered = 0;
  for (int i = 0; i < 200; ++i) {
    ASSERT_EQ(hw.trigger()->wait_edge(100'000'000).status, EdgeStatus::ok);
    for (Side side : {Side::left, Side::right}) {
      const AcquireResult r = hw.camera(side).acquire(8'000'000);
      if (r.status != AcquireStatus::ok) continue;
      EXPECT_EQ(r.frame.clock, ClockId::virtual_clock);
      EXPECT_EQ(r.frame.sequence, static_cast<std::uint32_t>(i));
      hw.camera(side).release(r.frame);
      ++delivered;
    }
  }
  EXPECT_GT(delivered, 220) << "most frames arrive";
  EXPECT_LT(delivered, 380) << "the drop rate reaches the cameras";
}

// A camera that never delivers: enough to stand for a real backend's.
class IdleCamera final : public CameraSource {
 public:
  explicit IdleCamera(CameraConfig config) : config_(std::move(config)) {}
  const std::string& name() const override { return config_.device; }
  const CameraConfig& config() const override { return config_; }
  void start() override {}
  void stop() override {}
  bool streaming() const override { return false; }
  AcquireResult acquire(Nanoseconds) override { return {}; }
  void release(const Frame&) override {}
  void reopen() override {}
  void set_exposure(Nanoseconds, double) override {}

 private:
  CameraConfig config_;
};

TEST(Hardware, RealBackendsRunOnTheMonotonicClockWithoutAScene) {
  BackendRegistry registry;
  int made = 0;
  registry.add_camera("fake", [&](const CameraConfig& config, const BackendContext& context) {
    EXPECT_EQ(context.sim, nullptr) << "no simulation for a real backend";
    EXPECT_EQ(context.clock->id(), ClockId::monotonic);
    ++made;
    return std::make_unique<IdleCamera>(config);
  });
  HardwareConfig c = simulated(1);
  c.camera_backend = "fake";
  c.trigger_backend = std::string(kNoBackend);
  Hardware hw(std::move(c), registry);
  EXPECT_EQ(made, 2);
  EXPECT_EQ(hw.clock().id(), ClockId::monotonic);
  EXPECT_EQ(hw.sim(), nullptr);
  EXPECT_EQ(hw.scene_images(), 0u);
  EXPECT_EQ(hw.scene_bytes(), 0u);
  EXPECT_EQ(hw.trigger(), nullptr);
}

TEST(Hardware, ASimulatedBoardWithoutImagesOrWithAnUnknownPartSaysWhat) {
  try {
    Hardware hw(simulated(0));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no images"), std::string::npos) << e.what();
  }
  HardwareConfig c = simulated(1);
  c.serial_backend = "carrier-pigeon";
  try {
    Hardware hw(std::move(c));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown backend 'carrier-pigeon'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace epipole::hal

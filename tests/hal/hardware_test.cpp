// hal::Hardware: a board's devices made from its parts' backends, the simulation kept inside.
#include "epipole/hal/hardware.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "epipole/core/error.hpp"
#include "sim/sim.hpp"
#include "sim/sim_settings.hpp"

namespace epipole::hal {
namespace {

template <typename F>
std::string test_error(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

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
  c.width = kSceneWidth;
  c.height = kSceneHeight;
  auto sim = std::make_unique<SimSettings>();
  sim->charge_compute = false;
  auto scene = std::make_shared<StereoImages>();
  for (int i = 0; i < images; ++i) {
    scene->left.emplace_back(kSceneWidth, kSceneHeight);
    scene->right.emplace_back(kSceneWidth, kSceneHeight);
  }
  sim->images = std::move(scene);
  c.sections.set("sim", std::move(sim));
  return c;
}

TEST(Hardware, ASimulatedBoardRunsOnItsVirtualClockWithItsScene) {
  HardwareConfig c = simulated(3);
  sim_settings(c.sections).drop_rate = 0.25;
  Hardware hw(std::move(c));
  EXPECT_EQ(hw.clock().id(), ClockId::virtual_clock);
  ASSERT_NE(simulated_board(hw), nullptr);
  EXPECT_EQ(simulated_board(hw)->scene_images(), 3u);
  EXPECT_EQ(hw.backend_bytes(), 2u * 3u * GrayImage(kSceneWidth, kSceneHeight).size_bytes())
      << "rows padded as allocated";
  ASSERT_NE(hw.trigger(), nullptr);
  EXPECT_EQ(hw.serial(), nullptr) << "no link asked for";
  EXPECT_EQ(simulated_board(hw)->camera(Side::left), &hw.camera(Side::left));
  EXPECT_EQ(simulated_board(hw)->camera(Side::right), &hw.camera(Side::right));

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
    EXPECT_EQ(context.board, nullptr) << "nothing shared for a backend without a section";
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
  EXPECT_EQ(hw.backend_board(), nullptr);
  EXPECT_EQ(simulated_board(hw), nullptr);
  EXPECT_EQ(hw.backend_bytes(), 0u);
  EXPECT_EQ(hw.trigger(), nullptr);
}

// A backend with a section of its own: what it read reaches what its devices share, which gives
// them the board's clock and counts its memory; the board file knows nothing of it.
struct Gains final : BackendSettings {
  int gain = 0;
  std::unique_ptr<BackendSettings> clone() const override { return std::make_unique<Gains>(*this); }
};

struct SharedGain final : BackendBoard {
  explicit SharedGain(int g, bool clocked = true) : gain(g), has_clock(clocked) {}
  int gain;
  bool has_clock;
  VirtualClock clock;
  Clock* own_clock() override { return has_clock ? &clock : nullptr; }
  std::size_t memory_bytes() const override { return 4096; }
};

TEST(Hardware, ABackendsSectionMakesWhatItsDevicesShare) {
  BackendRegistry registry;
  int gain_seen = -1;
  registry.add_camera("rig",
                      [&](const CameraConfig& config, const BackendContext& context) {
                        gain_seen = dynamic_cast<SharedGain&>(*context.board).gain;
                        EXPECT_EQ(context.clock->id(), ClockId::virtual_clock);
                        return std::make_unique<IdleCamera>(config);
                      },
                      {.section = "rig"});
  registry.add_section({"rig", nullptr,
                        [](const BackendSettings& s, const HardwareConfig&) {
                          return std::make_unique<SharedGain>(dynamic_cast<const Gains&>(s).gain);
                        },
                        nullptr});
  HardwareConfig c = simulated(1);
  c.camera_backend = "rig";
  c.trigger_backend = std::string(kNoBackend);
  const std::string missing = test_error([&] { Hardware hw(c, registry); });
  EXPECT_NE(missing.find("backend 'rig' needs the board file's 'rig' section"), std::string::npos)
      << missing;

  auto gains = std::make_unique<Gains>();
  gains->gain = 12;
  c.sections.set("rig", std::move(gains));
  const HardwareConfig copy = c;  // copies the settings
  Hardware hw(copy, registry);
  EXPECT_EQ(gain_seen, 12);
  EXPECT_EQ(hw.clock().id(), ClockId::virtual_clock);
  EXPECT_EQ(hw.backend_bytes(), 4096u);
}

// A port that carries nothing: enough to stand for a serial backend's.
class SilentPort final : public SerialPort {
 public:
  IoResult read(std::span<std::byte>, Nanoseconds) override { return {IoStatus::timeout, 0}; }
  IoResult write(std::span<const std::byte> data, Nanoseconds) override {
    return {IoStatus::ok, data.size()};
  }
  bool is_open() const override { return true; }
  void reopen() override {}
  void close() override {}
};

TEST(Hardware, EachBackendsDevicesGetWhatTheirOwnSectionMakes) {
  BackendRegistry registry;
  const auto gain_of = [](const BackendContext& context) {
    return context.board != nullptr ? dynamic_cast<SharedGain&>(*context.board).gain : -1;
  };
  std::vector<int> cameras_saw, link_saw;
  registry.add_camera("rig",
                      [&](const CameraConfig& config, const BackendContext& context) {
                        cameras_saw.push_back(gain_of(context));
                        return std::make_unique<IdleCamera>(config);
                      },
                      {.section = "rig"});
  registry.add_serial("radio",
                      [&](const SerialConfig&, const BackendContext& context) {
                        link_saw.push_back(gain_of(context));
                        EXPECT_EQ(context.clock->id(), ClockId::virtual_clock)
                            << "the cameras' board's clock is every device's";
                        return std::make_unique<SilentPort>();
                      },
                      {.section = "radio"});
  int boards_made = 0;
  for (const char* name : {"rig", "radio"}) {
    registry.add_section({name, nullptr,
                          [&, clocked = name == std::string("rig")](const BackendSettings& s,
                                                                    const HardwareConfig&) {
                            ++boards_made;
                            return std::make_unique<SharedGain>(dynamic_cast<const Gains&>(s).gain,
                                                                clocked);
                          },
                          nullptr});
  }
  HardwareConfig c = simulated(1);
  c.camera_backend = "rig";
  c.trigger_backend = std::string(kNoBackend);
  c.serial_backend = "radio";
  for (const auto& [name, gain] : {std::pair{"rig", 3}, std::pair{"radio", 7}}) {
    auto gains = std::make_unique<Gains>();
    gains->gain = gain;
    c.sections.set(name, std::move(gains));
  }
  Hardware hw(c, registry);
  EXPECT_EQ(cameras_saw, (std::vector<int>{3, 3})) << "both cameras share one board";
  EXPECT_EQ(link_saw, (std::vector<int>{7}));
  EXPECT_EQ(boards_made, 2);
  EXPECT_EQ(dynamic_cast<SharedGain&>(*hw.backend_board()).gain, 3) << "the cameras'";
  EXPECT_EQ(hw.backend_bytes(), 2 * 4096u) << "both boards' memory";

  c.sections.set("radio", nullptr);
  const std::string missing = test_error([&] { Hardware no_radio(c, registry); });
  EXPECT_NE(missing.find("serial: backend 'radio' needs the board file's 'radio' section"),
            std::string::npos)
      << missing;
}

TEST(Hardware, ASimulatedTriggerBesideRealCamerasIsRefusedForItsOwnClock) {
  HardwareConfig c = simulated(1);
  c.camera_backend = "v4l2";
  c.left.device = "/dev/video0";
  c.left.format = PixelFormat::yuyv;
  c.right.device = "/dev/video2";
  c.right.format = PixelFormat::yuyv;
  const std::string error = test_error([&] { Hardware hw(c); });
  EXPECT_NE(error.find("trigger: backend 'sim' runs on a clock of its own"), std::string::npos)
      << error;
}

TEST(Hardware, StandInsReplaceARealBoardsDevicesButNotASimulatedOnes) {
  HardwareConfig sim = simulated(1);
  EXPECT_FALSE(stand_in_for_devices(sim)) << "the simulated board opens nothing";

  HardwareConfig real = simulated(1);
  real.camera_backend = "v4l2";
  real.left.device = "/dev/video0";
  real.left.format = PixelFormat::yuyv;
  real.right.device = "/dev/video2";
  real.trigger_backend = "gpiod";
  real.trigger.role = TriggerRole::slave;
  real.sections = {};
  ASSERT_TRUE(stand_in_for_devices(real));
  EXPECT_EQ(real.camera_backend, "sim");
  EXPECT_EQ(real.left.format, PixelFormat::grey);
  EXPECT_EQ(real.trigger_backend, "sim");
  EXPECT_EQ(real.trigger.role, TriggerRole::master);
  Hardware hw(std::move(real));
  EXPECT_EQ(hw.camera(Side::left).config().width, kSceneWidth);
  EXPECT_EQ(simulated_board(hw)->scene_images(), 1u) << "one blank image of the board's size";
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

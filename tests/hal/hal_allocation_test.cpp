#include <gtest/gtest.h>

#include <memory>
#include <string_view>
#include <vector>

#include "allocation_counter.hpp"
#include "epipole/hal/recovery.hpp"
#include "epipole/hal/stereo_pairing.hpp"
#include "libcamera/libcamera_camera.hpp"
#include "sim/sim.hpp"

namespace epipole::hal {
namespace {

// A simulated board at 30 Hz with 64x32 images, and a camera configuration for it.
SimBoard small_board() {
  std::vector<GrayImage> left, right;
  left.emplace_back(64, 32);
  right.emplace_back(64, 32);
  return SimBoard(30.0, std::move(left), std::move(right));
}

CameraConfig small_camera(const char* device, TriggerMode trigger) {
  CameraConfig config;
  config.width = 64;
  config.height = 32;
  config.trigger = trigger;
  config.device = device;
  return config;
}

// Pairs from the grabber, `turns` times, each given back at once; `before` runs first each turn.
template <typename Before>
int grab_pairs(StereoGrabber& grabber, int turns, Before before) {
  int pairs = 0;
  for (int i = 0; i < turns; ++i) {
    before(i);
    const PairResult p = grabber.next(100'000'000);
    if (p.status != PairStatus::ok) continue;
    ++pairs;
    grabber.release(p.pair);
  }
  return pairs;
}

TEST(HalAllocations, AcquireReleaseAndPairingNeverAllocate) {
  SimBoard board = small_board();
  SimCamera l(small_camera("left", TriggerMode::external), board.left, board.clock, board.timing);
  SimCamera r(small_camera("right", TriggerMode::external), board.right, board.clock, board.timing);
  board.trigger.connect(l);
  board.trigger.connect(r);
  r.inject({.kind = SimFaultKind::drop, .sequence = 20, .count = 2});
  r.inject({.kind = SimFaultKind::corrupt_pixels, .sequence = 30});
  r.inject({.kind = SimFaultKind::damaged, .sequence = 35});
  l.inject({.kind = SimFaultKind::disconnect, .sequence = 40});
  for (SimCamera* camera : {&l, &r}) {
    camera->inject({.kind = SimFaultKind::wrong_sequence, .sequence = 50, .value = 51});
  }
  board.trigger.inject({SimTriggerGlitchKind::unrecorded, 60, 0});
  board.trigger.inject({SimTriggerGlitchKind::extra_edge, 70, 10'000});
  TriggerRecord record;
  record.set_min_gap(1'000'000);
  board.trigger.record_edges_to(&record);
  RecoveringCamera rl(l, board.clock);
  StereoGrabber grabber(rl, r, board.clock,
                        {.tolerance = 1'000'000,
                         .trigger_period = 0,
                         .edge_delay = board.timing.exposure_delay,
                         .edge_tolerance = 1'000'000},
                        &record);
  board.trigger.start();
  l.start();
  r.start();
  test::AllocationCounter counter;
  const int pairs = grab_pairs(grabber, 200, [](int) {});
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_GT(pairs, 100);
  EXPECT_EQ(rl.counters().reopens, 1u);
  EXPECT_EQ(grabber.pairer().counters().right().corrupt, 1u);
  EXPECT_EQ(grabber.pairer().counters().left().off_trigger, 1u) << "edge 60 was not recorded";
  EXPECT_EQ(record.bounces(), 1u);
}

TEST(HalAllocations, RunTimeControlsAndPairingByTimeNeverAllocate) {
  SimBoard board = small_board();
  SimCamera triggered(small_camera("left", TriggerMode::external), board.left, board.clock,
                      board.timing);
  board.trigger.connect(triggered);
  // Two free-running cameras at slightly different rates, paired by time.
  CameraConfig config = small_camera("left", TriggerMode::free_running);
  config.exposure = 2'000'000;
  config.gain = 1.0;
  SimCamera l(config, board.left, board.clock, board.timing);
  config.device = "right";
  config.fps = 30.1;
  SimCamera r(config, board.right, board.clock, board.timing);
  l.set_fault_rates({.drop = 0.05, .seed = 3});
  RecoveringCamera rl(l, board.clock);
  StereoGrabber grabber(rl, r, board.clock,
                        {.tolerance = 10'000'000, .trigger_period = 33'222'591});
  board.trigger.start();
  triggered.start();
  l.start();
  r.start();
  test::AllocationCounter counter;
  const int pairs = grab_pairs(grabber, 300, [&](int i) {
    if (i % 50 == 10) {  // 60 Hz, 4 ms and 2x at 10, 110, 210; back at 60, 160, 260
      board.trigger.set_rate(i % 100 == 10 ? 60.0 : 30.0);
      rl.set_exposure(i % 100 == 10 ? 4'000'000 : 0, i % 100 == 10 ? 2.0 : 0.0);
      grabber.pairer().set_trigger_period(33'222'591);
    }
    const AcquireResult t = triggered.acquire(100'000'000);
    if (t.status == AcquireStatus::ok) triggered.release(t.frame);
  });
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_GT(pairs, 200);
  EXPECT_EQ(board.trigger.config().rate_hz, 30.0);
  EXPECT_EQ(l.config().exposure, 0);
}

// The libcamera backend's acquire/release half, fed with fake completed requests: frames,
// damaged and cancelled requests, conversions.
class CountingRequeuer final : public LibcameraStream::Requeuer {
 public:
  bool requeue(int) override {
    ++count;
    return true;
  }
  int count = 0;
};

TEST(HalAllocations, LibcameraAcquireReleaseNeverAllocates) {
  for (const char* name : {"R8", "R10_CSI2P"}) {
    const LibcameraFormat* format = nullptr;
    for (const LibcameraFormat& f : libcamera_formats()) {
      if (std::string_view(f.name) == name) format = &f;
    }
    ASSERT_NE(format, nullptr);
    const int w = 64, h = 32;
    const std::size_t stride = row_bytes(format->layout, w);
    std::vector<std::vector<std::uint8_t>> storage(4, std::vector<std::uint8_t>(stride * h, 7));
    std::vector<MappedPlane> planes;
    for (const auto& s : storage) planes.push_back({s.data(), s.size()});
    CountingRequeuer requeuer;
    LibcameraStream stream;
    const std::uint32_t g = stream.start("cam0", *format, w, h, stride, planes, requeuer);
    int frames = 0;
    int corrupt = 0;
    test::AllocationCounter counter;
    for (std::uint32_t i = 0; i < 300; ++i) {
      RequestCompletion c;
      c.slot = static_cast<int>(i % 4);
      c.generation = g;
      c.sequence = i;
      c.damaged = i % 7 == 3;
      c.cancelled = i % 11 == 5;
      ASSERT_TRUE(stream.ring().complete(c));
      const AcquireResult r = stream.acquire(0);
      if (r.status == AcquireStatus::corrupt) ++corrupt;
      if (r.status != AcquireStatus::ok) continue;
      ++frames;
      stream.release(r.frame);
    }
    EXPECT_EQ(counter.count(), 0u) << name;
    EXPECT_GT(frames, 200) << name;
    EXPECT_GT(corrupt, 30) << name;
    EXPECT_EQ(requeuer.count, 300) << name;
  }
}

}  // namespace
}  // namespace epipole::hal

#include <gtest/gtest.h>

#include <memory>
#include <string_view>
#include <vector>

#include "allocation_counter.hpp"
#include "epipole/hal/libcamera_camera.hpp"
#include "epipole/hal/recovery.hpp"
#include "epipole/hal/sim.hpp"
#include "epipole/hal/stereo_pairing.hpp"

namespace epipole::hal {
namespace {

TEST(HalAllocations, AcquireReleaseAndPairingNeverAllocate) {
  std::vector<GrayImage> left, right;
  left.emplace_back(64, 32);
  right.emplace_back(64, 32);
  SimBoard board(30.0, std::move(left), std::move(right));
  CameraConfig config;
  config.width = 64;
  config.height = 32;
  config.trigger = TriggerMode::external;
  config.device = "left";
  SimCamera l(config, board.left, board.clock, board.timing);
  config.device = "right";
  SimCamera r(config, board.right, board.clock, board.timing);
  board.trigger.connect(l);
  board.trigger.connect(r);
  r.inject({.kind = SimFaultKind::drop, .sequence = 20, .count = 2});
  r.inject({.kind = SimFaultKind::corrupt_pixels, .sequence = 30});
  r.inject({.kind = SimFaultKind::damaged, .sequence = 35});
  l.inject({.kind = SimFaultKind::disconnect, .sequence = 40});
  for (SimCamera* camera : {&l, &r}) {
    camera->inject({.kind = SimFaultKind::wrong_sequence, .sequence = 50, .value = 51});
  }
  TriggerRecord record;
  board.trigger.record_to(&record);
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
  int pairs = 0;
  test::AllocationCounter counter;
  for (int i = 0; i < 200; ++i) {
    const PairResult p = grabber.next(100'000'000);
    if (p.status != PairStatus::ok) continue;
    ++pairs;
    grabber.release(p.pair);
  }
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_GT(pairs, 100);
  EXPECT_EQ(rl.counters().reopens, 1u);
  EXPECT_EQ(grabber.pairer().counters().corrupt_right, 1u);
  EXPECT_EQ(grabber.pairer().counters().off_trigger_left, 1u);
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

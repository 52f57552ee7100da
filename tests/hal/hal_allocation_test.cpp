#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "allocation_counter.hpp"
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

}  // namespace
}  // namespace epipole::hal

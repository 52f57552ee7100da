#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <iterator>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"
#include "epipole/hal/recovery.hpp"
#include "epipole/hal/registry.hpp"
#include "epipole/hal/stereo_pairing.hpp"
#include "libcamera/libcamera_camera.hpp"
#include "sim/sim.hpp"

namespace epipole::hal {
namespace {

constexpr int kW = 32;
constexpr int kH = 16;
constexpr Nanoseconds kMs = 1'000'000;
constexpr Nanoseconds kPeriod = 20 * kMs;  // 50 Hz
constexpr Nanoseconds kSecond = 1000 * kMs;

std::vector<GrayImage> images() {
  std::vector<GrayImage> v;
  GrayImage image(kW, kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) image(x, y) = static_cast<std::uint8_t>(x * 5 + y);
  }
  v.push_back(std::move(image));
  return v;
}

CameraConfig config_for(const std::string& device) {
  CameraConfig c;
  c.device = device;
  c.width = kW;
  c.height = kH;
  c.trigger = TriggerMode::external;
  c.buffer_count = 8;
  return c;
}

SimCameraTiming timing() {
  SimCameraTiming t;
  t.exposure_delay = 4 * kMs;
  t.jitter = 300'000;  // +-0.3 ms per camera: |dt| <= 0.6 ms for one trigger
  t.readout = 2 * kMs;
  return t;
}

// A board with two cameras from the registry, as the firmware builds it, and the record of its
// trigger's edges (a bounce is an edge less than a quarter period after the one before, as the
// firmware sets it).
struct Rig {
  Rig()
      : board(50.0, images(), images(), timing()),
        left_camera(BackendRegistry::builtin().create_camera("sim", config_for("left"),
                                                             {&board.clock, &board})),
        right_camera(BackendRegistry::builtin().create_camera("sim", config_for("right"),
                                                              {&board.clock, &board})),
        left(dynamic_cast<SimCamera&>(*left_camera)),
        right(dynamic_cast<SimCamera&>(*right_camera)) {
    record.set_min_gap(kPeriod / 4);
    board.trigger.record_edges_to(&record);
    board.trigger.start();
    left.start();
    right.start();
  }
  TriggerRecord record;
  SimBoard board;
  std::unique_ptr<CameraSource> left_camera, right_camera;
  SimCamera& left;
  SimCamera& right;
};

// The edge delay learned from the first pairs.
PairingConfig pairing() {
  return {.tolerance = kMs, .trigger_period = kPeriod, .edge_tolerance = kMs};
}

// The edge delay given, as a board file gives it.
PairingConfig pairing_with_delay() {
  PairingConfig c = pairing();
  c.edge_delay = timing().exposure_delay;  // the sim stamps frames at edge + exposure delay
  return c;
}

struct Tally {
  std::uint64_t pairs = 0;
  std::uint64_t lost = 0;
  std::uint64_t renumbered = 0;  // pairs whose number is not their edge's in the schedule
};

// Runs the grabber over `triggers` trigger periods and checks every pair: same trigger (ground
// truth from the cameras), |dt| within the tolerance, and, with a trigger record, the pair
// carries its own trigger's edge (the time it fired, whatever the counts say) and that edge's
// number on both frames.
Tally run(Rig& rig, CameraSource& left, CameraSource& right, StereoGrabber& grabber, int triggers) {
  Tally tally;
  const Nanoseconds end = rig.board.clock.now() + triggers * kPeriod;
  while (rig.board.clock.now() < end) {
    const PairResult r = grabber.next(5 * kPeriod);
    if (r.status == PairStatus::device_lost) {
      ++tally.lost;
      continue;
    }
    if (r.status != PairStatus::ok) continue;
    const StereoPair& p = r.pair;
    const std::uint32_t trigger = rig.left.true_sequence(p.left);
    EXPECT_EQ(trigger, rig.right.true_sequence(p.right))
        << "frames of two different triggers were paired";
    EXPECT_EQ(p.edge.has_value(), grabber.pairer().trigger() != nullptr);
    if (p.edge) {
      EXPECT_EQ(p.edge->timestamp, rig.board.trigger.edge_time(trigger))
          << "pair of trigger " << trigger << " carries another edge";
      EXPECT_EQ(p.left.sequence, p.edge->sequence);
      EXPECT_EQ(p.right.sequence, p.edge->sequence);
      if (p.edge->sequence != trigger) ++tally.renumbered;
    }
    const Nanoseconds dt = p.left.timestamp - p.right.timestamp;
    EXPECT_LE(dt < 0 ? -dt : dt, grabber.pairer().config().tolerance);
    ++tally.pairs;
    grabber.release(p);
  }
  (void)left;
  (void)right;
  return tally;
}

void expect_counters_add_up(const StereoPairer& pairer) {
  const PairingCounters& c = pairer.counters();
  EXPECT_EQ(c.left().pushed, c.pairs + c.left().unpaired + c.left().mismatched +
                                 c.left().out_of_order + c.left().off_trigger +
                                 pairer.waiting(Side::left));
  EXPECT_EQ(c.right().pushed, c.pairs + c.right().unpaired + c.right().mismatched +
                                  c.right().out_of_order + c.right().off_trigger +
                                  pairer.waiting(Side::right));
}

TEST(StereoPairing, CleanRunPairsEveryTrigger) {
  Rig rig;
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing(), &rig.record);
  const Tally t = run(rig, rig.left, rig.right, grabber, 500);
  EXPECT_GE(t.pairs, 499u);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.left().unpaired + c.right().unpaired + c.left().mismatched + c.left().out_of_order,
            0u);
  expect_counters_add_up(grabber.pairer());
}

TEST(StereoPairing, DropsOnEitherSideAreCountedNotMispaired) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::drop, .sequence = 10, .count = 3});
  rig.right.inject({.kind = SimFaultKind::drop, .sequence = 20, .count = 1});
  rig.right.inject({.kind = SimFaultKind::drop, .sequence = 30, .count = 5});
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing(), &rig.record);
  const Tally t = run(rig, rig.left, rig.right, grabber, 100);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.right().unpaired, 3u);  // right's 10, 11, 12
  EXPECT_EQ(c.left().unpaired, 6u);   // left's 20, 30..34
  EXPECT_GE(t.pairs, 100u - 9u - 1u);
  expect_counters_add_up(grabber.pairer());
}

// The cameras' numbers are never trusted: garbled on one side or on both the same way, every
// pair still carries its own trigger's edge and number.
TEST(StereoPairing, GarbledSequencesChangeNothing) {
  for (const bool delay_given : {false, true}) {
    Rig rig;
    rig.left.inject({.kind = SimFaultKind::wrong_sequence, .sequence = 10, .value = 11});
    rig.right.inject({.kind = SimFaultKind::wrong_sequence, .sequence = 21, .value = 20});
    for (SimCamera* camera : {&rig.left, &rig.right}) {
      camera->inject({.kind = SimFaultKind::wrong_sequence, .sequence = 30, .value = 32});
    }
    StereoGrabber grabber(rig.left, rig.right, rig.board.clock,
                          delay_given ? pairing_with_delay() : pairing(), &rig.record);
    const Tally t = run(rig, rig.left, rig.right, grabber, 80);
    const PairingCounters& c = grabber.pairer().counters();
    EXPECT_GE(t.pairs, 79u);
    EXPECT_EQ(t.renumbered, 0u);
    for (const PairingSideCounters& side : c.sides) {
      EXPECT_EQ(side.unpaired + side.mismatched + side.out_of_order + side.off_trigger, 0u);
    }
    expect_counters_add_up(grabber.pairer());
  }
}

TEST(StereoPairing, RandomFaultsAndGarblesNeverCostAPairItsEdge) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rig rig;
    // The same seed on both cameras: the same triggers are dropped, delayed and garbled
    // (to s - 1 or s + 1) on both sides; the timestamp jitter stays independent.
    const SimFaultRates rates{.drop = 0.03,
                              .wrong_sequence = 0.05,
                              .delay = 0.03,
                              .max_delay = 2 * kPeriod,
                              .seed = seed};
    rig.left.set_fault_rates(rates);
    rig.right.set_fault_rates(rates);
    StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing(), &rig.record);
    const Tally t = run(rig, rig.left, rig.right, grabber, 3000);
    EXPECT_GT(t.pairs, 2800u) << seed;
    EXPECT_EQ(t.renumbered, 0u) << seed;
    expect_counters_add_up(grabber.pairer());
  }
}

// The simulated trigger's glitches, through the grabber: a bounce 10 us after an edge, an extra
// edge half a period after one, an edge the record missed, and a master that woke 3 ms late,
// with the edge delay given and learned. Every later pair carries its own edge's time (checked
// by run() against the schedule) and pairs keep coming.
TEST(StereoPairing, TriggerGlitchesCostAtMostTheirOwnPair) {
  for (const bool delay_given : {true, false}) {
    SCOPED_TRACE(delay_given ? "delay given" : "delay learned");
    Rig rig;
    rig.board.trigger.inject({SimTriggerGlitchKind::extra_edge, 30, 10'000});
    rig.board.trigger.inject({SimTriggerGlitchKind::extra_edge, 40, kPeriod / 2});
    rig.board.trigger.inject({SimTriggerGlitchKind::unrecorded, 50, 0});
    rig.board.trigger.inject({SimTriggerGlitchKind::late, 60, 3 * kMs});
    StereoGrabber grabber(rig.left, rig.right, rig.board.clock,
                          delay_given ? pairing_with_delay() : pairing(), &rig.record);
    const Tally t = run(rig, rig.left, rig.right, grabber, 100);
    Rig clean;
    StereoGrabber clean_grabber(clean.left, clean.right, clean.board.clock, pairing(),
                                &clean.record);
    const Tally clean_run = run(clean, clean.left, clean.right, clean_grabber, 100);
    EXPECT_EQ(t.pairs, clean_run.pairs - 1) << "every trigger but the one whose edge was missed";
    // Numbers: the bounce took none, the extra edge one (after trigger 40), the missed edge (50)
    // none: triggers 41..49 carry the schedule's number + 1, and from 51 on the same again.
    EXPECT_EQ(t.renumbered, 9u);
    EXPECT_EQ(rig.record.bounces(), 1u);
    const PairingCounters& c = grabber.pairer().counters();
    EXPECT_EQ(c.left().off_trigger, 1u);
    EXPECT_EQ(c.right().off_trigger, 1u);
    EXPECT_EQ(c.left().unpaired + c.right().unpaired + c.left().out_of_order, 0u);
    expect_counters_add_up(grabber.pairer());
  }
}

TEST(StereoPairing, CleanRunLearnsTheEdgeDelay) {
  Rig rig;
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing(), &rig.record);
  const Tally t = run(rig, rig.left, rig.right, grabber, 500);
  EXPECT_GE(t.pairs, 499u);
  const StereoPairer& pairer = grabber.pairer();
  EXPECT_EQ(pairer.counters().delay_learned, 1u);
  ASSERT_TRUE(pairer.edge_delay().has_value());
  // The sim stamps frames 4 ms after their edge, +-0.3 ms.
  EXPECT_NEAR(static_cast<double>(*pairer.edge_delay()), 4e6, 0.3e6);
  EXPECT_EQ(pairer.counters().left().off_trigger, 0u);
  // A trigger edge the record never saw drops the pair: it cannot pass by default.
  TriggerRecord empty;
  StereoGrabber blind(rig.left, rig.right, rig.board.clock, pairing_with_delay(), &empty);
  const Tally none = run(rig, rig.left, rig.right, blind, 20);
  EXPECT_EQ(none.pairs, 0u);
  EXPECT_GE(blind.pairer().counters().left().off_trigger, 18u);
  expect_counters_add_up(blind.pairer());
}

TEST(StereoPairing, EdgeToleranceMustBeBelowHalfThePeriod) {
  Rig rig;
  TriggerRecord record;
  PairingConfig c = pairing_with_delay();
  c.edge_tolerance = 10 * kMs;
  try {
    StereoPairer pairer(rig.left, rig.right, c, &record);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("edge tolerance 10000000 ns"), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(StereoPairer(rig.left, rig.right, c)) << "no record: the edges are not used";
  c = pairing();
  c.trigger_period = 0;
  EXPECT_THROW(StereoPairer(rig.left, rig.right, c, &record), Error)
      << "no delay to learn it within one period";
}

TEST(TriggerRecord, FindsTheNearestEdgeOnlyOnTheFramesClock) {
  TriggerRecord record;
  record.add({0, 1000, ClockId::virtual_clock});
  record.add({1, 1000 + kPeriod, ClockId::monotonic});
  const auto near_first = record.find_near(1000 + 10, 100, ClockId::virtual_clock);
  ASSERT_TRUE(near_first.has_value());
  EXPECT_EQ(near_first->sequence, 0u);
  EXPECT_FALSE(record.find_near(1000 + 10, 100, ClockId::monotonic).has_value())
      << "the edge at that time is on another clock";
  EXPECT_FALSE(record.find_near(1000 + kPeriod, 100, ClockId::virtual_clock).has_value());
  EXPECT_EQ(record.find_near(1000 + kPeriod - 50, 100, ClockId::monotonic)->sequence, 1u);
  EXPECT_FALSE(record.find_near(1000 + kPeriod, 100, ClockId::other).has_value());
}

TEST(TriggerRecord, HoldsTheLastEdges) {
  TriggerRecord record;
  EXPECT_FALSE(record.find(0).has_value());
  EXPECT_FALSE(record.newest(ClockId::monotonic).has_value());
  for (std::uint32_t s = 0; s < 100; ++s) record.add({s, 1000 + s * kPeriod});
  ASSERT_TRUE(record.find(99).has_value());
  EXPECT_EQ(record.find(99)->timestamp, 1000 + 99 * kPeriod);
  EXPECT_EQ(record.find(36)->sequence, 36u);
  EXPECT_FALSE(record.find(35).has_value()) << "overwritten by 99";
  EXPECT_FALSE(record.find(100).has_value());
  EXPECT_EQ(record.added(), 100u);
  EXPECT_EQ(record.newest(ClockId::monotonic), 1000 + 99 * kPeriod);
  EXPECT_EQ(record.latest_at(1000 + 50 * kPeriod - 1, ClockId::monotonic)->sequence, 49u);
  EXPECT_EQ(record.latest_at(1000 + 50 * kPeriod, ClockId::monotonic)->sequence, 50u);
  EXPECT_FALSE(record.latest_at(1000 + 50 * kPeriod, ClockId::other).has_value());
}

// The record numbers the edges itself: a master that skipped slots (its numbers 0, 1, 5, 6) or a
// slave that counted a bounce leaves no gap and no extra number; a bounce is counted.
TEST(TriggerRecord, NumbersEdgesInOrderAndIgnoresBounces) {
  TriggerRecord record;
  record.set_min_gap(kPeriod / 4);
  EXPECT_TRUE(record.add({0, 1000}));
  EXPECT_TRUE(record.add({1, 1000 + kPeriod}));
  EXPECT_FALSE(record.add({2, 1000 + kPeriod + 10'000})) << "10 us after the edge before";
  EXPECT_TRUE(record.add({5, 1000 + 3 * kPeriod}));
  EXPECT_TRUE(record.add({6, 1000 + 3 * kPeriod + kPeriod / 4})) << "a quarter period is no bounce";
  EXPECT_EQ(record.added(), 4u);
  EXPECT_EQ(record.bounces(), 1u);
  EXPECT_EQ(record.find(2)->timestamp, 1000 + 3 * kPeriod);
  EXPECT_EQ(record.find(3)->timestamp, 1000 + 3 * kPeriod + kPeriod / 4);
  EXPECT_FALSE(record.find(4).has_value());
}

TEST(StereoPairing, CorruptFramesAreCountedAndTheWaitGoesOn) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::damaged, .sequence = 10});
  rig.right.inject({.kind = SimFaultKind::damaged, .sequence = 20});
  rig.right.inject({.kind = SimFaultKind::damaged, .sequence = 21});
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing(), &rig.record);
  const Tally t = run(rig, rig.left, rig.right, grabber, 50);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.left().corrupt, 1u);
  EXPECT_EQ(c.right().corrupt, 2u);
  EXPECT_EQ(c.right().unpaired, 1u);  // right's 10
  EXPECT_EQ(c.left().unpaired, 2u);   // left's 20 and 21
  EXPECT_GE(t.pairs, 50u - 3u - 1u);
  expect_counters_add_up(grabber.pairer());
}

TEST(Recovery, CorruptFramesAreCountedApartAndNeverReopen) {
  Rig rig;
  for (std::uint32_t s = 5; s < 10; ++s) {
    rig.left.inject({.kind = SimFaultKind::damaged, .sequence = s});
  }
  RecoveryConfig config;
  config.timeouts_before_reopen = 3;
  RecoveringCamera left(rig.left, rig.board.clock, config);
  int frames = 0;
  int corrupt = 0;
  while (rig.board.clock.now() < 30 * kPeriod) {
    const AcquireResult r = left.acquire(2 * kPeriod);
    if (r.status == AcquireStatus::corrupt) {
      EXPECT_FALSE(r.frame.valid());
      ++corrupt;
    }
    if (r.status == AcquireStatus::ok) {
      ++frames;
      left.release(r.frame);
    }
  }
  EXPECT_EQ(corrupt, 5);
  EXPECT_EQ(left.counters().corrupt, 5u);
  EXPECT_EQ(left.counters().timeouts, 0u);
  EXPECT_EQ(left.counters().losses, 0u);
  EXPECT_EQ(left.counters().reopen_attempts, 0u);
  EXPECT_GE(frames, 24);
}

// A loss found while reopening is deferred (frames lent before it are still being read) is
// reported at once and often, without a reopen or a wait; the first acquire after the deferral
// reopens the device, and frames flow again.
TEST(Recovery, ADeferredLossIsReopenedOnlyOnceAllowed) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::disconnect, .sequence = 5, .value = 0});
  RecoveringCamera left(rig.left, rig.board.clock, {});
  left.defer_reopen(true);
  AcquireResult lent{};
  int frames = 0;
  for (;;) {
    const AcquireResult r = left.acquire(2 * kPeriod);
    if (r.status != AcquireStatus::ok) {
      ASSERT_EQ(r.status, AcquireStatus::device_lost);
      break;
    }
    ++frames;
    if (lent.frame.valid()) left.release(lent.frame);
    lent = r;  // the last frame stays lent across the loss
  }
  EXPECT_EQ(frames, 5);
  EXPECT_TRUE(left.recovering());
  EXPECT_EQ(left.counters().losses, 1u);
  EXPECT_EQ(left.counters().reopen_attempts, 0u);
  const Nanoseconds before = rig.board.clock.now();
  EXPECT_EQ(left.acquire(2 * kPeriod).status, AcquireStatus::device_lost);
  EXPECT_EQ(rig.board.clock.now(), before) << "a deferred loss does not wait";
  EXPECT_EQ(left.counters().reopen_attempts, 0u);

  left.release(lent.frame);
  left.defer_reopen(false);
  AcquireResult back = left.acquire(2 * kPeriod);
  EXPECT_EQ(left.counters().reopen_attempts, 1u);
  EXPECT_EQ(left.counters().reopens, 1u);
  EXPECT_TRUE(left.recovering()) << "reopened, but no frame yet";
  for (int i = 0; i < 3 && back.status == AcquireStatus::timeout; ++i) {
    back = left.acquire(2 * kPeriod);  // the stream starts again at the next trigger
  }
  ASSERT_EQ(back.status, AcquireStatus::ok);
  EXPECT_FALSE(left.recovering()) << "frames flow again";
  left.release(back.frame);
}

TEST(StereoPairing, DelaysAndSkewedTimestamps) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::delay, .sequence = 5, .duration = 3 * kPeriod});
  rig.right.inject({.kind = SimFaultKind::delay, .sequence = 15, .duration = 45 * kMs});
  rig.right.inject({.kind = SimFaultKind::skew, .sequence = 25, .duration = 5 * kMs});
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing(), &rig.record);
  const Tally t = run(rig, rig.left, rig.right, grabber, 60);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.left().unpaired + c.right().unpaired, 2u) << "trigger 25's times differ by 5 ms";
  EXPECT_GE(t.pairs, 55u);
  expect_counters_add_up(grabber.pairer());
}

TEST(StereoPairing, ToleranceMustBeBelowHalfThePeriod) {
  Rig rig;
  try {
    StereoPairer pairer(rig.left, rig.right, {.tolerance = 10 * kMs, .trigger_period = kPeriod});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("half the trigger period"), std::string::npos);
  }
}

TEST(StereoPairing, RandomFaultsOverManyFrames) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Rig rig;
    rig.left.set_fault_rates({.drop = 0.05,
                              .corrupt_pixels = 0.02,
                              .wrong_sequence = 0.05,
                              .delay = 0.05,
                              .max_delay = 2 * kPeriod,
                              .seed = seed});
    rig.right.set_fault_rates({.drop = 0.05,
                               .corrupt_pixels = 0.02,
                               .wrong_sequence = 0.05,
                               .delay = 0.05,
                               .max_delay = 2 * kPeriod,
                               .seed = seed * 1000 + 7});
    StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing(), &rig.record);
    const Tally t = run(rig, rig.left, rig.right, grabber, 3000);
    const PairingCounters& c = grabber.pairer().counters();
    EXPECT_GT(t.pairs, 2000u) << seed;
    EXPECT_GT(c.left().unpaired + c.right().unpaired, 100u) << seed;
    EXPECT_EQ(t.renumbered, 0u) << seed;
    expect_counters_add_up(grabber.pairer());
  }
}

TEST(StereoPairing, DisconnectAndReconnectWithRecovery) {
  Rig rig;
  rig.right.inject({.kind = SimFaultKind::disconnect, .sequence = 50, .value = 3});
  RecoveryConfig config;
  config.backoff = {.initial = 10 * kMs, .max = 200 * kMs};
  RecoveringCamera right(rig.right, rig.board.clock, config);
  RecoveringCamera left(rig.left, rig.board.clock, config);
  StereoGrabber grabber(left, right, rig.board.clock, pairing(), &rig.record);
  Nanoseconds lost_at = 0;
  Nanoseconds back_at = 0;
  std::uint64_t pairs = 0;
  while (rig.board.clock.now() < 300 * kPeriod) {
    const PairResult r = grabber.next(5 * kPeriod);
    if (r.status == PairStatus::device_lost) {
      EXPECT_EQ(r.lost_side, Side::right);
      if (lost_at == 0) lost_at = rig.board.clock.now();
      continue;
    }
    if (r.status != PairStatus::ok) continue;
    if (lost_at != 0 && back_at == 0) back_at = rig.board.clock.now();
    EXPECT_EQ(rig.left.true_sequence(r.pair.left), rig.right.true_sequence(r.pair.right));
    EXPECT_EQ(r.pair.left.sequence, rig.left.true_sequence(r.pair.left));
    EXPECT_EQ(r.pair.right.sequence, r.pair.left.sequence);
    ++pairs;
    grabber.release(r.pair);
  }
  ASSERT_NE(lost_at, 0);
  ASSERT_NE(back_at, 0);
  // Attempts: at once (fails), +10 ms (fails), +20 ms (fails), +40 ms succeeds.
  const RecoveryCounters& c = right.counters();
  EXPECT_EQ(c.losses, 1u);
  EXPECT_EQ(c.reopen_attempts, 4u);
  EXPECT_EQ(c.reopen_failures, 3u);
  EXPECT_EQ(c.reopens, 1u);
  EXPECT_GE(back_at - lost_at, 70 * kMs);
  EXPECT_LE(back_at - lost_at, 70 * kMs + 3 * kPeriod);
  EXPECT_GT(pairs, 280u);
  EXPECT_EQ(left.counters().losses, 0u);
  EXPECT_NE(right.last_error().find("sim:right"), std::string::npos);
  expect_counters_add_up(grabber.pairer());
}

// Both cameras go, one after the other (a driver unloaded under them): while the left one is
// gone the right one is still read, so its own loss is found and it is reopened without waiting
// for the left one; once both are back, frames of one trigger pair again.
TEST(StereoPairing, TheOtherCameraIsStillReadWhileOneIsGone) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::disconnect, .sequence = 50, .value = 8});
  rig.right.inject({.kind = SimFaultKind::disconnect, .sequence = 55, .value = 1});
  RecoveryConfig config;
  config.backoff = {.initial = 10 * kMs, .max = 200 * kMs};
  RecoveringCamera left(rig.left, rig.board.clock, config);
  RecoveringCamera right(rig.right, rig.board.clock, config);
  StereoGrabber grabber(left, right, rig.board.clock, pairing(), &rig.record);
  bool right_back_while_left_gone = false;
  std::uint64_t pairs_after = 0;
  while (rig.board.clock.now() < 300 * kPeriod) {
    const PairResult r = grabber.next(5 * kPeriod);
    if (left.recovering() && right.counters().reopens == 1 && !right.recovering()) {
      right_back_while_left_gone = true;
    }
    if (r.status != PairStatus::ok) continue;
    EXPECT_EQ(rig.left.true_sequence(r.pair.left), rig.right.true_sequence(r.pair.right));
    if (right.counters().reopens == 1 && left.counters().reopens == 1) ++pairs_after;
    grabber.release(r.pair);
  }
  EXPECT_EQ(left.counters().losses, 1u);
  EXPECT_EQ(right.counters().losses, 1u);
  EXPECT_EQ(right.counters().reopen_failures, 1u);
  EXPECT_EQ(left.counters().reopen_failures, 8u);
  EXPECT_TRUE(right_back_while_left_gone);
  EXPECT_GT(pairs_after, 150u);
  expect_counters_add_up(grabber.pairer());
}

// Both cameras go at once and come back at once (a driver reloaded). Paired, the one reopened
// first brings the other back with it, though the other's own back-off would have waited for
// far longer: free-running cameras start streaming back to back, as at start-up, and their
// frames pair. Unpaired, each waits for its own back-off.
TEST(Recovery, APairedCameraBringsItsLostPartnerBackWithIt) {
  for (const bool paired : {true, false}) {
    SCOPED_TRACE(paired ? "paired" : "apart");
    Rig rig;
    rig.left.inject({.kind = SimFaultKind::disconnect, .sequence = 50, .value = 2});
    rig.right.inject({.kind = SimFaultKind::disconnect, .sequence = 50, .value = 1});
    RecoveringCamera left(rig.left, rig.board.clock,
                          {.backoff = {.initial = 10 * kMs, .max = 40 * kMs}});
    RecoveringCamera right(rig.right, rig.board.clock,
                           {.backoff = {.initial = 50 * kPeriod, .max = 50 * kPeriod}});
    if (paired) left.pair_with(right);
    StereoGrabber grabber(left, right, rig.board.clock, pairing(), &rig.record);
    Nanoseconds left_back = 0;
    Nanoseconds right_back = 0;
    std::uint64_t pairs_after = 0;
    while (rig.board.clock.now() < 200 * kPeriod) {
      const PairResult r = grabber.next(5 * kPeriod);
      if (left_back == 0 && left.counters().reopens == 1) left_back = rig.board.clock.now();
      if (right_back == 0 && right.counters().reopens == 1) right_back = rig.board.clock.now();
      if (r.status != PairStatus::ok) continue;
      EXPECT_EQ(rig.left.true_sequence(r.pair.left), rig.right.true_sequence(r.pair.right));
      if (left_back != 0 && right_back != 0) ++pairs_after;
      grabber.release(r.pair);
    }
    ASSERT_NE(left_back, 0);
    ASSERT_NE(right_back, 0);
    EXPECT_EQ(left.counters().losses, 1u);
    EXPECT_EQ(right.counters().losses, 1u);
    if (paired) {
      EXPECT_EQ(right_back, left_back);
      EXPECT_GT(pairs_after, 130u);
    } else {
      EXPECT_GE(right_back - left_back, 40 * kPeriod);
      EXPECT_LT(pairs_after, 110u);
    }
    expect_counters_add_up(grabber.pairer());
  }
}

TEST(Recovery, ACameraCannotBeItsOwnPartner) {
  Rig rig;
  RecoveringCamera left(rig.left, rig.board.clock);
  EXPECT_THROW(left.pair_with(left), Error);
}

// The camera stalls while the trigger fires on: three timeouts in a row are its fault, whether
// it follows the trigger's record or not.
TEST(Recovery, TimeoutsInARowReopenTheCamera) {
  for (const bool follows : {false, true}) {
    SCOPED_TRACE(follows ? "following the trigger" : "no trigger record");
    Rig rig;
    rig.left.inject({.kind = SimFaultKind::stall, .sequence = 5, .duration = 40 * kPeriod});
    RecoveryConfig config;
    config.timeouts_before_reopen = 3;
    RecoveringCamera left(rig.left, rig.board.clock, config);
    if (follows) left.follow_trigger(&rig.record);
    int frames = 0;
    while (rig.board.clock.now() < 100 * kPeriod) {
      const AcquireResult r = left.acquire(2 * kPeriod);
      if (r.status == AcquireStatus::ok) {
        ++frames;
        left.release(r.frame);
      }
    }
    EXPECT_EQ(left.counters().timeouts, 3u);
    EXPECT_EQ(left.counters().losses, 1u);
    EXPECT_EQ(left.counters().reopens, 1u) << "the reopen ended the stall: frames flow again";
    EXPECT_EQ(left.counters().trigger_waits, 0u) << "the trigger fired all along";
    EXPECT_FALSE(left.recovering());
    EXPECT_GT(frames, 80);
  }
}

// A trigger that stops for 10 s (an autopilot that disarmed): an externally triggered camera
// that follows the trigger's record waits for it, and reopens nothing; one that does not
// follow it takes the silence for a fault and reopens again and again.
TEST(Recovery, AStoppedTriggerReopensNothing) {
  for (const bool follows : {true, false}) {
    Rig rig;
    rig.board.trigger.inject({SimTriggerGlitchKind::pause, 50, 10 * kSecond});
    RecoveryConfig config;
    config.timeouts_before_reopen = 3;
    RecoveringCamera left(rig.left, rig.board.clock, config);
    if (follows) left.follow_trigger(&rig.record);
    int frames_after = 0;
    const Nanoseconds pause_end = 50 * kPeriod + 10 * kSecond;
    while (rig.board.clock.now() < pause_end + 2 * kSecond) {
      const AcquireResult r = left.acquire(200 * kMs);
      if (r.status != AcquireStatus::ok) continue;
      if (r.frame.timestamp > pause_end) ++frames_after;
      left.release(r.frame);
    }
    if (follows) {
      EXPECT_EQ(left.counters().reopens, 0u);
      EXPECT_EQ(left.counters().losses, 0u);
      EXPECT_EQ(left.counters().trigger_waits, 50u) << "10 s of 200 ms waits";
      EXPECT_GT(frames_after, 90) << "frames come again with the edges";
    } else {
      EXPECT_EQ(left.counters().trigger_waits, 0u);
      // Lost after 3 timeouts (0.6 s), reopened at once; then each reopen that brought no frame
      // waits the longer of its back-off (0.1, 0.2, 0.4, ... s) and 3 more timeouts: 7 reopens,
      // and the next is due 3 s after the trigger came back, so no frame in the 2 s after it.
      EXPECT_EQ(left.counters().reopens, 7u);
      EXPECT_EQ(frames_after, 0);
    }
  }
}

// A device that opens but fails every dequeue (EIO) for 10 s: lost once, recovering until frames
// flow again, reopened after 0, 0.1, 0.2, 0.4, 0.8, 1.6, 3.2 and 5 s (the maximum): 8 reopens,
// the last of which brings frames and resets the back-off.
TEST(Recovery, ADeviceThatFailsEveryDequeueIsReopenedLessAndLessOften) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::broken, .sequence = 10, .duration = 10 * kSecond});
  RecoveringCamera left(rig.left, rig.board.clock, {});
  int episodes = 0;  // how often recovering() went from false to true: one journal line each
  bool was_recovering = false;
  int frames_after = 0;
  while (rig.board.clock.now() < 15 * kSecond) {
    const AcquireResult r = left.acquire(2 * kPeriod);
    if (left.recovering() && !was_recovering) ++episodes;
    was_recovering = left.recovering();
    if (r.status != AcquireStatus::ok) continue;
    if (r.frame.timestamp > 10 * kSecond) ++frames_after;
    left.release(r.frame);
  }
  EXPECT_EQ(episodes, 1);
  EXPECT_EQ(left.counters().reopens, 8u);
  EXPECT_EQ(left.counters().losses, 8u);
  EXPECT_FALSE(left.recovering());
  EXPECT_GT(frames_after, 100);
}

TEST(Backoff, DoublesUpToTheMaximum) {
  Backoff b({.initial = 10, .max = 35});
  EXPECT_TRUE(b.due(0));
  b.failed(100);
  EXPECT_EQ(b.next_attempt(), 110);
  EXPECT_FALSE(b.due(109));
  b.failed(110);
  EXPECT_EQ(b.next_attempt(), 130);
  b.failed(130);
  EXPECT_EQ(b.next_attempt(), 165);
  b.failed(165);
  EXPECT_EQ(b.next_attempt(), 200);
  b.succeeded();
  EXPECT_EQ(b.current_delay(), 10);
  EXPECT_THROW(Backoff({.initial = 0, .max = 5}), Error);
}

// A port that hangs up on the third read and cannot be reopened twice.
class FakePort final : public SerialPort {
 public:
  IoResult read(std::span<std::byte>, Nanoseconds) override {
    ++reads;
    return {reads == 3 ? IoStatus::hung_up : IoStatus::timeout, 0};
  }
  IoResult write(std::span<const std::byte> data, Nanoseconds) override {
    return {IoStatus::ok, data.size()};
  }
  bool is_open() const override { return open; }
  void reopen() override {
    if (failures_left > 0) {
      --failures_left;
      throw Error("serial port /dev/fake: cannot open");
    }
    open = true;
  }
  void close() override { open = false; }
  int reads = 0;
  int failures_left = 2;
  bool open = true;
};

// A camera whose device is not there until `present` (a USB camera slower to appear at boot than
// the firmware): start() and reopen() throw DeviceMissing meanwhile, as the V4L2 backend does.
class LateCamera final : public CameraSource {
 public:
  explicit LateCamera(CameraSource& camera) : camera_(camera) {}
  const std::string& name() const override { return camera_.name(); }
  const CameraConfig& config() const override { return camera_.config(); }
  void start() override {
    if (!present) throw DeviceMissing("camera late: not there (yet)");
    camera_.start();
  }
  void stop() override { camera_.stop(); }
  bool streaming() const override { return present && camera_.streaming(); }
  AcquireResult acquire(Nanoseconds timeout) override {
    if (!present) return {AcquireStatus::device_lost, {}};
    return camera_.acquire(timeout);
  }
  void release(const Frame& frame) override { camera_.release(frame); }
  void reopen() override {
    if (!present) throw DeviceMissing("camera late: not there (yet)");
    camera_.reopen();
  }
  void set_exposure(Nanoseconds exposure, double gain) override {
    camera_.set_exposure(exposure, gain);
  }
  bool present = false;

 private:
  CameraSource& camera_;
};

TEST(Recovery, ACameraNotThereAtStartIsWaitedFor) {
  Rig rig;
  rig.left.stop();
  LateCamera late(rig.left);
  RecoveringCamera left(late, rig.board.clock, {.backoff = {.initial = 20 * kMs, .max = 80 * kMs}});
  left.start();  // no exception: the camera is waited for
  EXPECT_TRUE(left.recovering());
  EXPECT_NE(left.last_error().find("not there"), std::string::npos) << left.last_error();
  int lost = 0;
  while (rig.board.clock.now() < 500 * kMs) {
    EXPECT_EQ(left.acquire(kPeriod).status, AcquireStatus::device_lost);
    ++lost;
  }
  const RecoveryCounters before = left.counters();
  EXPECT_EQ(before.losses, 1u);
  EXPECT_EQ(before.reopens, 0u);
  // Tried again with back-off growing to its maximum: 20, 40, 80, 80, ... ms.
  EXPECT_GE(before.reopen_attempts, 5u);
  EXPECT_LE(before.reopen_attempts, 8u);
  EXPECT_EQ(before.reopen_failures, before.reopen_attempts);
  late.present = true;
  int frames = 0;
  while (rig.board.clock.now() < 1500 * kMs) {
    const AcquireResult r = left.acquire(2 * kPeriod);
    if (r.status != AcquireStatus::ok) continue;
    ++frames;
    left.release(r.frame);
  }
  EXPECT_FALSE(left.recovering());
  EXPECT_EQ(left.counters().reopens, 1u);
  EXPECT_GE(frames, 40) << "frames flow once it is there (50 Hz trigger)";
  EXPECT_GT(lost, 0);
}

TEST(Recovery, SerialHangUpReopensWithBackoff) {
  VirtualClock clock;
  FakePort fake;
  RecoveringSerialPort port(fake, clock, {.initial = 10 * kMs, .max = 100 * kMs});
  std::array<std::byte, 8> buffer{};
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::timeout);
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::timeout);
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::hung_up);
  EXPECT_FALSE(fake.open);
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::closed);  // attempt 1 fails
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::closed);  // not due yet
  clock.advance(10 * kMs);
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::closed);  // attempt 2 fails
  clock.advance(10 * kMs);
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::closed);  // due only after 20 ms
  clock.advance(10 * kMs);
  EXPECT_EQ(port.read(buffer, kMs).status, IoStatus::timeout);  // reopened
  const RecoveryCounters& c = port.counters();
  EXPECT_EQ(c.losses, 1u);
  EXPECT_EQ(c.reopen_attempts, 3u);
  EXPECT_EQ(c.reopen_failures, 2u);
  EXPECT_EQ(c.reopens, 1u);
  EXPECT_EQ(c.timeouts, 3u);
}

TEST(Registry, UnknownAndUnavailableBackends) {
  const BackendRegistry& r = BackendRegistry::builtin();
  CameraConfig c = config_for("/dev/video3");
  try {
    r.create_camera("usb", c);
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("/dev/video3"), std::string::npos) << m;
    EXPECT_NE(m.find("'usb'"), std::string::npos) << m;
    EXPECT_NE(m.find("sim"), std::string::npos) << m;
    EXPECT_NE(m.find("v4l2"), std::string::npos) << m;
  }
  try {
    r.create_camera("libcamera", c)->start();
    FAIL();
  } catch (const Error& e) {
    // Built: no such camera (when it is started: it may appear later); not built: it says so.
    EXPECT_NE(std::string(e.what()).find(libcamera_build_version().empty()
                                             ? "not built into this binary"
                                             : "camera /dev/video3: no libcamera camera"),
              std::string::npos)
        << e.what();
  }
  try {
    // Built: a line that is not there (yet) is waited for; not built: it says so.
    TriggerConfig t;
    t.line = "CAM_TRIG";
    const auto line = r.create_trigger("gpiod", t);
    line->start();
    EXPECT_FALSE(line->available());
    EXPECT_NE(line->unavailable_reason().find("no GPIO line"), std::string::npos);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not built into this binary"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(r.create_camera("sim", c), Error) << "no simulated board";
  // A serial device that is not there (yet) is waited for: the port is made closed.
  const auto late_port =
      r.create_serial("termios", {.device = "/dev/nonexistent-tty", .baud = 115200});
  EXPECT_FALSE(late_port->is_open());
  try {
    late_port->reopen();
    FAIL();
  } catch (const DeviceMissing& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/nonexistent-tty: not there"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(r.create_serial("uart", {.device = "/dev/ttyS0", .baud = 9600}), Error);
}

TEST(Registry, TellsWhatEachBackendIs) {
  const BackendRegistry& r = BackendRegistry::builtin();
  EXPECT_EQ(r.camera_backends(), (std::vector<std::string>{"sim", "v4l2", "libcamera"}));
  EXPECT_EQ(r.trigger_backends(), (std::vector<std::string>{"sim", "gpiod"}));
  EXPECT_EQ(r.serial_backends(), (std::vector<std::string>{"termios", "pty"}));
  EXPECT_TRUE(r.camera_traits("sim").simulated);
  EXPECT_FALSE(r.camera_traits("v4l2").simulated);
  EXPECT_TRUE(r.camera_traits("v4l2").needs_device);
  EXPECT_FALSE(r.camera_traits("libcamera").simulated) << "built or not";
  EXPECT_TRUE(r.trigger_traits("sim").simulated);
  EXPECT_FALSE(r.trigger_traits("gpiod").simulated);
  EXPECT_TRUE(r.serial_traits("termios").needs_device);
  EXPECT_TRUE(r.serial_traits("pty").simulated);
  EXPECT_FALSE(r.serial_traits(kNoBackend).simulated) << "no backend has no traits";
  EXPECT_FALSE(r.camera_traits("gige").needs_device);
  // The simulated board knows the cameras the "sim" backend made on it.
  SimBoard board(30.0, images(), images(), timing());
  EXPECT_EQ(board.camera(Side::left), nullptr);
  const auto right = r.create_camera("sim", config_for("right"), {&board.clock, &board});
  EXPECT_EQ(board.camera(Side::right), right.get());
  EXPECT_EQ(board.camera(Side::left), nullptr);
}

TEST(Registry, FreeRunningSimCamerasIgnoreTheBoardsTrigger) {
  SimBoard board(50.0, images(), images());
  const BackendContext context{&board.clock, &board};
  CameraConfig c = config_for("left");
  c.trigger = TriggerMode::free_running;
  c.fps = 25.0;
  auto camera = BackendRegistry::builtin().create_camera("sim", c, context);
  board.trigger.start();
  camera->start();
  Nanoseconds last = -1;
  for (std::uint32_t i = 0; i < 10; ++i) {
    const AcquireResult r = camera->acquire(100 * kMs);
    ASSERT_EQ(r.status, AcquireStatus::ok);
    EXPECT_EQ(r.frame.sequence, i) << "its own frame counter";
    if (last >= 0) {
      EXPECT_EQ(r.frame.timestamp - last, 40 * kMs) << "its own rate, not 50 Hz";
    }
    last = r.frame.timestamp;
    camera->release(r.frame);
  }
}

TEST(TriggerLines, WithRateChecksTheRateAndTheRole) {
  TriggerConfig t{.line = "GPIO17",
                  .chip = {},
                  .role = TriggerRole::master,
                  .rate_hz = 30.0,
                  .pulse_width = 100'000};
  EXPECT_EQ(with_rate(t, 60.0).rate_hz, 60.0);
  EXPECT_EQ(with_rate(t, 60.0).line, "GPIO17");
  EXPECT_EQ(period_of(60.0), 16'666'667);
  const auto message = [](const TriggerConfig& c, double rate) {
    try {
      with_rate(c, rate);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(t, 0.0).find("trigger GPIO17: rate 0 Hz is impossible"), std::string::npos)
      << message(t, 0.0);
  EXPECT_NE(message(t, 1e4).find("rate 10000 Hz"), std::string::npos) << message(t, 1e4);
  EXPECT_NE(message(t, 20000.0).find("GPIO17"), std::string::npos);
  t.pulse_width = 20 * kMs;
  EXPECT_NE(message(t, 60.0).find("trigger GPIO17: pulse width 20000000 ns does not fit"),
            std::string::npos)
      << message(t, 60.0);
  t.role = TriggerRole::slave;
  EXPECT_NE(message(t, 30.0).find("trigger GPIO17: a slave line cannot set a rate (30 Hz"),
            std::string::npos)
      << message(t, 30.0);
}

// A device that forgets its exposure when it is reopened (back to automatic), as a replaced or
// reset camera would.
class ForgetfulCamera final : public CameraSource {
 public:
  explicit ForgetfulCamera(SimCamera& camera) : camera_(camera) {}
  const std::string& name() const override { return camera_.name(); }
  const CameraConfig& config() const override { return camera_.config(); }
  void start() override { camera_.start(); }
  void stop() override { camera_.stop(); }
  bool streaming() const override { return camera_.streaming(); }
  AcquireResult acquire(Nanoseconds timeout) override { return camera_.acquire(timeout); }
  void release(const Frame& frame) override { camera_.release(frame); }
  void reopen() override {
    camera_.reopen();
    camera_.set_exposure(0, 0.0);
  }
  void set_exposure(Nanoseconds exposure, double gain) override {
    camera_.set_exposure(exposure, gain);
  }

 private:
  SimCamera& camera_;
};

TEST(Recovery, SetExposureIsAppliedAgainAfterAReopen) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::disconnect, .sequence = 5});
  ForgetfulCamera forgetful(rig.left);
  RecoveringCamera left(forgetful, rig.board.clock);
  left.set_exposure(4 * kMs, 2.0);
  EXPECT_EQ(rig.left.config().exposure, 4 * kMs);
  EXPECT_EQ(left.config().gain, 2.0);
  EXPECT_THROW(left.set_exposure(-1, 1.0), Error);
  EXPECT_EQ(rig.left.config().exposure, 4 * kMs) << "refused: nothing changed";
  int frames = 0;
  while (rig.board.clock.now() < 20 * kPeriod) {
    const AcquireResult r = left.acquire(2 * kPeriod);
    if (r.status != AcquireStatus::ok) continue;
    ++frames;
    left.release(r.frame);
  }
  EXPECT_EQ(left.counters().reopens, 1u);
  EXPECT_GT(frames, 10);
  EXPECT_EQ(rig.left.config().exposure, 4 * kMs) << "the device forgot; the wrapper set it again";
  EXPECT_EQ(rig.left.config().gain, 2.0);
}

TEST(StereoPairing, ARateChangeIsCheckedAgainstTheTolerances) {
  Rig rig;
  TriggerRecord record;
  StereoPairer pairer(rig.left, rig.right,
                      {.tolerance = kMs, .trigger_period = kPeriod, .edge_tolerance = 2 * kMs},
                      &record);
  pairer.set_trigger_period(5 * kMs);
  EXPECT_EQ(pairer.config().trigger_period, 5 * kMs);
  const auto refusal = [&](Nanoseconds period) {
    try {
      pairer.set_trigger_period(period);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // The edge tolerance (2 ms) is not below half of 4 ms; the tolerance (1 ms) not below 1 ms.
  EXPECT_NE(refusal(4 * kMs).find("edge tolerance 2000000 ns is not below half the trigger "
                                  "period 4000000 ns"),
            std::string::npos)
      << refusal(4 * kMs);
  EXPECT_NE(refusal(2 * kMs).find("timestamp tolerance 1000000 ns is not below half the "
                                  "trigger period 2000000 ns"),
            std::string::npos)
      << refusal(2 * kMs);
  EXPECT_EQ(pairer.config().trigger_period, 5 * kMs) << "a refused period changes nothing";
  pairer.set_trigger_period(0);  // unknown: not checked
}

// --- Pairing by time, for free-running cameras ---

// Frames the test hands to the pairer itself; release() counts what comes back.
class HandCamera final : public CameraSource {
 public:
  explicit HandCamera(std::string name) : name_(std::move(name)) { config_.device = name_; }
  const std::string& name() const override { return name_; }
  const CameraConfig& config() const override { return config_; }
  void start() override {}
  void stop() override {}
  bool streaming() const override { return true; }
  AcquireResult acquire(Nanoseconds) override { return {}; }
  void release(const Frame&) override { ++released; }
  void reopen() override {}
  void set_exposure(Nanoseconds, double) override {}
  int released = 0;

 private:
  std::string name_;
  CameraConfig config_;
};

Frame hand_frame(std::uint32_t sequence, Nanoseconds t, ClockId clock = ClockId::monotonic) {
  Frame f;
  f.sequence = sequence;
  f.timestamp = t;
  f.clock = clock;
  f.buffer = 0;
  return f;
}

TEST(PairingByTime, NearestWithinTheToleranceEachFrameOnce) {
  HandCamera l("left"), r("right");
  StereoPairer pairer(l, r, {.tolerance = 9 * kMs, .trigger_period = 20 * kMs});
  // Two right frames within the tolerance of one left frame: the nearer one pairs, the other is
  // dropped; the pair carries the left frame's number.
  EXPECT_FALSE(pairer.push(Side::right, hand_frame(1000, 95 * kMs)));
  EXPECT_FALSE(pairer.push(Side::right, hand_frame(1001, 99 * kMs)));
  ASSERT_TRUE(pairer.push(Side::left, hand_frame(7, 100 * kMs)));
  StereoPair p = pairer.take();
  EXPECT_EQ(p.left.sequence, 7u);
  EXPECT_EQ(p.right.sequence, 1001u);
  EXPECT_EQ(pairer.counters().right().unpaired, 1u);
  pairer.release(p);
  // Beyond the tolerance: the earlier frame can pair with nothing later, and goes.
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(8, 120 * kMs)));
  EXPECT_FALSE(pairer.push(Side::right, hand_frame(1002, 130 * kMs + 1)));
  EXPECT_EQ(pairer.counters().left().unpaired, 1u);
  ASSERT_TRUE(pairer.push(Side::left, hand_frame(9, 139 * kMs)));
  p = pairer.take();
  EXPECT_EQ(p.left.sequence, 9u);
  EXPECT_EQ(p.right.sequence, 1002u);
  pairer.release(p);
  // Frames on different clocks never pair.
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(10, 160 * kMs)));
  EXPECT_FALSE(pairer.push(Side::right, hand_frame(1003, 160 * kMs, ClockId::other)));
  EXPECT_EQ(pairer.counters().left().mismatched, 1u);
  EXPECT_EQ(pairer.counters().right().mismatched, 1u);
  // A timestamp or a sequence that does not increase on its side is refused.
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(11, 150 * kMs)));
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(10, 200 * kMs)));
  EXPECT_EQ(pairer.counters().left().out_of_order, 2u);
  // The earlier frame's successor is nearer to the later one: the successor pairs.
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(12, 200 * kMs)));
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(13, 207 * kMs)));
  ASSERT_TRUE(pairer.push(Side::right, hand_frame(1004, 208 * kMs)));
  p = pairer.take();
  EXPECT_EQ(p.left.sequence, 13u);
  EXPECT_EQ(p.right.sequence, 1004u);
  pairer.release(p);
  const PairingCounters& c = pairer.counters();
  EXPECT_EQ(c.pairs, 3u);
  EXPECT_EQ(c.left().unpaired, 2u);
  EXPECT_EQ(c.left().pushed, 8u);
  EXPECT_EQ(c.right().pushed, 5u);
  expect_counters_add_up(pairer);
  EXPECT_EQ(l.released, 8) << "every frame went back to its camera once";
  EXPECT_EQ(r.released, 5);
}

// A reopened camera counts from 0 again (V4L2, at every stream start): nothing to renumber, the
// edge at each pair's time numbers it.
TEST(StereoPairing, AReopenedSideNeedsNoNumbers) {
  HandCamera l("left"), r("right");
  TriggerRecord record;
  const Nanoseconds delay = 4 * kMs;
  StereoPairer pairer(l, r, {.tolerance = 2 * kMs, .trigger_period = kPeriod, .edge_delay = delay},
                      &record);
  for (std::uint32_t s = 0; s < 60; ++s) record.add({s, s * kPeriod});
  for (std::uint32_t s = 30; s < 33; ++s) {
    EXPECT_FALSE(pairer.push(Side::left, hand_frame(s + 100, s * kPeriod + delay)));
    ASSERT_TRUE(pairer.push(Side::right, hand_frame(s, s * kPeriod + delay + kMs)));
    const StereoPair p = pairer.take();
    EXPECT_EQ(p.left.sequence, s);
    EXPECT_EQ(p.right.sequence, s);
    ASSERT_TRUE(p.edge.has_value());
    EXPECT_EQ(p.edge->timestamp, s * kPeriod);
    pairer.release(p);
  }
  pairer.reset(Side::right);
  pairer.reset(Side::left);
  // Both restart at 0; right misses edge 40, so left's frame of 40 has no partner.
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(0, 40 * kPeriod + delay)));
  EXPECT_FALSE(pairer.push(Side::right, hand_frame(0, 41 * kPeriod + delay + kMs)));
  EXPECT_EQ(pairer.counters().left().unpaired, 1u);
  ASSERT_TRUE(pairer.push(Side::left, hand_frame(1, 41 * kPeriod + delay)));
  StereoPair p = pairer.take();
  EXPECT_EQ(p.left.sequence, 41u);
  EXPECT_EQ(p.right.sequence, 41u);
  pairer.release(p);
  expect_counters_add_up(pairer);
  EXPECT_EQ(l.released, 5);
  EXPECT_EQ(r.released, 4);
}

// By hand: each glitch of the line costs at most its own pair, with the delay given and learned.
TEST(StereoPairing, EachPairTakesTheEdgeAtItsTime) {
  for (const bool delay_given : {true, false}) {
    SCOPED_TRACE(delay_given ? "delay given" : "delay learned");
    HandCamera l("left"), r("right");
    TriggerRecord record;
    record.set_min_gap(kPeriod / 4);
    const Nanoseconds delay = 3 * kMs;
    PairingConfig c{.tolerance = kMs, .trigger_period = kPeriod};
    if (delay_given) c.edge_delay = delay;
    StereoPairer pairer(l, r, c, &record);
    std::uint32_t camera = 0;  // the cameras' own count, which no glitch of the line touches
    std::vector<Nanoseconds> times;
    std::vector<std::uint32_t> numbers;
    const auto fire = [&](Nanoseconds edge) {
      ++camera;
      EXPECT_FALSE(pairer.push(Side::left, hand_frame(camera, edge + delay)));
      if (!pairer.push(Side::right, hand_frame(camera, edge + delay + 200'000))) return;
      const StereoPair p = pairer.take();
      EXPECT_TRUE(p.edge.has_value());
      if (p.edge) {
        times.push_back(p.edge->timestamp);
        numbers.push_back(p.edge->sequence);
      }
      pairer.release(p);
    };
    Nanoseconds t = 0;
    for (int i = 0; i < 20; ++i, t += kPeriod) {
      record.add({0, t});
      fire(t);
    }
    record.add({0, t});  // a bounce 10 us after an edge: ignored
    record.add({0, t + 10'000});
    fire(t);
    t += kPeriod;
    record.add({0, t});  // an extra edge half a period after one: taken by no pair
    fire(t);
    record.add({0, t + kPeriod / 2});
    t += kPeriod;
    fire(t);  // a missing edge: this pair alone is dropped
    t += kPeriod;
    record.add({0, t + 700'000});  // a master waking late: the cameras fire late too
    fire(t + 700'000);
    t += kPeriod;
    for (int i = 0; i < 5; ++i, t += kPeriod) {
      record.add({0, t});
      fire(t);
    }
    EXPECT_EQ(record.bounces(), 1u);
    ASSERT_EQ(times.size(), 28u) << "every pair but the one of the missing edge";
    for (std::size_t i = 0; i < times.size(); ++i) {
      const Nanoseconds expected =
          static_cast<Nanoseconds>(i < 22 ? i : i + 1) * kPeriod + (i == 22 ? 700'000 : 0);
      EXPECT_EQ(times[i], expected) << i;
    }
    // The numbers are the record's: the extra edge took number 22, so the pairs after it go on
    // from 23.
    EXPECT_EQ(numbers[21], 21u);
    EXPECT_EQ(numbers[22], 23u);
    EXPECT_EQ(numbers[27], 28u);
    EXPECT_EQ(pairer.counters().left().off_trigger, 1u);
    EXPECT_EQ(pairer.counters().right().off_trigger, 1u);
    EXPECT_EQ(pairer.counters().delay_learned, delay_given ? 0u : 1u);
    expect_counters_add_up(pairer);
  }
}

// The edge is recorded by another thread, and may come a little after the frames: the newest
// pair waits for it, and is dropped only once a later frame shows the edge never came.
TEST(StereoPairing, APairWaitsForItsEdgeUntilALaterFrame) {
  HandCamera l("left"), r("right");
  TriggerRecord record;
  StereoPairer pairer(l, r, {.tolerance = kMs, .trigger_period = kPeriod, .edge_delay = kMs},
                      &record);
  record.add({0, 0});
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(0, kMs)));
  ASSERT_TRUE(pairer.push(Side::right, hand_frame(0, kMs)));
  pairer.release(pairer.take());
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(1, kPeriod + kMs)));
  EXPECT_FALSE(pairer.push(Side::right, hand_frame(1, kPeriod + kMs)));
  record.add({0, kPeriod});
  pairer.retry();
  ASSERT_TRUE(pairer.has_pair());
  StereoPair p = pairer.take();
  EXPECT_EQ(p.edge->sequence, 1u);
  pairer.release(p);
  // Edge 2 never comes: the pair waits until the left camera's next frame, then goes.
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(2, 2 * kPeriod + kMs)));
  EXPECT_FALSE(pairer.push(Side::right, hand_frame(2, 2 * kPeriod + kMs)));
  EXPECT_EQ(pairer.counters().left().off_trigger, 0u);
  record.add({0, 3 * kPeriod});
  EXPECT_FALSE(pairer.push(Side::left, hand_frame(3, 3 * kPeriod + kMs)));
  EXPECT_EQ(pairer.counters().left().off_trigger, 1u);
  ASSERT_TRUE(pairer.push(Side::right, hand_frame(3, 3 * kPeriod + kMs)));
  p = pairer.take();
  EXPECT_EQ(p.edge->sequence, 2u);
  pairer.release(p);
}

TEST(PairingByTime, TheToleranceIsChecked) {
  HandCamera l("left"), r("right");
  EXPECT_THROW(StereoPairer(l, r, {.tolerance = 10 * kMs, .trigger_period = 20 * kMs}), Error)
      << "the tolerance must be below half the frame period";
}

// A camera that notes every frame it lends: its trigger (ground truth) and its timestamp.
class LoggingCamera final : public CameraSource {
 public:
  explicit LoggingCamera(SimCamera& camera) : camera_(camera) { log.reserve(8192); }
  const std::string& name() const override { return camera_.name(); }
  const CameraConfig& config() const override { return camera_.config(); }
  void start() override { camera_.start(); }
  void stop() override { camera_.stop(); }
  bool streaming() const override { return camera_.streaming(); }
  AcquireResult acquire(Nanoseconds timeout) override {
    const AcquireResult r = camera_.acquire(timeout);
    if (r.status == AcquireStatus::ok) {
      log.push_back({camera_.true_sequence(r.frame), r.frame.timestamp});
    }
    return r;
  }
  void release(const Frame& frame) override { camera_.release(frame); }
  void reopen() override { camera_.reopen(); }
  void set_exposure(Nanoseconds exposure, double gain) override {
    camera_.set_exposure(exposure, gain);
  }
  struct Seen {
    std::uint32_t truth;
    Nanoseconds timestamp;
  };
  std::vector<Seen> log;

 private:
  SimCamera& camera_;
};

// Two free-running simulated cameras on one clock: each its own trigger, rate, phase, jitter
// and faults.
struct FreeRig {
  FreeRig(double left_fps, double right_fps, Nanoseconds right_phase, std::uint64_t seed)
      : left_sim(free_config("left", left_fps), shared(), clock, free_timing(seed)),
        right_sim(free_config("right", right_fps), shared(), clock, free_timing(seed + 100)),
        left(left_sim),
        right(right_sim) {
    left.start();
    clock.advance(right_phase);
    right.start();
  }
  static CameraConfig free_config(const std::string& device, double fps) {
    CameraConfig c = config_for(device);
    c.trigger = TriggerMode::free_running;
    c.fps = fps;
    return c;
  }
  static SimCameraTiming free_timing(std::uint64_t seed) {
    SimCameraTiming t = timing();  // +-0.3 ms of jitter
    t.seed = seed;
    return t;
  }
  static std::shared_ptr<const std::vector<GrayImage>> shared() {
    return std::make_shared<const std::vector<GrayImage>>(images());
  }
  VirtualClock clock;
  SimCamera left_sim, right_sim;
  LoggingCamera left, right;
};

struct TimeTally {
  std::uint64_t pairs = 0;
  std::uint32_t longest_gap = 0;    // left frames between two pairs, by the left camera's truth
  std::uint32_t truth_differs = 0;  // pairs whose cameras' frame counters disagree
};

// Runs a grabber pairing by time until the left camera has delivered `frames`, and checks each
// pair: |dt| within the tolerance, each frame once (the truths increase on both sides), and
// the two are each other's nearest among every frame the cameras delivered.
TimeTally run_by_time(FreeRig& rig, StereoGrabber& grabber, std::size_t frames) {
  TimeTally t;
  const Nanoseconds tolerance = grabber.pairer().config().tolerance;
  std::vector<std::pair<Nanoseconds, Nanoseconds>> pairs;
  pairs.reserve(frames);
  std::int64_t last_left = -1, last_right = -1;
  while (rig.left.log.size() < frames) {
    const PairResult r = grabber.next(100 * kMs);
    if (r.status != PairStatus::ok) continue;
    const StereoPair& p = r.pair;
    const auto lt = static_cast<std::int64_t>(rig.left_sim.true_sequence(p.left));
    const auto rt = static_cast<std::int64_t>(rig.right_sim.true_sequence(p.right));
    EXPECT_GT(lt, last_left) << "a left frame paired twice";
    EXPECT_GT(rt, last_right) << "a right frame paired twice";
    if (last_left >= 0)
      t.longest_gap = std::max(t.longest_gap, static_cast<std::uint32_t>(lt - last_left));
    t.truth_differs += lt != rt ? 1 : 0;
    last_left = lt;
    last_right = rt;
    const Nanoseconds dt = p.left.timestamp - p.right.timestamp;
    EXPECT_LE(dt < 0 ? -dt : dt, tolerance) << "left frame " << lt;
    EXPECT_EQ(p.left.sequence, static_cast<std::uint32_t>(lt)) << "the pair's number is left's";
    pairs.emplace_back(p.left.timestamp, p.right.timestamp);
    ++t.pairs;
    grabber.release(p);
  }
  // Mutual nearest: no delivered frame of the other side is nearer to either frame of a pair.
  // (Each log is in time order: frames are 20 ms apart, the jitter is 0.3 ms.)
  const auto nearest = [](const std::vector<LoggingCamera::Seen>& log, Nanoseconds at) {
    const auto it =
        std::lower_bound(log.begin(), log.end(), at,
                         [](const auto& s, Nanoseconds time) { return s.timestamp < time; });
    Nanoseconds best = std::numeric_limits<Nanoseconds>::max();
    if (it != log.end()) best = it->timestamp - at;
    if (it != log.begin()) best = std::min(best, at - std::prev(it)->timestamp);
    return best;
  };
  for (const auto& [l, r] : pairs) {
    const Nanoseconds d = l > r ? l - r : r - l;
    EXPECT_EQ(nearest(rig.right.log, l), d) << "a right frame nearer to the left one at " << l;
    EXPECT_EQ(nearest(rig.left.log, r), d) << "a left frame nearer to the right one at " << r;
  }
  return t;
}

PairingConfig by_time() {
  return {.tolerance = 9 * kMs, .trigger_period = kPeriod};
}

TEST(PairingByTime, SameNominalRatePairsEveryFrameBothCamerasDelivered) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    // 50 Hz each, the right camera 3 ms behind, 4 % drops and some delays on either side.
    FreeRig rig(50.0, 50.0, 3 * kMs, seed);
    rig.left_sim.set_fault_rates({.drop = 0.04, .delay = 0.02, .max_delay = kPeriod, .seed = seed});
    rig.right_sim.set_fault_rates(
        {.drop = 0.04, .delay = 0.02, .max_delay = kPeriod, .seed = seed + 50});
    StereoGrabber grabber(rig.left, rig.right, rig.clock, by_time());
    const TimeTally t = run_by_time(rig, grabber, 3000);
    // Frame k of one camera belongs with frame k of the other (3 ms apart): every k both
    // delivered is a pair, and nothing else.
    std::vector<char> right_has(4000, 0);
    for (const auto& s : rig.right.log) right_has[s.truth] = 1;
    std::uint64_t both = 0;
    for (const auto& s : rig.left.log) both += right_has[s.truth];
    EXPECT_EQ(t.truth_differs, 0u) << seed;
    EXPECT_GE(t.pairs + 1, both) << seed;  // the last one may still be waiting
    EXPECT_LE(t.pairs, both) << seed;
    EXPECT_GT(t.pairs, 2600u) << seed;
    expect_counters_add_up(grabber.pairer());
    const PairingCounters& c = grabber.pairer().counters();
    EXPECT_GT(c.left().unpaired + c.right().unpaired, 100u)
        << seed << ": the drops reach the pairer";
    EXPECT_EQ(c.left().mismatched + c.right().mismatched, 0u) << seed;
  }
}

TEST(PairingByTime, SlightlyDifferentRatesDriftButPairsKeepComing) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    // 50 Hz and 50.05 Hz: the right camera gains 19.98 us a frame, so over 3000 frames the
    // phase goes round three times, each time through the band of 1.98 ms where no right frame
    // is within 9 ms of a left one (a period of 19.98 ms - 2 x 9 ms): 99 frames, narrowed or
    // widened by the jitter (+-0.3 ms each, +-1.2 ms on the band) to 39..159. 3 % drops.
    FreeRig rig(50.0, 50.05, 3 * kMs, seed);
    rig.left_sim.set_fault_rates({.drop = 0.03, .seed = seed});
    rig.right_sim.set_fault_rates({.drop = 0.03, .seed = seed + 50});
    StereoGrabber grabber(rig.left, rig.right, rig.clock, by_time());
    const TimeTally t = run_by_time(rig, grabber, 3000);
    EXPECT_GT(t.pairs, 2300u) << seed;
    EXPECT_GT(t.truth_differs, 1000u) << seed << ": the frame counters drifted apart";
    // The longest spell without a pair is that band (and a few drops beside it).
    EXPECT_GE(t.longest_gap, 39u) << seed;
    EXPECT_LE(t.longest_gap, 170u) << seed;
    EXPECT_GE(rig.right.log.back().truth, rig.left.log.back().truth + 1) << "the faster camera";
    expect_counters_add_up(grabber.pairer());
  }
}

TEST(Registry, SimBoardTrigger) {
  SimBoard board(100.0, images(), images());
  const BackendContext context{&board.clock, &board};
  TriggerConfig t;
  t.line = "sim";
  auto trigger = BackendRegistry::builtin().create_trigger("sim", t, context);
  trigger->start();
  EXPECT_EQ(trigger->wait_edge(kMs).edge.sequence, 0u);
  EXPECT_EQ(trigger->wait_edge(20 * kMs).edge.timestamp, 10 * kMs);
  // The handle sets the board's own trigger's rate: from edge 1 on, every 40 ms.
  trigger->set_rate(25.0);
  EXPECT_EQ(board.trigger.config().rate_hz, 25.0);
  EXPECT_EQ(board.trigger.period(), 40 * kMs);
  EXPECT_EQ(trigger->wait_edge(100 * kMs).edge.timestamp, 50 * kMs);
  EXPECT_THROW(trigger->set_rate(0.0), Error);
  CameraConfig bad = config_for("middle");
  EXPECT_THROW(BackendRegistry::builtin().create_camera("sim", bad, context), Error);
}

}  // namespace
}  // namespace epipole::hal

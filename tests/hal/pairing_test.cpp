#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/hal/libcamera_camera.hpp"
#include "epipole/hal/recovery.hpp"
#include "epipole/hal/registry.hpp"
#include "epipole/hal/sim.hpp"
#include "epipole/hal/stereo_pairing.hpp"

namespace epipole::hal {
namespace {

constexpr int kW = 32;
constexpr int kH = 16;
constexpr Nanoseconds kMs = 1'000'000;
constexpr Nanoseconds kPeriod = 20 * kMs;  // 50 Hz

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

// A board with two cameras from the registry, as the firmware builds it.
struct Rig {
  Rig()
      : board(50.0, images(), images(), timing()),
        left_camera(BackendRegistry::builtin().create_camera("sim", config_for("left"),
                                                             {&board.clock, &board})),
        right_camera(BackendRegistry::builtin().create_camera("sim", config_for("right"),
                                                              {&board.clock, &board})),
        left(dynamic_cast<SimCamera&>(*left_camera)),
        right(dynamic_cast<SimCamera&>(*right_camera)) {
    board.trigger.start();
    left.start();
    right.start();
  }
  SimBoard board;
  std::unique_ptr<CameraSource> left_camera, right_camera;
  SimCamera& left;
  SimCamera& right;
};

PairingConfig pairing() {
  return {.tolerance = kMs, .trigger_period = kPeriod};
}

struct Tally {
  std::uint64_t pairs = 0;
  std::uint64_t lost = 0;
  std::uint64_t wrong_numbers = 0;  // pairs of one trigger that carry another trigger's number
};

// Runs the grabber over `triggers` trigger periods and checks every pair: same trigger (ground
// truth from the cameras), equal sequences, |dt| within the tolerance.
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
    EXPECT_EQ(p.left.sequence, p.right.sequence);
    EXPECT_EQ(rig.left.true_sequence(p.left), rig.right.true_sequence(p.right))
        << "frames of two different triggers were paired";
    // The reported sequence may still be wrong when both cameras garbled it the same way: the
    // frames then are of one trigger, but only the trigger record can tell.
    if (p.left.sequence != rig.left.true_sequence(p.left)) ++tally.wrong_numbers;
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
  EXPECT_EQ(c.pushed_left, c.pairs + c.unpaired_left + c.mismatched_left + c.out_of_order_left +
                               c.off_trigger_left + pairer.waiting(Side::left));
  EXPECT_EQ(c.pushed_right, c.pairs + c.unpaired_right + c.mismatched_right + c.out_of_order_right +
                                c.off_trigger_right + pairer.waiting(Side::right));
}

TEST(StereoPairing, CleanRunPairsEveryTrigger) {
  Rig rig;
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing());
  const Tally t = run(rig, rig.left, rig.right, grabber, 500);
  EXPECT_GE(t.pairs, 499u);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.unpaired_left + c.unpaired_right + c.mismatched_left + c.out_of_order_left, 0u);
  expect_counters_add_up(grabber.pairer());
}

TEST(StereoPairing, DropsOnEitherSideAreCountedNotMispaired) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::drop, .sequence = 10, .count = 3});
  rig.right.inject({.kind = SimFaultKind::drop, .sequence = 20, .count = 1});
  rig.right.inject({.kind = SimFaultKind::drop, .sequence = 30, .count = 5});
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing());
  const Tally t = run(rig, rig.left, rig.right, grabber, 100);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.unpaired_right, 3u);  // right's 10, 11, 12
  EXPECT_EQ(c.unpaired_left, 6u);   // left's 20, 30..34
  EXPECT_GE(t.pairs, 100u - 9u - 1u);
  expect_counters_add_up(grabber.pairer());
}

TEST(StereoPairing, GarbledSequencesNeverPairFramesOfTwoTriggers) {
  Rig rig;
  // Left frame of trigger 10 claims to be 11; right of 21 claims 20 (a duplicate of 20).
  rig.left.inject({.kind = SimFaultKind::wrong_sequence, .sequence = 10, .value = 11});
  rig.right.inject({.kind = SimFaultKind::wrong_sequence, .sequence = 21, .value = 20});
  rig.left.inject({.kind = SimFaultKind::wrong_sequence, .sequence = 40, .value = 39});
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing());
  run(rig, rig.left, rig.right, grabber, 80);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_GE(c.mismatched_left + c.out_of_order_left + c.out_of_order_right, 3u);
  expect_counters_add_up(grabber.pairer());
}

PairingConfig pairing_with_edges() {
  PairingConfig c = pairing();
  c.edge_delay = timing().exposure_delay;  // the sim stamps frames at edge + exposure delay
  c.edge_tolerance = kMs;                  // +-0.3 ms of jitter fits
  return c;
}

TEST(StereoPairing, IdenticallyGarbledSequencesAreCaughtByTheTriggerRecord) {
  for (const bool with_record : {false, true}) {
    Rig rig;
    TriggerRecord record;
    rig.board.trigger.record_to(&record);
    // Both cameras report trigger 10 as 11 and trigger 30 as 32: the frames of each pair are of
    // one trigger, so sequences and timestamps agree, but the numbers are wrong.
    for (SimCamera* camera : {&rig.left, &rig.right}) {
      camera->inject({.kind = SimFaultKind::wrong_sequence, .sequence = 10, .value = 11});
      camera->inject({.kind = SimFaultKind::wrong_sequence, .sequence = 30, .value = 32});
    }
    StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing_with_edges(),
                          with_record ? &record : nullptr);
    const Tally t = run(rig, rig.left, rig.right, grabber, 60);
    const PairingCounters& c = grabber.pairer().counters();
    if (!with_record) {
      EXPECT_EQ(t.wrong_numbers, 2u) << "the faults must reach the pairer";
      EXPECT_EQ(c.off_trigger_left + c.off_trigger_right, 0u);
    } else {
      EXPECT_EQ(t.wrong_numbers, 0u);
      EXPECT_EQ(c.off_trigger_left, 2u);
      EXPECT_EQ(c.off_trigger_right, 2u);
      // Triggers 10 and 30 are rejected; the true 11, 31 and 32 are refused as not increasing.
      EXPECT_EQ(c.out_of_order_left, 3u);
      EXPECT_EQ(c.out_of_order_right, 3u);
      EXPECT_GE(t.pairs, 60u - 5u - 1u);
      EXPECT_GE(record.added(), 60u);
    }
    expect_counters_add_up(grabber.pairer());
  }
}

TEST(StereoPairing, RandomIdenticalGarblesNeverPassTheTriggerRecord) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    std::uint64_t wrong_without_record = 0;
    for (const bool with_record : {false, true}) {
      Rig rig;
      TriggerRecord record;
      rig.board.trigger.record_to(&record);
      // The same seed on both cameras: the same triggers are dropped, delayed and garbled
      // (to s - 1 or s + 1) on both sides; the timestamp jitter stays independent.
      const SimFaultRates rates{.drop = 0.03,
                                .wrong_sequence = 0.05,
                                .delay = 0.03,
                                .max_delay = 2 * kPeriod,
                                .seed = seed};
      rig.left.set_fault_rates(rates);
      rig.right.set_fault_rates(rates);
      StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing_with_edges(),
                            with_record ? &record : nullptr);
      const Tally t = run(rig, rig.left, rig.right, grabber, 3000);
      const PairingCounters& c = grabber.pairer().counters();
      EXPECT_GT(t.pairs, 2300u) << seed;
      if (with_record) {
        EXPECT_EQ(t.wrong_numbers, 0u) << seed;
        // The same run (the faults are decided by the seed): each wrongly numbered pair of the
        // run without the record is one rejection here.
        EXPECT_EQ(c.off_trigger_left, wrong_without_record) << seed;
        EXPECT_EQ(c.off_trigger_left, c.off_trigger_right) << seed;
      } else {
        wrong_without_record = t.wrong_numbers;
      }
      expect_counters_add_up(grabber.pairer());
    }
    EXPECT_GT(wrong_without_record, 10u) << "seed " << seed << ": the faults must reach the pairer";
  }
}

TEST(StereoPairing, CleanRunPassesTheTriggerRecord) {
  Rig rig;
  TriggerRecord record;
  rig.board.trigger.record_to(&record);
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing_with_edges(), &record);
  const Tally t = run(rig, rig.left, rig.right, grabber, 500);
  EXPECT_GE(t.pairs, 499u);
  EXPECT_EQ(grabber.pairer().counters().off_trigger_left, 0u);
  // A trigger edge the record never saw rejects the pair: the check cannot pass by default.
  TriggerRecord empty;
  StereoGrabber blind(rig.left, rig.right, rig.board.clock, pairing_with_edges(), &empty);
  const Tally none = run(rig, rig.left, rig.right, blind, 20);
  EXPECT_EQ(none.pairs, 0u);
  EXPECT_GE(blind.pairer().counters().off_trigger_left, 19u);
  expect_counters_add_up(blind.pairer());
}

TEST(StereoPairing, EdgeToleranceMustBeBelowHalfThePeriod) {
  Rig rig;
  TriggerRecord record;
  PairingConfig c = pairing_with_edges();
  c.edge_tolerance = 10 * kMs;
  try {
    StereoPairer pairer(rig.left, rig.right, c, &record);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("edge tolerance 10000000 ns"), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(StereoPairer(rig.left, rig.right, c)) << "no record: the edges are not used";
}

TEST(TriggerRecord, HoldsTheLastEdges) {
  TriggerRecord record;
  EXPECT_FALSE(record.find(0).has_value());
  for (std::uint32_t s = 0; s < 100; ++s) record.add({s, 1000 + s * kPeriod});
  ASSERT_TRUE(record.find(99).has_value());
  EXPECT_EQ(record.find(99)->timestamp, 1000 + 99 * kPeriod);
  EXPECT_EQ(record.find(36)->sequence, 36u);
  EXPECT_FALSE(record.find(35).has_value()) << "overwritten by 99";
  EXPECT_FALSE(record.find(100).has_value());
  EXPECT_EQ(record.added(), 100u);
  record.clear();
  EXPECT_FALSE(record.find(99).has_value());
}

TEST(StereoPairing, CorruptFramesAreCountedAndTheWaitGoesOn) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::damaged, .sequence = 10});
  rig.right.inject({.kind = SimFaultKind::damaged, .sequence = 20});
  rig.right.inject({.kind = SimFaultKind::damaged, .sequence = 21});
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing());
  const Tally t = run(rig, rig.left, rig.right, grabber, 50);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.corrupt_left, 1u);
  EXPECT_EQ(c.corrupt_right, 2u);
  EXPECT_EQ(c.unpaired_right, 1u);  // right's 10
  EXPECT_EQ(c.unpaired_left, 2u);   // left's 20 and 21
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

TEST(StereoPairing, DelaysAndSkewedTimestamps) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::delay, .sequence = 5, .duration = 3 * kPeriod});
  rig.right.inject({.kind = SimFaultKind::delay, .sequence = 15, .duration = 45 * kMs});
  rig.right.inject({.kind = SimFaultKind::skew, .sequence = 25, .duration = 5 * kMs});
  StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing());
  const Tally t = run(rig, rig.left, rig.right, grabber, 60);
  const PairingCounters& c = grabber.pairer().counters();
  EXPECT_EQ(c.mismatched_left, 1u) << "trigger 25's timestamps differ by 5 ms";
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
    StereoGrabber grabber(rig.left, rig.right, rig.board.clock, pairing());
    const Tally t = run(rig, rig.left, rig.right, grabber, 3000);
    const PairingCounters& c = grabber.pairer().counters();
    EXPECT_GT(t.pairs, 2000u) << seed;
    EXPECT_GT(c.unpaired_left + c.unpaired_right, 100u) << seed;
    EXPECT_GT(c.mismatched_left + c.out_of_order_left + c.out_of_order_right, 10u) << seed;
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
  StereoGrabber grabber(left, right, rig.board.clock, pairing());
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
    EXPECT_EQ(r.pair.left.sequence, r.pair.right.sequence);
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

TEST(Recovery, TimeoutsInARowReopenTheCamera) {
  Rig rig;
  rig.left.inject({.kind = SimFaultKind::stall, .sequence = 5, .duration = 40 * kPeriod});
  RecoveryConfig config;
  config.timeouts_before_reopen = 3;
  RecoveringCamera left(rig.left, rig.board.clock, config);
  int frames = 0;
  while (rig.board.clock.now() < 100 * kPeriod) {
    const AcquireResult r = left.acquire(2 * kPeriod);
    if (r.status == AcquireStatus::ok) {
      ++frames;
      left.release(r.frame);
    }
  }
  EXPECT_GE(left.counters().timeouts, 3u);
  EXPECT_GE(left.counters().reopens, 1u);
  EXPECT_GT(frames, 80);
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
    r.create_camera("libcamera", c);
    FAIL();
  } catch (const Error& e) {
    // Built: no such camera; not built (cross builds without a sysroot): it says so.
    EXPECT_NE(std::string(e.what()).find(libcamera_build_version().empty()
                                             ? "not built into this binary"
                                             : "camera /dev/video3: no libcamera camera"),
              std::string::npos)
        << e.what();
  }
  try {
    TriggerConfig t;
    t.line = "CAM_TRIG";
    r.create_trigger("gpiod", t);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("CAM_TRIG"), std::string::npos);
  }
  EXPECT_THROW(r.create_camera("sim", c), Error) << "no simulated board";
  try {
    r.create_serial("termios", {.device = "/dev/nonexistent-tty", .baud = 115200});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/nonexistent-tty"), std::string::npos);
  }
  EXPECT_THROW(r.create_serial("uart", {.device = "/dev/ttyS0", .baud = 9600}), Error);
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
  CameraConfig bad = config_for("middle");
  EXPECT_THROW(BackendRegistry::builtin().create_camera("sim", bad, context), Error);
}

}  // namespace
}  // namespace epipole::hal

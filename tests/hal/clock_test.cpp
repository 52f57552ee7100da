#include "epipole/hal/clock.hpp"

#include <gtest/gtest.h>

#include "epipole/core/error.hpp"

namespace epipole::hal {
namespace {

TEST(MonotonicClock, NeverGoesBackAndSleeps) {
  MonotonicClock clock;
  const Nanoseconds start = clock.now();
  EXPECT_GT(start, 0);
  clock.sleep_until(start + 2'000'000);
  EXPECT_GE(clock.now(), start + 2'000'000);
  clock.sleep_until(start);  // in the past: returns at once
}

TEST(VirtualClock, MovesOnlyWhenTold) {
  VirtualClock clock(1000);
  EXPECT_EQ(clock.now(), 1000);
  clock.advance(500);
  EXPECT_EQ(clock.now(), 1500);
  clock.sleep_until(10'000);
  EXPECT_EQ(clock.now(), 10'000);
  clock.sleep_until(5'000);  // never backwards
  EXPECT_EQ(clock.now(), 10'000);
  EXPECT_THROW(clock.advance(-1), Error);
}

// Charging compute, the host's time passes on the clock between its jumps, and only then.
TEST(VirtualClock, TheHostsTimePassesOnItOnlyWhenCharged) {
  VirtualClock clock(1000);
  MonotonicClock host;
  host.sleep_until(host.now() + 2'000'000);
  EXPECT_EQ(clock.now(), 1000) << "not charged unless asked";

  clock.charge_compute(true);
  const Nanoseconds before = host.now();
  const Nanoseconds start = clock.now();
  host.sleep_until(before + 3'000'000);
  const Nanoseconds after = clock.now();
  EXPECT_GE(after - start, 3'000'000) << "the host's 3 ms of work";
  EXPECT_LE(after - start, host.now() - before + 1) << "no more than the host's time";

  // A jump goes straight to its deadline; the host's time goes on from there.
  clock.sleep_until(after + 1'000'000'000);
  const Nanoseconds jumped = clock.now();
  EXPECT_GE(jumped, after + 1'000'000'000);
  EXPECT_LT(jumped, after + 1'000'000'000 + 1'000'000'000) << "not a second of host time";
  clock.advance(500);
  EXPECT_GE(clock.now(), jumped + 500);

  clock.charge_compute(false);
  const Nanoseconds stopped = clock.now();
  host.sleep_until(host.now() + 2'000'000);
  EXPECT_EQ(clock.now(), stopped) << "no longer charged";
}

}  // namespace
}  // namespace epipole::hal

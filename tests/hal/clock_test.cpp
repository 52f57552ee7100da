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

TEST(VirtualClock, SpentComputeTimeMovesItOnlyWhenCharged) {
  VirtualClock clock(1000);
  clock.spend(500);
  EXPECT_EQ(clock.now(), 1000) << "not charged unless asked";
  clock.charge_compute(true);
  clock.spend(500);
  EXPECT_EQ(clock.now(), 1500);
  clock.spend(-5);  // a host clock that stepped back charges nothing
  EXPECT_EQ(clock.now(), 1500);
}

}  // namespace
}  // namespace epipole::hal

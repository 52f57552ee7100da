#include "epipole/firmware/health_monitor.hpp"

#include <gtest/gtest.h>

#include "epipole/core/error.hpp"

namespace epipole::firmware {
namespace {

constexpr hal::Nanoseconds kMs = 1'000'000;

TEST(HealthMonitor, ReportsRatesPercentilesAndStageMeansOncePerWindow) {
  HealthMonitor monitor(0);
  StageTimes stages{};
  // 100 frames in the first second, latencies 1..100 ms (shuffled), rectify 2 ms, total 10 ms.
  for (int i = 0; i < 100; ++i) {
    stages[static_cast<std::size_t>(protocol::Stage::rectify)] = 2 * kMs;
    stages[static_cast<std::size_t>(protocol::Stage::total)] = 10 * kMs;
    monitor.record(((i * 37) % 100 + 1) * kMs, stages, ((i * 53) % 100) * kMs / 10);
  }
  EXPECT_FALSE(monitor.due(999 * kMs, {})) << "the window is not over yet";
  FaultCounts faults;
  faults.camera_timeouts = 3;
  faults.unpaired_frames = (std::uint64_t{1} << 32) + 70'000;  // wraps in the message
  faults.messages_dropped = 5;
  faults.snapshot_failures = 2;
  faults.triggers.stale = 1;
  faults.triggers.one_side = 2;
  faults.triggers.both_sides = 3;
  faults.triggers.corrupt = 4;
  const auto h = monitor.due(1000 * kMs, faults);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->frames, 100u);
  EXPECT_EQ(h->fps_centi, 10000);
  EXPECT_EQ(h->uptime_ms, 1000u);
  EXPECT_EQ(h->latency_p50_us, 50'000u);  // nearest rank: the 50th of 100
  EXPECT_EQ(h->latency_p99_us, 99'000u);
  EXPECT_EQ(h->stage_us[static_cast<std::size_t>(protocol::Stage::rectify)], 2000u);
  EXPECT_EQ(h->stage_us[static_cast<std::size_t>(protocol::Stage::total)], 10'000u);
  EXPECT_EQ(h->stage_us[static_cast<std::size_t>(protocol::Stage::detect)], 0u);
  // Waits 0, 0.1, .., 9.9 ms; 100 pairs of 10 ms in the second: the loop was busy all of it.
  EXPECT_EQ(h->wait_p50_us, 4900u);
  EXPECT_EQ(h->wait_p99_us, 9800u);
  EXPECT_EQ(h->busy_permille, 1000);
  EXPECT_EQ(h->camera_timeouts, 3u);
  EXPECT_EQ(h->unpaired_frames, 70'000u) << "modulo 2^32: it goes on, never stops";
  EXPECT_EQ(h->messages_dropped, 5u);
  EXPECT_EQ(h->snapshot_failures, 2u);
  EXPECT_EQ(h->dropped, 10u);
  EXPECT_EQ(h->dropped_stale, 1u);
  EXPECT_EQ(h->dropped_one_side, 2u);
  EXPECT_EQ(h->dropped_both_sides, 3u);
  EXPECT_EQ(h->dropped_corrupt, 4u);

  // The next window: one frame, then silence; a window without frames still reports.
  monitor.record(7 * kMs, stages);
  const auto h2 = monitor.due(2000 * kMs, {});
  ASSERT_TRUE(h2);
  EXPECT_EQ(h2->frames, 101u);
  EXPECT_EQ(h2->fps_centi, 100);
  EXPECT_EQ(h2->latency_p50_us, 7000u);
  EXPECT_EQ(h2->latency_p99_us, 7000u);
  EXPECT_EQ(h2->wait_p99_us, 0u) << "recorded without a wait";
  EXPECT_EQ(h2->busy_permille, 10) << "one pair of 10 ms in the second";
  const auto h3 = monitor.due(3000 * kMs, {});
  ASSERT_TRUE(h3);
  EXPECT_EQ(h3->fps_centi, 0);
  EXPECT_EQ(h3->latency_p99_us, 0u);
  EXPECT_EQ(h3->busy_permille, 0);
}

TEST(HealthMonitor, MoreFramesThanRoomStillCount) {
  HealthMonitor monitor(0, 4);
  for (int i = 0; i < 10; ++i) monitor.record((i + 1) * kMs, {});
  const auto h = monitor.due(1000 * kMs, {});
  ASSERT_TRUE(h);
  EXPECT_EQ(h->frames, 10u);
  EXPECT_EQ(h->fps_centi, 1000);
  EXPECT_EQ(h->latency_p99_us, 4000u) << "the first 4 frames make the percentiles";
}

TEST(HealthMonitor, WindowsDoNotDriftAndRestartAfterAStall) {
  HealthMonitor monitor(0);
  EXPECT_TRUE(monitor.due(1'010 * kMs, {}));
  EXPECT_FALSE(monitor.due(1'990 * kMs, {})) << "the second window ends at 2 s, not 2.01 s";
  EXPECT_TRUE(monitor.due(2'000 * kMs, {}));
  EXPECT_TRUE(monitor.due(9'500 * kMs, {})) << "after a stall, one message, not seven";
  EXPECT_FALSE(monitor.due(10'000 * kMs, {}));
  EXPECT_TRUE(monitor.due(10'500 * kMs, {}));
}

TEST(HealthMonitor, BadConfigurationIsAnError) {
  EXPECT_THROW(HealthMonitor(0, 0), Error);
  EXPECT_THROW(HealthMonitor(0, 10, 0), Error);
}

}  // namespace
}  // namespace epipole::firmware

// The trigger watch on hardware: its own thread waits on the line and records the edges while
// the frame loop's thread reads the record and changes the period (run under ThreadSanitizer by
// the host-tsan preset).
#include "epipole/firmware/trigger_watch.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

namespace epipole::firmware {
namespace {

// A line that fires an edge every millisecond, until told to go quiet.
class TickingLine final : public hal::TriggerLine {
 public:
  const hal::TriggerConfig& config() const override { return config_; }
  void start() override {}
  void stop() override {}
  hal::EdgeResult wait_edge(hal::Nanoseconds timeout) override {
    if (quiet_.load()) {
      std::this_thread::sleep_for(
          std::chrono::nanoseconds(std::min<hal::Nanoseconds>(timeout, 2'000'000)));
      return {hal::EdgeStatus::timeout, {}};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const auto now = std::chrono::steady_clock::now().time_since_epoch();
    return {hal::EdgeStatus::ok,
            {next_++, std::chrono::duration_cast<std::chrono::nanoseconds>(now).count()}};
  }
  void set_rate(double) override {}
  void go_quiet() { quiet_ = true; }

 private:
  hal::TriggerConfig config_;
  std::atomic<bool> quiet_{false};
  std::uint32_t next_ = 0;  // the watch's thread only
};

TEST(TriggerWatch, RecordsEdgesOnItsThreadWhileTheLoopReadsThem) {
  TickingLine line;
  TriggerWatch watch(line, 1'000'000);
  watch.start();
  std::uint64_t seen = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  while (std::chrono::steady_clock::now() < end) {
    const std::uint64_t added = watch.record().added();
    if (added > 0 && watch.record().find(static_cast<std::uint32_t>(added - 1))) ++seen;
    watch.set_period(1'000'000);
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  EXPECT_GT(seen, 10u);
  EXPECT_GT(watch.record().added(), 50u);
  EXPECT_EQ(watch.losses(), 0u);
  line.go_quiet();  // three periods without an edge: one loss, however long the quiet lasts
  const auto quiet_end = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (watch.losses() == 0 && std::chrono::steady_clock::now() < quiet_end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(watch.losses(), 1u);
  watch.stop();
}

// A line whose recovery throws (a look-up that ran out of memory, say) the first `throws` times.
class ThrowingLine final : public hal::TriggerLine {
 public:
  explicit ThrowingLine(int throws) : throws_(throws) {}
  const hal::TriggerConfig& config() const override { return config_; }
  void start() override {}
  void stop() override {}
  hal::EdgeResult wait_edge(hal::Nanoseconds) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (throws_.load() > 0) {
      --throws_;
      throw std::runtime_error("no memory for the chip list");
    }
    const auto now = std::chrono::steady_clock::now().time_since_epoch();
    return {hal::EdgeStatus::ok,
            {0, std::chrono::duration_cast<std::chrono::nanoseconds>(now).count()}};
  }
  void set_rate(double) override {}

 private:
  hal::TriggerConfig config_;
  std::atomic<int> throws_;
};

// Nothing the line throws leaves the watch's thread (it would end the firmware): the thread
// counts one loss for the spell of failures and goes on recording edges once the line works.
TEST(TriggerWatch, ALineThatThrowsNeverEndsTheThread) {
  ThrowingLine line(5);
  TriggerWatch watch(line, 1'000'000);
  watch.start();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (watch.record().added() < 20 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  watch.stop();
  EXPECT_GE(watch.record().added(), 20u);
  EXPECT_EQ(watch.losses(), 1u);
}

// Edges closer than a quarter period to the one before are bounces: the watch's record ignores
// them, and takes the new gap when the rate changes.
// Edges 1 ms apart on the line's own clock, however the thread is scheduled: what is a bounce
// depends on the edges' times alone.
class SteppingLine final : public hal::TriggerLine {
 public:
  const hal::TriggerConfig& config() const override { return config_; }
  void start() override {}
  void stop() override {}
  hal::EdgeResult wait_edge(hal::Nanoseconds) override {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    if (hold_) {
      parked_ = true;
      return {hal::EdgeStatus::timeout, {}};
    }
    parked_ = false;
    const std::uint32_t n = next_++;
    return {hal::EdgeStatus::ok, {n, 1'000'000'000 + static_cast<hal::Nanoseconds>(n) * 1'000'000}};
  }
  void set_rate(double) override {}
  // No edge until release(); parked(): the watch's thread has seen that (its counts are still).
  void hold() { hold_ = true; }
  bool parked() const { return parked_; }
  void release() { hold_ = false; }

 private:
  hal::TriggerConfig config_;
  std::uint32_t next_ = 0;  // the watch's thread only
  std::atomic<bool> hold_{false};
  std::atomic<bool> parked_{false};
};

TEST(TriggerWatch, TheRecordIgnoresBouncesByTheCurrentPeriod) {
  SteppingLine line;
  TriggerWatch watch(line, 100'000'000);  // 10 Hz: an edge 1 ms after another is a bounce
  watch.start();
  const auto until = [](const auto& done) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!done() && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  };
  until([&] { return watch.bounces() >= 60; });
  line.hold();
  until([&] { return line.parked(); });
  const std::uint64_t bounces = watch.bounces();
  const std::uint64_t added = watch.record().added();
  watch.set_period(1'000'000);  // 1 kHz: 1 ms apart is the rate
  line.release();
  until([&] { return watch.record().added() > added + 20; });
  watch.stop();
  EXPECT_GE(bounces, 60u);
  // At 10 Hz an edge is taken 25 ms (25 edges) after the one taken before: the first, the 26th...
  EXPECT_EQ(added, (added + bounces + 24) / 25) << bounces << " bounces";
  EXPECT_GT(watch.record().added(), added + 20);
  EXPECT_EQ(watch.bounces(), bounces) << "at 1 kHz none is a bounce";
}

}  // namespace
}  // namespace epipole::firmware

#include "epipole/core/task_batch.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole {
namespace {

TEST(TaskBatch, RunsEveryTaskOfEveryPartOnce) {
  for (const int threads : {1, 2, 3}) {
    ThreadPool pool(threads);
    TaskBatch batch;
    for (int round = 0; round < 50; ++round) {
      std::vector<std::atomic<int>> a(5), b(1), c(11);
      std::atomic<int> bad_worker{0};
      auto count = [&](std::vector<std::atomic<int>>& seen) {
        return [&seen, &bad_worker, threads](int task, int worker) {
          seen[static_cast<std::size_t>(task)]++;
          if (worker < 0 || worker >= threads) bad_worker++;
        };
      };
      auto fa = count(a);
      auto fb = count(b);
      auto fc = count(c);
      auto none = [](int, int) { FAIL() << "a part of no tasks ran one"; };
      EXPECT_EQ(batch.add(5, fa), 0);
      EXPECT_EQ(batch.add(0, none), 1);
      EXPECT_EQ(batch.add(1, fb, 0), 2);
      EXPECT_EQ(batch.add(11, fc), 3);
      batch.run(pool);
      for (const auto* seen : {&a, &b, &c}) {
        for (const auto& s : *seen) ASSERT_EQ(s.load(), 1);
      }
      EXPECT_EQ(bad_worker.load(), 0);
    }
  }
}

// The waiting part's tasks see every task of the part they wait for finished, however the
// workers take them.
TEST(TaskBatch, APartStartsAfterThePartItWaitsFor) {
  for (const int threads : {1, 2, 3}) {
    ThreadPool pool(threads);
    TaskBatch batch;
    for (int round = 0; round < 50; ++round) {
      std::atomic<int> first_done{0};
      std::atomic<int> second_done{0};
      std::atomic<int> early{0};
      auto first = [&](int task, int) {
        if (task == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
        first_done++;
      };
      auto second = [&](int, int) {
        if (first_done.load() != 4) early++;
        second_done++;
      };
      auto third = [&](int, int) {
        if (second_done.load() != 3) early++;
      };
      const int a = batch.add(4, first);
      const int b = batch.add(3, second, a);
      batch.add(2, third, b);
      batch.run(pool);
      EXPECT_EQ(early.load(), 0);
      EXPECT_EQ(second_done.load(), 3);
    }
  }
}

TEST(TaskBatch, AFailedPartStopsThePartsWaitingForItOnly) {
  ThreadPool pool(2);
  TaskBatch batch;
  std::atomic<int> waiting_ran{0};
  std::atomic<int> other_ran{0};
  auto failing = [](int task, int) {
    if (task == 1) throw Error("task 1 failed");
  };
  auto waiting = [&](int, int) { waiting_ran++; };
  auto other = [&](int, int) { other_ran++; };
  const int a = batch.add(3, failing);
  batch.add(2, waiting, a);
  batch.add(4, other);
  EXPECT_THROW(batch.run(pool), Error);
  EXPECT_EQ(waiting_ran.load(), 0);
  EXPECT_EQ(other_ran.load(), 4);
  // The batch is usable again.
  batch.add(2, other);
  batch.run(pool);
  EXPECT_EQ(other_ran.load(), 6);
}

TEST(TaskBatch, SpansCoverTheirParts) {
  ThreadPool pool(2);
  TaskBatch batch;
  auto sleep = [](int, int) { std::this_thread::sleep_for(std::chrono::milliseconds(3)); };
  auto nothing = [](int, int) {};
  const int a = batch.add(1, sleep);
  const int empty = batch.add(0, nothing);
  const int b = batch.add(2, sleep, a);
  batch.run(pool);
  EXPECT_GE(batch.span_ns(a, a), 3'000'000);
  EXPECT_GE(batch.span_ns(a, b), 6'000'000) << "b starts after a ends and takes 3 ms";
  EXPECT_EQ(batch.span_ns(empty, empty), 0);
  EXPECT_EQ(batch.span_ns(TaskBatch::kNoPart, a), 0);
  EXPECT_EQ(batch.span_ns(a, 7), 0);
}

TEST(TaskBatch, BadPartsAreErrors) {
  TaskBatch batch;
  auto nothing = [](int, int) {};
  EXPECT_THROW(batch.add(1, nothing, 0), Error) << "waits for a part not added";
  EXPECT_THROW(batch.add(-1, nothing), Error);
  for (int i = 0; i < TaskBatch::kMaxParts; ++i) batch.add(1, nothing);
  EXPECT_THROW(batch.add(1, nothing), Error);
  // Parts forgotten by clear() (an error between add() and run(), say) do not run.
  batch.clear();
  int ran = 0;
  auto count = [&](int, int) { ++ran; };
  batch.add(2, count);
  ThreadPool pool(1);
  batch.run(pool);
  EXPECT_EQ(ran, 2);
}

}  // namespace
}  // namespace epipole

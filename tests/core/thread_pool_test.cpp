#include "epipole/core/thread_pool.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole {
namespace {

TEST(ThreadPool, RunsEveryTaskOnceOnItsWorkers) {
  for (const int threads : {1, 2, 3}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (int round = 0; round < 50; ++round) {
      std::vector<std::atomic<int>> seen(17);
      std::atomic<int> bad_worker{0};
      pool.run(17, [&](int task, int worker) {
        seen[static_cast<std::size_t>(task)]++;
        if (worker < 0 || worker >= threads) bad_worker++;
      });
      for (const auto& s : seen) ASSERT_EQ(s.load(), 1);
      EXPECT_EQ(bad_worker.load(), 0);
    }
  }
}

TEST(ThreadPool, UsesSeveralThreads) {
  ThreadPool pool(2);
  std::mutex mutex;
  std::set<std::thread::id> ids;
  std::atomic<int> arrived{0};
  pool.run(2, [&](int, int) {
    {
      const std::lock_guard lock(mutex);
      ids.insert(std::this_thread::get_id());
    }
    arrived++;
    // Wait for the other task: only possible if both run at once.
    while (arrived.load() < 2) std::this_thread::yield();
  });
  EXPECT_EQ(ids.size(), 2u);
}

TEST(ThreadPool, RethrowsATaskError) {
  ThreadPool pool(2);
  EXPECT_THROW(pool.run(4,
                        [](int task, int) {
                          if (task == 2) throw Error("task 2 failed");
                        }),
               Error);
  int count = 0;
  pool.run(3, [&](int, int) { ++count; });  // still usable; tasks may share count only if 1 thread
  EXPECT_GE(count, 1);
}

TEST(ThreadPool, RejectsBadThreadCounts) {
  EXPECT_THROW(ThreadPool(0), Error);
  EXPECT_THROW(ThreadPool(65), Error);
}

}  // namespace
}  // namespace epipole

#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>

#include "epipole/core/thread_pool.hpp"

namespace epipole {

// The tasks of several stages as one ThreadPool::run, so that the workers go on to the next
// stage's tasks instead of waiting for the slowest task of each stage. Parts are added in the
// order their tasks should start. A part may name an earlier part that must have finished
// before its own tasks run: they wait for it, which cannot deadlock, because the pool starts
// tasks in index order, so every task of the earlier part is already running on some worker.
// When a task of the earlier part threw, the waiting part's tasks do not run (run() rethrows).
//
// Fixed memory: at most kMaxParts parts, no allocation. Not re-entrant; one run at a time.
class TaskBatch {
 public:
  static constexpr int kMaxParts = 8;
  static constexpr int kNoPart = -1;

  // Adds `count` tasks calling task(i, worker) for i in [0, count) (worker as ThreadPool::run
  // gives it). `task` must outlive run(). Returns the part's index, for `after` and span_ns().
  int add(int count, TaskRef task, int after = kNoPart);
  // Forgets the parts added so far (after an error between add() and run(), say).
  void clear();
  // Runs every part's tasks on `pool` and forgets the parts (their times stay until the next
  // add()). Rethrows the first exception a task threw.
  void run(ThreadPool& pool);

  // The wall time of parts in the last run: from the first task of `first` starting to the last
  // task of `last` ending, in nanoseconds; 0 when either is kNoPart or did not run a task.
  std::int64_t span_ns(int first, int last) const;

 private:
  struct Part {
    std::optional<TaskRef> task;
    int first = 0;  // its first task's index in the run
    int count = 0;
    int after = kNoPart;
    std::atomic<int> unfinished{0};
    std::atomic<bool> failed{false};
    std::atomic<std::int64_t> start_ns{0};
    std::atomic<std::int64_t> end_ns{0};
  };
  void run_task(int index, int worker);

  std::array<Part, kMaxParts> parts_;
  int size_ = 0;
  int tasks_ = 0;
  bool ran_ = false;  // the parts are the last run's: add() starts a new batch
};

}  // namespace epipole

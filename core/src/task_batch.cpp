#include "epipole/core/task_batch.hpp"

#include <chrono>

#include "epipole/core/error.hpp"

namespace epipole {

namespace {

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Lowers (raises) `value` to `candidate` when it is smaller (larger).
void lower_to(std::atomic<std::int64_t>& value, std::int64_t candidate) {
  std::int64_t seen = value.load(std::memory_order_relaxed);
  while (candidate < seen && !value.compare_exchange_weak(seen, candidate)) {
  }
}
void raise_to(std::atomic<std::int64_t>& value, std::int64_t candidate) {
  std::int64_t seen = value.load(std::memory_order_relaxed);
  while (candidate > seen && !value.compare_exchange_weak(seen, candidate)) {
  }
}

}  // namespace

void TaskBatch::clear() {
  size_ = 0;
  tasks_ = 0;
  ran_ = false;
}

int TaskBatch::add(int count, TaskRef task, int after) {
  if (ran_) clear();
  require(size_ < kMaxParts, "a task batch holds at most ", kMaxParts, " parts");
  require(count >= 0, "a part of ", count, " tasks");
  require(after == kNoPart || (after >= 0 && after < size_),
          "a part can only wait for a part added before it");
  Part& p = parts_[static_cast<std::size_t>(size_)];
  p.task = task;
  p.first = tasks_;
  p.count = count;
  p.after = after;
  p.unfinished.store(count);
  p.failed.store(false);
  p.start_ns.store(INT64_MAX);
  p.end_ns.store(0);
  tasks_ += count;
  return size_++;
}

void TaskBatch::run_task(int index, int worker) {
  std::size_t i = 0;
  while (index >= parts_[i].first + parts_[i].count) ++i;
  Part& p = parts_[i];
  struct Finish {  // the part's count goes down even when the task throws
    Part& part;
    ~Finish() {
      raise_to(part.end_ns, now_ns());
      if (part.unfinished.fetch_sub(1) == 1) part.unfinished.notify_all();
    }
  };
  if (p.after != kNoPart) {
    Part& before = parts_[static_cast<std::size_t>(p.after)];
    for (int left = before.unfinished.load(); left != 0; left = before.unfinished.load()) {
      before.unfinished.wait(left);
    }
    if (before.failed.load()) {
      p.failed.store(true);
      if (p.unfinished.fetch_sub(1) == 1) p.unfinished.notify_all();
      return;
    }
  }
  lower_to(p.start_ns, now_ns());
  const Finish finish{p};
  try {
    (*p.task)(index - p.first, worker);
  } catch (...) {
    p.failed.store(true);
    throw;
  }
}

void TaskBatch::run(ThreadPool& pool) {
  ran_ = true;
  pool.run(tasks_, [this](int index, int worker) { run_task(index, worker); });
}

std::int64_t TaskBatch::span_ns(int first, int last) const {
  if (first < 0 || first >= size_ || last < 0 || last >= size_) return 0;
  const std::int64_t start = parts_[static_cast<std::size_t>(first)].start_ns.load();
  const std::int64_t end = parts_[static_cast<std::size_t>(last)].end_ns.load();
  return end > start ? end - start : 0;
}

}  // namespace epipole

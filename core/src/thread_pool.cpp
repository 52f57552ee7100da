#include "epipole/core/thread_pool.hpp"

#include <sched.h>

#include <algorithm>
#include <exception>

#include "epipole/core/error.hpp"

namespace epipole {

int usable_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  return sched_getaffinity(0, sizeof set, &set) == 0 ? std::max(1, CPU_COUNT(&set)) : 1;
}

ThreadPool::ThreadPool(int threads, const std::function<void()>& on_start) {
  require(threads >= 1 && threads <= 64, "thread count ", threads, " is outside 1..64");
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  for (int w = 1; w < threads; ++w) {
    workers_.emplace_back([this, w, on_start] {
      if (on_start) on_start();
      {
        const std::lock_guard lock(mutex_);
        ++started_;
      }
      done_.notify_all();
      work(w);
    });
  }
  // Every worker has run on_start() before the pool is used (or its creator turns real-time
  // and keeps a core a worker would need to start on).
  std::unique_lock lock(mutex_);
  done_.wait(lock, [&] { return started_ == threads - 1; });
}

ThreadPool::~ThreadPool() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  start_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::drain(int worker) {
  std::unique_lock lock(mutex_);
  while (next_ < count_) {
    const int task = next_++;
    const TaskRef* const f = task_;
    lock.unlock();
    try {
      (*f)(task, worker);
    } catch (...) {
      lock.lock();
      if (!error_) error_ = std::current_exception();
      lock.unlock();
    }
    lock.lock();
    if (--unfinished_ == 0) done_.notify_all();
  }
}

void ThreadPool::work(int worker) {
  unsigned seen = 0;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      start_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    drain(worker);
  }
}

void ThreadPool::run(int count, TaskRef task) {
  if (count <= 0) return;
  {
    const std::lock_guard lock(mutex_);
    task_ = &task;
    count_ = count;
    next_ = 0;
    unfinished_ = count;
    error_ = nullptr;
    ++generation_;
  }
  if (!workers_.empty()) start_.notify_all();
  drain(0);
  std::exception_ptr error;
  {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return unfinished_ == 0; });
    task_ = nullptr;
    count_ = 0;
    error = error_;
    error_ = nullptr;
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace epipole

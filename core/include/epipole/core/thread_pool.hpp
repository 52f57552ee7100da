#pragma once

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace epipole {

// The CPUs this process may run on (its affinity mask, which a service manager may narrow), at
// least 1: the default number of threads.
int usable_cpus();

// A non-owning reference to a callable of signature void(int task, int worker): no allocation,
// valid only while the callable it refers to lives (the span of one ThreadPool::run call).
class TaskRef {
 public:
  template <typename Callable>
  requires(!std::is_same_v<std::remove_cvref_t<Callable>, TaskRef>)
      TaskRef(Callable& callable)  // NOLINT(google-explicit-constructor)
      : object_(&callable), call_([](void* object, int task, int worker) {
          (*static_cast<Callable*>(object))(task, worker);
        }) {}

  void operator()(int task, int worker) const { call_(object_, task, worker); }

 private:
  void* object_;
  void (*call_)(void*, int, int);
};

// A fixed pool of worker threads, all created by the constructor and joined by the destructor.
// run(count, task) calls task(i, worker) for every i in [0, count) (e.g. one row stripe each)
// and returns when all are done. The calling thread works too, as worker 0; background threads
// are workers 1..threads()-1, so per-worker scratch buffers can be indexed by `worker`.
// run() never allocates; it is not re-entrant and must be called from one thread at a time.
class ThreadPool {
 public:
  // `on_start` runs first on each background worker (its name and scheduling, say), before the
  // constructor returns.
  explicit ThreadPool(int threads, const std::function<void()>& on_start = {});
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  // Runs task(i, worker) for i in [0, count). Tasks start in index order (a worker takes the
  // next one when it is free; TaskBatch relies on this). An exception thrown by a task is
  // rethrown here (the first one; the other tasks still run).
  void run(int count, TaskRef task);
  template <typename Callable>
  void run(int count, Callable&& callable) {
    TaskRef task(callable);
    run(count, task);
  }

 private:
  void work(int worker);
  void drain(int worker);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  // The one task slot, guarded by mutex_.
  const TaskRef* task_ = nullptr;
  int count_ = 0;
  int next_ = 0;
  int unfinished_ = 0;
  unsigned generation_ = 0;
  bool stopping_ = false;
  int started_ = 0;  // workers past on_start()
  std::exception_ptr error_;
};

}  // namespace epipole

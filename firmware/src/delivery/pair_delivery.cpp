#include "delivery/pair_delivery.hpp"

#include <exception>
#include <utility>

#include "epipole/core/error.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "steady_time.hpp"

namespace epipole::firmware::outputs {

PairDelivery::PairDelivery(std::string name, const BoardConfig& board, PairParts parts, Work work,
                           HealthWork health_work, int copies)
    : name_(std::move(name)),
      work_(std::move(work)),
      health_work_(std::move(health_work)),
      slots_(static_cast<std::size_t>(copies), Slot::free),
      order_(static_cast<std::size_t>(copies), 0) {
  require(copies >= 2, "output ", name_, ": needs at least two copies of a pair");
  copies_.reserve(static_cast<std::size_t>(copies));
  for (int i = 0; i < copies; ++i) copies_.emplace_back(board, parts);
}

PairDelivery::~PairDelivery() {
  stop();
}

void PairDelivery::start() {
  if (thread_.joinable()) return;
  {
    const std::lock_guard lock(mutex_);
    stopping_ = false;
  }
  thread_ = std::thread([this] { run(); });
}

void PairDelivery::stop() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void PairDelivery::offer(const FrameResult& result, const PairStamp& stamp) {
  std::size_t chosen = slots_.size();
  {
    const std::lock_guard lock(mutex_);
    for (std::size_t i = 0; i < slots_.size(); ++i) {
      if (slots_[i] == Slot::free) {
        chosen = i;
        break;
      }
    }
    if (chosen == slots_.size()) {  // every copy waits or is in work: replace the oldest waiting
      chosen = oldest_waiting();
      if (chosen == slots_.size()) return;  // cannot be with two copies and one thread
      ++counters_.dropped;
    }
    slots_[chosen] = Slot::filling;
  }
  copies_[chosen].copy_from(result, stamp);  // outside the lock: the thread never reads it now
  {
    const std::lock_guard lock(mutex_);
    slots_[chosen] = Slot::waiting;
    order_[chosen] = ++offered_;
  }
  wake_.notify_one();
}

void PairDelivery::offer_health(const HealthReport& report) {
  if (!health_work_) return;
  {
    const std::lock_guard lock(mutex_);
    health_ = report;
    health_order_ = ++offered_;
  }
  wake_.notify_one();
}

DeliveryCounters PairDelivery::counters() const {
  const std::lock_guard lock(mutex_);
  return counters_;
}

std::size_t PairDelivery::working_set_bytes() const {
  std::size_t bytes = sizeof(PairDelivery);
  for (const PairCopy& c : copies_) bytes += c.working_set_bytes();
  return bytes;
}

template <class DoWork>
void PairDelivery::do_work(DoWork&& work) {
  try {
    work();
  } catch (const std::exception& e) {
    {
      const std::lock_guard lock(mutex_);
      ++counters_.failures;
    }
    if (faults_said_.allow(detail::steady_now())) {
      journal(Priority::warning, "output %s: %s (going on; health counts output_failures)",
              name_.c_str(), e.what());
    }
  }
}

std::size_t PairDelivery::oldest_waiting() const {
  std::size_t oldest = slots_.size();
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i] == Slot::waiting && (oldest == slots_.size() || order_[i] < order_[oldest])) {
      oldest = i;
    }
  }
  return oldest;
}

void PairDelivery::run() {
  enter_thread_role_or_say(ThreadRole::output);
  std::unique_lock lock(mutex_);
  for (;;) {
    const std::size_t next = oldest_waiting();
    if (stopping_ && next == slots_.size() && !health_) return;  // what waited is done first
    // In the order they were offered: the pairs before a health message, then it.
    if (health_ && (next == slots_.size() || health_order_ < order_[next])) {
      health_in_work_ = *health_;
      health_.reset();
      lock.unlock();
      do_work([&] { health_work_(health_in_work_); });
      lock.lock();
      continue;
    }
    if (next == slots_.size()) {
      wake_.wait(lock);
      continue;
    }
    slots_[next] = Slot::working;
    lock.unlock();
    bool done = false;
    const hal::Nanoseconds started = detail::steady_now();
    do_work([&] {
      work_(copies_[next]);
      done = true;
    });
    const hal::Nanoseconds took = detail::steady_now() - started;
    lock.lock();
    slots_[next] = Slot::free;
    if (done) {
      ++counters_.delivered;
      counters_.work_ns += static_cast<std::uint64_t>(took);
    }
  }
}

}  // namespace epipole::firmware::outputs

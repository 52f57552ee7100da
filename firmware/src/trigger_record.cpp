#include "epipole/firmware/trigger_record.hpp"

#include <chrono>

#include "steady_time.hpp"

namespace epipole::firmware {

using detail::steady_now;

TriggerRecord::TriggerRecord(hal::TriggerLine& line, bool threaded, hal::Nanoseconds period)
    : line_(line), threaded_(threaded), period_(period) {}

TriggerRecord::~TriggerRecord() {
  stop();
}

void TriggerRecord::start() {
  line_.start();
  last_edge_ = steady_now();
  if (threaded_ && !thread_.joinable()) {
    stopping_ = false;
    thread_ = std::thread([this] { run(); });
  }
}

void TriggerRecord::stop() {
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
  line_.stop();
}

void TriggerRecord::note(const hal::EdgeResult& r, hal::Nanoseconds now) {
  if (r.status == hal::EdgeStatus::ok) {
    const std::lock_guard lock(mutex_);
    ring_[next_] = r.edge;
    next_ = (next_ + 1) % kEdges;
    if (size_ < kEdges) ++size_;
    ++edges_;
    last_edge_ = now;
    quiet_ = false;
    return;
  }
  // One loss per quiet spell, however long it lasts.
  const bool lost = r.status == hal::EdgeStatus::lost || now - last_edge_ > 3 * period_;
  if (lost && !quiet_) {
    ++losses_;
    quiet_ = true;
  }
}

void TriggerRecord::poll() {
  for (int i = 0; i < static_cast<int>(kEdges); ++i) {
    const hal::EdgeResult r = line_.wait_edge(0);
    if (r.status != hal::EdgeStatus::ok) {
      if (r.status == hal::EdgeStatus::lost) note(r, last_edge_);
      break;
    }
    note(r, r.edge.timestamp);
  }
}

void TriggerRecord::run() {
  while (!stopping_) {
    const hal::EdgeResult r = line_.wait_edge(std::min<hal::Nanoseconds>(100'000'000, 2 * period_));
    note(r, steady_now());
    if (r.status == hal::EdgeStatus::lost) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

std::optional<hal::TriggerEdge> TriggerRecord::find(std::uint32_t sequence) const {
  const std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < size_; ++i) {
    const hal::TriggerEdge& e = ring_[(next_ + kEdges - 1 - i) % kEdges];
    if (e.sequence == sequence) return e;
  }
  return std::nullopt;
}

}  // namespace epipole::firmware

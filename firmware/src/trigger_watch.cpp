#include "epipole/firmware/trigger_watch.hpp"

#include <algorithm>
#include <chrono>

#include "steady_time.hpp"

namespace epipole::firmware {

using detail::steady_now;

TriggerWatch::TriggerWatch(hal::TriggerLine& line, hal::SimTrigger* sim, hal::Nanoseconds period)
    : line_(line), sim_(sim), period_(period) {
  if (sim_ != nullptr) sim_->record_to(&record_);
}

TriggerWatch::~TriggerWatch() {
  stop();
  if (sim_ != nullptr) sim_->record_to(nullptr);
}

void TriggerWatch::start() {
  line_.start();
  if (sim_ == nullptr && !thread_.joinable()) {
    stopping_ = false;
    thread_ = std::thread([this] { run(); });
  }
}

void TriggerWatch::stop() {
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
  line_.stop();
}

void TriggerWatch::run() {
  hal::Nanoseconds last_edge = steady_now();
  bool quiet = false;  // one loss per quiet spell, however long it lasts
  while (!stopping_) {
    const hal::Nanoseconds period = period_.load();
    const hal::EdgeResult r = line_.wait_edge(std::min<hal::Nanoseconds>(100'000'000, 2 * period));
    const hal::Nanoseconds now = steady_now();
    if (r.status == hal::EdgeStatus::ok) {
      record_.add(r.edge);
      last_edge = now;
      quiet = false;
      continue;
    }
    if ((r.status == hal::EdgeStatus::lost || now - last_edge > 3 * period) && !quiet) {
      ++losses_;
      quiet = true;
    }
    if (r.status == hal::EdgeStatus::lost) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

}  // namespace epipole::firmware

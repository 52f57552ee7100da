#include "epipole/firmware/trigger_watch.hpp"

#include <algorithm>
#include <chrono>
#include <exception>

#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "steady_time.hpp"

namespace epipole::firmware {

using detail::steady_now;

TriggerWatch::TriggerWatch(hal::TriggerLine& line, hal::Nanoseconds period)
    : line_(line), period_(period) {
  record_.set_min_gap(min_gap(period));
  line_records_itself_ = line_.record_edges_to(&record_);  // once record_ is made
}

TriggerWatch::~TriggerWatch() {
  stop();
  if (line_records_itself_) line_.record_edges_to(nullptr);
}

void TriggerWatch::set_period(hal::Nanoseconds period) {
  period_.store(period);
  record_.set_min_gap(min_gap(period));
}

void TriggerWatch::start() {
  line_.start();
  if (!line_records_itself_ && !thread_.joinable()) {
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
  enter_thread_role_or_say(ThreadRole::trigger);
  hal::Nanoseconds last_edge = steady_now();
  bool quiet = false;   // one loss per quiet spell, however long it lasts
  bool failed = false;  // one journal line per spell of failures
  while (!stopping_) {
    try {
      const hal::Nanoseconds period = period_.load();
      const hal::EdgeResult r =
          line_.wait_edge(std::min<hal::Nanoseconds>(100'000'000, 2 * period));
      const hal::Nanoseconds now = steady_now();
      if (r.status == hal::EdgeStatus::ok) {
        record_.add(r.edge);
        last_edge = now;
        quiet = false;
        failed = false;
        continue;
      }
      if ((r.status == hal::EdgeStatus::lost || now - last_edge > 3 * period) && !quiet) {
        ++losses_;
        quiet = true;
      }
      if (r.status == hal::EdgeStatus::lost) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    } catch (const std::exception& e) {
      // The line's recovery can fail in ways it did not foresee (out of memory in a look-up):
      // the thread says so once and tries again, it never ends the firmware.
      if (!failed) journal(Priority::error, "trigger: %s; trying again", e.what());
      failed = true;
      if (!quiet) ++losses_;
      quiet = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

}  // namespace epipole::firmware

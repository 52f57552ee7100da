#pragma once

#include <atomic>
#include <cstdint>
#include <thread>

#include "epipole/hal/trigger.hpp"

namespace epipole::firmware {

// Keeps the record of the board's trigger edges (hal::TriggerRecord) that the stereo pairer
// checks pairs against and that gives every result its trigger time. On hardware a thread of
// its own waits on the line — a master fires its pulses as it waits, a slave is told of each
// edge by the kernel; a line that records its own edges (one on a virtual clock, as the clock
// passes them: hal::TriggerLine::record_edges_to) needs no thread. An edge less than a
// quarter of the period after the edge before it is a bounce: the record ignores and counts it.
// Fixed memory.
class TriggerWatch {
 public:
  TriggerWatch(hal::TriggerLine& line, hal::Nanoseconds period);
  ~TriggerWatch();
  TriggerWatch(const TriggerWatch&) = delete;
  TriggerWatch& operator=(const TriggerWatch&) = delete;

  void start();
  void stop();

  // The line's rate changed (hal::TriggerLine::set_rate): losses and bounces are judged by the
  // new period.
  void set_period(hal::Nanoseconds period);
  static hal::Nanoseconds min_gap(hal::Nanoseconds period) { return period / 4; }

  const hal::TriggerRecord& record() const { return record_; }
  const hal::TriggerLine& line() const { return line_; }
  // Times the line went quiet for more than three periods, or reported itself lost.
  std::uint64_t losses() const { return losses_.load(); }
  // Edges ignored as bounces (hal::TriggerRecord::bounces).
  std::uint64_t bounces() const { return record_.bounces(); }

 private:
  void run();

  hal::TriggerLine& line_;
  bool line_records_itself_ = false;
  std::atomic<hal::Nanoseconds> period_;
  hal::TriggerRecord record_;
  std::atomic<std::uint64_t> losses_{0};
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace epipole::firmware

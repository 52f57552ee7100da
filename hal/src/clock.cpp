#include "epipole/hal/clock.hpp"

#include <algorithm>
#include <cerrno>
#include <ctime>

#include "epipole/core/error.hpp"

namespace epipole::hal {

namespace {
constexpr Nanoseconds kPerSecond = 1'000'000'000;
}

Nanoseconds MonotonicClock::now() const {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<Nanoseconds>(ts.tv_sec) * kPerSecond + ts.tv_nsec;
}

void MonotonicClock::sleep_until(Nanoseconds deadline) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline / kPerSecond);
  ts.tv_nsec = static_cast<long>(deadline % kPerSecond);
  // clock_nanosleep returns the error number; EINTR (a signal) just means sleep again.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

Nanoseconds VirtualClock::now() const {
  const std::lock_guard lock(mutex_);
  charge_host_time();
  return now_;
}

void VirtualClock::sleep_until(Nanoseconds deadline) {
  const std::lock_guard lock(mutex_);
  charge_host_time();
  now_ = std::max(now_, deadline);
}

void VirtualClock::advance(Nanoseconds delta) {
  require(delta >= 0, "a virtual clock cannot go back (advance by ", delta, " ns)");
  const std::lock_guard lock(mutex_);
  charge_host_time();
  now_ += delta;
}

void VirtualClock::charge_compute(bool on) {
  const std::lock_guard lock(mutex_);
  charge_compute_ = on;
  host_charged_until_ = MonotonicClock().now();
}

void VirtualClock::charge_host_time() const {
  if (!charge_compute_) return;
  const Nanoseconds host = MonotonicClock().now();
  now_ += host - host_charged_until_;
  host_charged_until_ = host;
}

}  // namespace epipole::hal

#include "epipole/hal/clock.hpp"

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

void VirtualClock::sleep_until(Nanoseconds deadline) {
  Nanoseconds current = now_.load(std::memory_order_acquire);
  while (current < deadline &&
         !now_.compare_exchange_weak(current, deadline, std::memory_order_acq_rel)) {
  }
}

void VirtualClock::spend(Nanoseconds elapsed) {
  if (charge_compute_ && elapsed > 0) advance(elapsed);
}

void VirtualClock::advance(Nanoseconds delta) {
  require(delta >= 0, "a virtual clock cannot go back (advance by ", delta, " ns)");
  now_.fetch_add(delta, std::memory_order_acq_rel);
}

}  // namespace epipole::hal

#pragma once

#include <atomic>
#include <cstdint>

namespace epipole::hal {

// Nanoseconds on CLOCK_MONOTONIC (or on a virtual clock in simulation): the time base of
// trigger edges, frame timestamps and latencies.
using Nanoseconds = std::int64_t;

class Clock {
 public:
  virtual ~Clock() = default;
  virtual Nanoseconds now() const = 0;
  // Blocks until now() >= deadline (returns at once if it already is).
  virtual void sleep_until(Nanoseconds deadline) = 0;
};

// CLOCK_MONOTONIC: the same clock the kernel stamps V4L2 buffers and GPIO edge events with.
class MonotonicClock final : public Clock {
 public:
  Nanoseconds now() const override;
  void sleep_until(Nanoseconds deadline) override;
};

// Simulated time that only moves when told to: sleep_until jumps straight to the deadline, so
// a simulated hour of frames runs as fast as the host can compute them, deterministically.
class VirtualClock final : public Clock {
 public:
  explicit VirtualClock(Nanoseconds start = 0) : now_(start) {}
  Nanoseconds now() const override { return now_.load(std::memory_order_acquire); }
  void sleep_until(Nanoseconds deadline) override;
  void advance(Nanoseconds delta);

 private:
  std::atomic<Nanoseconds> now_;
};

}  // namespace epipole::hal

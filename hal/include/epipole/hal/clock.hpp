#pragma once

#include <cstdint>
#include <mutex>

namespace epipole::hal {

// Nanoseconds on CLOCK_MONOTONIC (or on a virtual clock in simulation): the time base of
// trigger edges, frame timestamps and latencies.
using Nanoseconds = std::int64_t;

// The clock a timestamp was taken on: a frame's and a trigger edge's say it, and times are only
// compared on one clock (a V4L2 driver may stamp on another: `other`).
enum class ClockId { monotonic, virtual_clock, other };

class Clock {
 public:
  virtual ~Clock() = default;
  virtual Nanoseconds now() const = 0;
  // Blocks until now() >= deadline (returns at once if it already is).
  virtual void sleep_until(Nanoseconds deadline) = 0;
  // Which clock this is, to compare with the clock a timestamp says it was taken on.
  virtual ClockId id() const = 0;
};

// CLOCK_MONOTONIC: the same clock the kernel stamps V4L2 buffers and GPIO edge events with.
class MonotonicClock final : public Clock {
 public:
  Nanoseconds now() const override;
  void sleep_until(Nanoseconds deadline) override;
  ClockId id() const override { return ClockId::monotonic; }
};

// Simulated time that only moves when told to: sleep_until jumps straight to the deadline, so
// a simulated hour of frames runs as fast as the host can compute them, deterministically.
// Charging compute time, the host's time also passes on it between those jumps: whatever the
// firmware does outside its waits takes as long as on the host, so a simulation sees the host's
// speed (not deterministic then).
class VirtualClock final : public Clock {
 public:
  explicit VirtualClock(Nanoseconds start = 0) : now_(start) {}
  Nanoseconds now() const override;
  void sleep_until(Nanoseconds deadline) override;
  void advance(Nanoseconds delta);
  // Off unless asked for; set before the clock is shared between threads.
  void charge_compute(bool on);
  ClockId id() const override { return ClockId::virtual_clock; }

 private:
  // Adds the host's time since the last charge (when charging); mutex_ held.
  void charge_host_time() const;
  mutable std::mutex mutex_;
  mutable Nanoseconds now_;
  mutable Nanoseconds host_charged_until_ = 0;
  bool charge_compute_ = false;
};

}  // namespace epipole::hal

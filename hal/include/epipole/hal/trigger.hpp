#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

#include "epipole/hal/clock.hpp"

namespace epipole::hal {

// One trigger pulse: its sequence number (from 0 at start) and the time of its rising edge.
struct TriggerEdge {
  std::uint32_t sequence = 0;
  Nanoseconds timestamp = 0;
  ClockId clock = ClockId::monotonic;  // the clock `timestamp` was taken on
};

enum class TriggerRole {
  master,  // drives the line: pulses of pulse_width at rate_hz from a timer
  slave,   // listens: rising edges with kernel timestamps
};

struct TriggerConfig {
  std::string line;  // a GPIO line name ("CAM_TRIGGER"); "sim" for the simulated board
  std::string chip;  // optional gpiochip; empty: search all chips for the line name
  TriggerRole role = TriggerRole::master;
  double rate_hz = 30.0;
  Nanoseconds pulse_width = 1'000'000;
};

// Throws Error naming the line and the setting when the configuration cannot be valid.
void validate(const TriggerConfig& config);
// The configuration with another rate, checked as validate() checks it (0 < rate <= 1000 Hz,
// the pulse width fits the period); a slave line cannot change its rate (the master sets it).
// Throws Error naming the line and the rate.
TriggerConfig with_rate(const TriggerConfig& config, double rate_hz);
// The period of a rate, rounded to the nanosecond.
Nanoseconds period_of(double rate_hz);

enum class EdgeStatus { ok, timeout, lost };

struct EdgeResult {
  EdgeStatus status = EdgeStatus::timeout;
  TriggerEdge edge;
};

// A trigger line. A master reports the edges it fires; a slave the edges it sees. wait_edge()
// never allocates or throws once started.
class TriggerRecord;

class TriggerLine {
 public:
  virtual ~TriggerLine() = default;
  virtual const TriggerConfig& config() const = 0;
  virtual void start() = 0;
  virtual void stop() = 0;
  virtual EdgeResult wait_edge(Nanoseconds timeout) = 0;
  // Changes the rate, running or not: the edges after the last one fired come at the new
  // period, sequence numbers go on without a gap and times keep increasing; config().rate_hz
  // holds the new rate. Throws Error naming the line and the rate when the rate is impossible
  // (with_rate()); nothing changes then. May be called while another thread waits in
  // wait_edge(); config() belongs to the thread that calls set_rate(). Never allocates.
  virtual void set_rate(double rate_hz) = 0;
  // False while the line cannot be used: not there (yet), or gone with its chip. A hardware
  // line is then looked for again with back-off by wait_edge(), which reports it lost. Both may
  // be called from any thread; the reason allocates, so callers ask for it when available()
  // changes.
  virtual bool available() const { return true; }
  virtual std::string unavailable_reason() const { return {}; }
  // Adds every edge to `record` (null: no more) as it fires, with no thread waiting for them:
  // the simulated trigger, whose edges come as its virtual clock passes them. False for a line
  // that cannot: its edges are waited for with wait_edge().
  virtual bool record_edges_to(TriggerRecord* /*record*/) { return false; }
};

// The edge times of a master line whose rate may change: edge n comes at the time of the
// period it falls in. A rate change re-anchors the schedule at an edge already fired, so that
// sequence numbers stay contiguous and times increase. Remembers the last kSegments rates (for
// edges of an old rate that some reader has not reached yet); fixed memory.
class EdgeSchedule {
 public:
  static constexpr std::size_t kSegments = 8;
  // Edge 0 at `first_edge`, then one every `period`.
  void start(Nanoseconds first_edge, Nanoseconds period);
  // Edges after `anchor` (an edge already fired) come every `period` from its time.
  void change_period(std::uint32_t anchor, Nanoseconds period);
  Nanoseconds time(std::uint32_t sequence) const;
  // The number of edges at or before `t`.
  std::uint32_t edges_until(Nanoseconds t) const;
  Nanoseconds period() const { return newest().period; }
  // The oldest sequence whose time is still known (older rates are forgotten).
  std::uint32_t oldest() const { return segments_[first_].first; }

 private:
  struct Segment {
    std::uint32_t first = 0;  // the sequence of ...
    Nanoseconds time = 0;     // ... this edge, from which edges come every
    Nanoseconds period = 1;
  };
  const Segment& newest() const { return segments_[(first_ + count_ - 1) % kSegments]; }
  std::array<Segment, kSegments> segments_{};
  std::size_t first_ = 0, count_ = 1;
};

// The recent edges of a trigger line: written by whoever waits on the line (the master's timer,
// a slave's edge events, the simulated board's trigger) and read by the stereo pairer, which
// gives every pair the edge at its frames' time. The record numbers the edges itself, one after
// the other in the order they come, whatever the line called them: a master that woke late and
// skipped a slot, or a slave that counted a bounce, leaves no gap and no extra number. An edge
// less than `min_gap` after the edge before it (on the same clock) is a bounce: ignored and
// counted. Holds the last kCapacity edges in fixed memory; add() and the look-ups never allocate
// and may run on different threads.
class TriggerRecord {
 public:
  static constexpr std::size_t kCapacity = 64;
  // The gap below which an edge is a bounce (0: none is). The firmware sets a quarter of the
  // trigger period (TriggerWatch).
  void set_min_gap(Nanoseconds min_gap);
  // Takes an edge (its sequence is replaced by the record's next number); false for a bounce.
  bool add(const TriggerEdge& edge);
  // The edge of that number, while it is among the last kCapacity.
  std::optional<TriggerEdge> find(std::uint32_t sequence) const;
  // The edge nearest `time` (a time on `clock`), when one of the last kCapacity taken on that
  // clock lies within `tolerance` of it.
  std::optional<TriggerEdge> find_near(Nanoseconds time, Nanoseconds tolerance,
                                       ClockId clock) const;
  // The newest edge at or before `time` on `clock`, among the last kCapacity.
  std::optional<TriggerEdge> latest_at(Nanoseconds time, ClockId clock) const;
  // The time of the newest edge taken on `clock` (nullopt: none yet).
  std::optional<Nanoseconds> newest(ClockId clock) const;
  // Edges taken (not counting bounces), and bounces ignored, since the start.
  std::uint64_t added() const;
  std::uint64_t bounces() const;

 private:
  struct Slot {
    TriggerEdge edge;
    bool valid = false;
  };
  mutable std::mutex mutex_;
  std::array<Slot, kCapacity> slots_{};
  std::uint64_t added_ = 0;
  std::uint64_t bounces_ = 0;
  Nanoseconds min_gap_ = 0;
  std::optional<TriggerEdge> last_;
};

}  // namespace epipole::hal

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

enum class EdgeStatus { ok, timeout, lost };

struct EdgeResult {
  EdgeStatus status = EdgeStatus::timeout;
  TriggerEdge edge;
};

// A trigger line. A master reports the edges it fires; a slave the edges it sees. wait_edge()
// never allocates or throws once started.
class TriggerLine {
 public:
  virtual ~TriggerLine() = default;
  virtual const TriggerConfig& config() const = 0;
  virtual void start() = 0;
  virtual void stop() = 0;
  virtual EdgeResult wait_edge(Nanoseconds timeout) = 0;
};

// The recent edges of a trigger line: written by whoever waits on the line (the master's timer,
// a slave's edge events, the simulated board's trigger) and read by the stereo pairer, which
// checks every pair against the trigger's own sequence and time. Holds the last kCapacity
// edges in fixed memory; add() and find() never allocate and may run on different threads.
class TriggerRecord {
 public:
  static constexpr std::size_t kCapacity = 64;
  void add(const TriggerEdge& edge);
  // The edge of that sequence, while it is among the last kCapacity.
  std::optional<TriggerEdge> find(std::uint32_t sequence) const;
  std::uint64_t added() const;
  void clear();

 private:
  struct Slot {
    TriggerEdge edge;
    bool valid = false;
  };
  mutable std::mutex mutex_;
  std::array<Slot, kCapacity> slots_{};
  std::uint64_t added_ = 0;
};

}  // namespace epipole::hal

#pragma once

#include <cstdint>
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

}  // namespace epipole::hal

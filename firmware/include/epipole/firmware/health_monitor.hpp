#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>

#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/trigger_ledger.hpp"

namespace epipole::firmware {

// Per-stage processing times of one frame pair, nanoseconds (protocol::Stage order).
using StageTimes = std::array<hal::Nanoseconds, protocol::kStageCount>;

// The fault counters the health message reports, read from the board each second (totals
// since start; the message carries them modulo 2^32).
struct FaultCounts {
  hal::TriggerAccount triggers;  // what became of every trigger up to the newest pair
  std::uint64_t camera_timeouts = 0;
  std::uint64_t camera_reopens = 0;
  std::uint64_t trigger_losses = 0;
  std::uint64_t link_reopens = 0;
  std::uint64_t unpaired_frames = 0;
  std::uint64_t bad_commands = 0;
  std::uint64_t messages_dropped = 0;
  std::uint64_t snapshot_failures = 0;
  std::uint64_t trigger_bounces = 0;
  std::uint64_t pairs_off_trigger = 0;
  std::uint64_t outputs_dropped = 0;
  std::uint64_t output_failures = 0;
};

// Collects what the health message says: frames per second, the latency from trigger edge to
// publishing and the wait of pairs for the frame loop (50th and 99th percentile each), the mean
// time of each stage and the share of the window spent on pairs (the total stage), over windows
// of one second on the board's clock. Fixed memory: room for `max_frames_per_window` latencies
// and waits is allocated by the constructor (later frames of a window still count, but only the
// first ones enter the percentiles); record() and due() never allocate.
class HealthMonitor {
 public:
  explicit HealthMonitor(hal::Nanoseconds start, int max_frames_per_window = 1024,
                         hal::Nanoseconds window = 1'000'000'000);

  // `wait`: from the later of the pair's two frames to the start of its processing.
  void record(hal::Nanoseconds latency, const StageTimes& stages, hal::Nanoseconds wait = 0);
  // When a window has ended by `now`: its health message (and a new window starts).
  std::optional<protocol::Health> due(hal::Nanoseconds now, const FaultCounts& faults);

  std::uint64_t frames() const { return frames_; }
  std::size_t working_set_bytes() const {
    return 2 * static_cast<std::size_t>(capacity_) * sizeof(hal::Nanoseconds);
  }

 private:
  hal::Nanoseconds start_;
  hal::Nanoseconds window_;
  hal::Nanoseconds window_start_;
  std::unique_ptr<hal::Nanoseconds[]> latencies_;
  std::unique_ptr<hal::Nanoseconds[]> waits_;
  int capacity_;
  int count_ = 0;  // latencies and waits stored this window
  int window_frames_ = 0;
  StageTimes stage_sums_{};
  std::uint64_t frames_ = 0;
};

}  // namespace epipole::firmware

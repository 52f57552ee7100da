#include "epipole/firmware/health_monitor.hpp"

#include <algorithm>
#include <limits>

#include "epipole/core/error.hpp"
#include "wire_units.hpp"

namespace epipole::firmware {

using detail::saturate;
using detail::to_us;

namespace {
// A total since start as the message carries it: modulo 2^32.
std::uint32_t wrapped(std::uint64_t total) {
  return static_cast<std::uint32_t>(total);
}

// The nearest-rank percentile of the first `count` values (reordered), in microseconds.
std::uint32_t percentile_us(hal::Nanoseconds* values, int count, int percent) {
  const int k = std::max(0, (count * percent + 99) / 100 - 1);
  std::nth_element(values, values + k, values + count);
  return to_us(values[k]);
}
}  // namespace

HealthMonitor::HealthMonitor(hal::Nanoseconds start, int max_frames_per_window,
                             hal::Nanoseconds window)
    : start_(start), window_(window), window_start_(start), capacity_(max_frames_per_window) {
  require(max_frames_per_window >= 1, "health: room for at least one frame per window is needed");
  require(window > 0, "health: the window must be positive");
  latencies_ = std::make_unique<hal::Nanoseconds[]>(static_cast<std::size_t>(capacity_));
  waits_ = std::make_unique<hal::Nanoseconds[]>(static_cast<std::size_t>(capacity_));
}

void HealthMonitor::record(hal::Nanoseconds latency, const StageTimes& stages,
                           hal::Nanoseconds wait) {
  if (count_ < capacity_) {
    latencies_[static_cast<std::size_t>(count_)] = latency;
    waits_[static_cast<std::size_t>(count_)] = std::max<hal::Nanoseconds>(wait, 0);
    ++count_;
  }
  for (std::size_t i = 0; i < stages.size(); ++i) stage_sums_[i] += stages[i];
  ++window_frames_;
  ++frames_;
}

std::optional<protocol::Health> HealthMonitor::due(hal::Nanoseconds now, const FaultCounts& f) {
  if (now - window_start_ < window_) return std::nullopt;
  protocol::Health h;
  h.uptime_ms = wrapped(static_cast<std::uint64_t>(now - start_) / 1'000'000);
  h.frames = wrapped(frames_);
  h.dropped = wrapped(f.triggers.dropped());
  h.dropped_stale = wrapped(f.triggers.stale);
  h.dropped_one_side = wrapped(f.triggers.one_side);
  h.dropped_both_sides = wrapped(f.triggers.both_sides);
  h.dropped_corrupt = wrapped(f.triggers.corrupt);
  // Frames per second over the window's nominal length (the window is checked when a frame
  // arrives, a little after it ended), or over the real time after a stall.
  const bool stalled = now - window_start_ >= 2 * window_;
  const hal::Nanoseconds length = stalled ? now - window_start_ : window_;
  const double seconds = static_cast<double>(length) * 1e-9;
  h.fps_centi = saturate<std::uint16_t>(
      static_cast<std::uint64_t>(static_cast<double>(window_frames_) * 100.0 / seconds + 0.5));
  if (count_ > 0) {
    h.latency_p50_us = percentile_us(latencies_.get(), count_, 50);
    h.latency_p99_us = percentile_us(latencies_.get(), count_, 99);
    h.wait_p50_us = percentile_us(waits_.get(), count_, 50);
    h.wait_p99_us = percentile_us(waits_.get(), count_, 99);
  }
  // Busy: the pairs' total (processing and publishing) over the window; a pair that began in the
  // window before counts here, so a saturated loop can exceed the window by a little.
  const hal::Nanoseconds busy = stage_sums_[static_cast<std::size_t>(protocol::Stage::total)];
  h.busy_permille = static_cast<std::uint16_t>(std::min<hal::Nanoseconds>(
      1000, std::max<hal::Nanoseconds>(busy, 0) * 1000 / std::max<hal::Nanoseconds>(length, 1)));
  if (window_frames_ > 0) {
    for (std::size_t i = 0; i < stage_sums_.size(); ++i) {
      h.stage_us[i] = to_us(stage_sums_[i] / window_frames_);
    }
  }
  h.camera_timeouts = wrapped(f.camera_timeouts);
  h.camera_reopens = wrapped(f.camera_reopens);
  h.trigger_losses = wrapped(f.trigger_losses);
  h.link_reopens = wrapped(f.link_reopens);
  h.unpaired_frames = wrapped(f.unpaired_frames);
  h.bad_commands = wrapped(f.bad_commands);
  h.messages_dropped = wrapped(f.messages_dropped);
  h.snapshot_failures = wrapped(f.snapshot_failures);
  h.trigger_bounces = wrapped(f.trigger_bounces);
  h.pairs_off_trigger = wrapped(f.pairs_off_trigger);
  h.outputs_dropped = wrapped(f.outputs_dropped);
  h.output_failures = wrapped(f.output_failures);
  // The next window starts where this one should have ended, so windows do not drift; after a
  // long gap (a stall) it starts now.
  window_start_ = stalled ? now : window_start_ + window_;
  count_ = 0;
  window_frames_ = 0;
  stage_sums_.fill(0);
  return h;
}

}  // namespace epipole::firmware

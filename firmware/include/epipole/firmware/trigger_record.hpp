#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <thread>

#include "epipole/hal/trigger.hpp"

namespace epipole::firmware {

// The recent edges of the board's trigger line, so that every result can carry the time of the
// trigger that exposed its frames. On hardware a thread of its own waits for the edges (a
// master fires them as it waits; a slave is told of them by the kernel); on the simulated board
// the frame loop collects them (poll()), as the virtual clock passes them. Fixed memory.
class TriggerRecord {
 public:
  // `threaded`: a thread of the record's own waits for edges (hardware); otherwise poll().
  TriggerRecord(hal::TriggerLine& line, bool threaded, hal::Nanoseconds period);
  ~TriggerRecord();
  TriggerRecord(const TriggerRecord&) = delete;
  TriggerRecord& operator=(const TriggerRecord&) = delete;

  void start();
  void stop();
  // Takes the edges that have passed (simulated board).
  void poll();
  // The edge of a trigger sequence, if it is among the recent ones.
  std::optional<hal::TriggerEdge> find(std::uint32_t sequence) const;

  std::uint64_t edges() const { return edges_.load(); }
  // Times the line went quiet for more than three periods, or reported itself lost.
  std::uint64_t losses() const { return losses_.load(); }

 private:
  void note(const hal::EdgeResult& r, hal::Nanoseconds now);
  void run();

  hal::TriggerLine& line_;
  bool threaded_;
  hal::Nanoseconds period_;
  static constexpr std::size_t kEdges = 64;
  mutable std::mutex mutex_;
  std::array<hal::TriggerEdge, kEdges> ring_{};
  std::size_t next_ = 0;
  std::size_t size_ = 0;
  std::atomic<std::uint64_t> edges_{0};
  std::atomic<std::uint64_t> losses_{0};
  hal::Nanoseconds last_edge_ = 0;
  bool quiet_ = false;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace epipole::firmware

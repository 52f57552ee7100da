#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include "epipole/hal/clock.hpp"
#include "epipole/hal/recovery.hpp"
#include "epipole/hal/trigger.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace epipole::hal {

// The trigger line through libgpiod's 1.x API (Debian bookworm: 1.6), the line looked up by
// name (in config.chip when given, else on every chip) when it starts. A line that is not there
// (its chip's driver not loaded yet, a GPIO expander unplugged) or that cannot be requested is
// no error: wait_edge() reports it lost and looks for it again with back-off, and a line whose
// chip goes away while in use is given back and looked for the same way; available() and
// unavailable_reason() say so. A master drives the line: wait_edge()
// sleeps on the monotonic clock to the next period, raises the line for pulse_width and reports
// the edge. A slave requests rising-edge events and reports each with the kernel's timestamp.
// set_rate() (a master only) may come from another thread while one waits in wait_edge(): the
// new period is an atomic that wait_edge() reads before each edge, re-anchoring the schedule at
// the last edge it fired.
// libgpiod 2.x has a different API; it would be another class behind the same TriggerLine.
// Built only when the libgpiod 1.x headers and library are found (epipole_hal_gpiod).
class GpiodTrigger final : public TriggerLine {
 public:
  explicit GpiodTrigger(TriggerConfig config);
  ~GpiodTrigger() override;
  GpiodTrigger(const GpiodTrigger&) = delete;
  GpiodTrigger& operator=(const GpiodTrigger&) = delete;

  const TriggerConfig& config() const override { return config_; }
  void start() override;
  void stop() override;
  EdgeResult wait_edge(Nanoseconds timeout) override;
  void set_rate(double rate_hz) override;
  bool available() const override { return requested_.load(std::memory_order_acquire); }
  std::string unavailable_reason() const override;

 private:
  // Finds the line and requests it; on failure keeps the reason and schedules the next try.
  bool acquire();
  // Looks for the line on every chip that opens; keeps the reason when it is on none.
  bool find_on_any_chip();
  // Gives the line back and closes its chip (it may be gone).
  void release(const char* reason);
  void set_reason(std::string reason);
  // A read or write on the line failed (its chip removed): released, looked for again later.
  EdgeResult line_went_away();

  TriggerConfig config_;
  struct CloseChip {
    void operator()(gpiod_chip* chip) const;
  };
  using Chip = std::unique_ptr<gpiod_chip, CloseChip>;
  Chip chip_;                   // the chip of line_
  gpiod_line* line_ = nullptr;  // the chip's: gone with it
  bool started_ = false;
  std::atomic<bool> requested_{false};
  Backoff backoff_;
  mutable std::mutex reason_mutex_;
  std::string reason_;  // why the line is not requested
  MonotonicClock clock_;
  std::atomic<Nanoseconds> period_;  // written by set_rate(), read by wait_edge()
  EdgeSchedule schedule_;            // wait_edge()'s thread only
  std::uint32_t next_ = 0;           // the number of the next edge fired or seen
  std::uint32_t slot_ = 0;  // a master's next slot of the schedule (a late wake-up skips slots)
};

}  // namespace epipole::hal

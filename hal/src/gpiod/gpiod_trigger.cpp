#include "gpiod/gpiod_trigger.hpp"

#include <gpiod.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <memory>
#include <utility>
#include <vector>

#include "backends.hpp"
#include "epipole/core/error.hpp"
#include "epipole/hal/registry.hpp"

namespace epipole::hal {

namespace {
constexpr const char* kConsumer = "epipole-trigger";
constexpr Nanoseconds kPerSecond = 1'000'000'000;
}  // namespace

GpiodTrigger::GpiodTrigger(TriggerConfig config) : config_(std::move(config)) {
  validate(config_);
  period_ = period_of(config_.rate_hz);
  reason_.reserve(256);
  set_reason("not started");
}

GpiodTrigger::~GpiodTrigger() {
  stop();
}

std::string GpiodTrigger::unavailable_reason() const {
  const std::lock_guard lock(reason_mutex_);
  return requested_.load(std::memory_order_acquire) ? std::string() : reason_;
}

void GpiodTrigger::set_reason(std::string reason) {
  const std::lock_guard lock(reason_mutex_);
  reason_ = std::move(reason);
}

bool GpiodTrigger::find_on_any_chip() {
  // libgpiod's own search (gpiod_line_find) fails as soon as one chip does not open, and a
  // service user is given only the chips its board uses (the udev rules): those that do not
  // open are skipped and counted.
  std::vector<std::filesystem::path> chips;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    if (entry.path().filename().string().starts_with("gpiochip")) chips.push_back(entry.path());
  }
  std::sort(chips.begin(), chips.end());
  int closed = 0;
  std::string why;
  for (const std::filesystem::path& path : chips) {
    Chip chip(gpiod_chip_open(path.c_str()));
    if (!chip) {
      ++closed;
      why = std::strerror(errno);
      continue;
    }
    if (gpiod_line* line = gpiod_chip_find_line(chip.get(), config_.line.c_str());
        line != nullptr) {
      chip_ = std::move(chip);
      line_ = line;
      return true;
    }
  }
  set_reason(cat("no GPIO line of that name on any chip",
                 closed > 0 ? cat(" (", closed, " of ", chips.size(), " chips do not open: ", why,
                                  "; the udev rules give the board's chips to the gpio group)")
                            : ""));
  return false;
}

void GpiodTrigger::CloseChip::operator()(gpiod_chip* chip) const {
  gpiod_chip_close(chip);
}

bool GpiodTrigger::acquire() {
  errno = 0;
  if (config_.chip.empty()) {
    find_on_any_chip();
  } else {
    chip_.reset(gpiod_chip_open_lookup(config_.chip.c_str()));
    if (!chip_) {
      set_reason(cat("cannot open GPIO chip ", config_.chip, ": ", std::strerror(errno)));
    } else if (line_ = gpiod_chip_find_line(chip_.get(), config_.line.c_str()); line_ == nullptr) {
      set_reason(cat("no GPIO line of that name on ", config_.chip));
    }
  }
  const Nanoseconds now = clock_.now();
  if (line_ != nullptr) {
    const int r = config_.role == TriggerRole::master
                      ? gpiod_line_request_output(line_, kConsumer, 0)
                      : gpiod_line_request_rising_edge_events(line_, kConsumer);
    if (r == 0) {
      // Edge numbers go on from where they were: a master's schedule puts the next slot now.
      const Nanoseconds period = period_.load(std::memory_order_acquire);
      schedule_.start(now - static_cast<Nanoseconds>(slot_) * period, period);
      backoff_.succeeded();
      requested_.store(true, std::memory_order_release);
      return true;
    }
    set_reason(cat("cannot request the line as ",
                   config_.role == TriggerRole::master ? "output" : "rising-edge input", ": ",
                   std::strerror(errno)));
  }
  release(nullptr);
  backoff_.failed(now);
  return false;
}

void GpiodTrigger::release(const char* reason) {
  if (reason != nullptr) set_reason(cat("the line went away: ", reason));
  if (requested_.exchange(false, std::memory_order_acq_rel)) gpiod_line_release(line_);
  line_ = nullptr;  // the chip's
  chip_.reset();
}

EdgeResult GpiodTrigger::line_went_away() {
  release(std::strerror(errno));
  backoff_.failed(clock_.now());
  return {EdgeStatus::lost, {}};
}

void GpiodTrigger::start() {
  if (started_) return;
  started_ = true;
  next_ = 0;
  slot_ = 0;
  backoff_.succeeded();
  acquire();
}

void GpiodTrigger::set_rate(double rate_hz) {
  // Only rate_hz is written: the waiting thread reads the role and the pulse width.
  config_.rate_hz = with_rate(config_, rate_hz).rate_hz;
  period_.store(period_of(rate_hz), std::memory_order_release);
}

void GpiodTrigger::stop() {
  if (!started_) return;
  started_ = false;
  release(nullptr);
  set_reason("stopped");
}

EdgeResult GpiodTrigger::wait_edge(Nanoseconds timeout) {
  timeout = std::max<Nanoseconds>(timeout, 0);
  if (!requested_.load(std::memory_order_relaxed)) {
    if (!started_) return {EdgeStatus::lost, {}};
    const Nanoseconds now = clock_.now();
    if (!backoff_.due(now) || !acquire()) {
      clock_.sleep_until(std::min(now + timeout, backoff_.next_attempt()));
      return {EdgeStatus::lost, {}};
    }
  }
  if (config_.role == TriggerRole::master) {
    const Nanoseconds period = period_.load(std::memory_order_acquire);
    if (period != schedule_.period()) {  // set_rate(): from the last edge fired on
      schedule_.change_period(slot_ == 0 ? 0 : slot_ - 1, period);
    }
    const Nanoseconds now = clock_.now();
    Nanoseconds edge = schedule_.time(slot_);
    if (edge < now) {
      // Late: the missed slots are skipped instead of fired in a burst; the edges' numbers have
      // no gap (an edge never fired is no trigger that was lost).
      slot_ += static_cast<std::uint32_t>((now - edge + period - 1) / period);
      edge = schedule_.time(slot_);
    }
    if (edge > now + timeout) {
      clock_.sleep_until(now + timeout);
      return {EdgeStatus::timeout, {}};
    }
    clock_.sleep_until(edge);
    if (gpiod_line_set_value(line_, 1) != 0) return line_went_away();
    const Nanoseconds fired = clock_.now();
    clock_.sleep_until(fired + config_.pulse_width);
    if (gpiod_line_set_value(line_, 0) != 0) return line_went_away();
    ++slot_;
    return {EdgeStatus::ok, TriggerEdge{next_++, fired, ClockId::monotonic}};
  }
  const timespec ts{static_cast<time_t>(timeout / kPerSecond),
                    static_cast<long>(timeout % kPerSecond)};
  const int r = gpiod_line_event_wait(line_, &ts);
  if (r == 0) return {EdgeStatus::timeout, {}};
  gpiod_line_event event{};
  if (r < 0 || gpiod_line_event_read(line_, &event) != 0) return line_went_away();
  const Nanoseconds stamp = static_cast<Nanoseconds>(event.ts.tv_sec) * kPerSecond +
                            static_cast<Nanoseconds>(event.ts.tv_nsec);
  // The kernel stamps line events on CLOCK_MONOTONIC (since Linux 5.7, older than any kernel of a
  // supported board: earlier ones used the real-time clock).
  return {EdgeStatus::ok, TriggerEdge{next_++, stamp, ClockId::monotonic}};
}

void register_gpiod(BackendRegistry& registry) {
  registry.add_trigger("gpiod", [](const TriggerConfig& config, const BackendContext&) {
    return std::unique_ptr<TriggerLine>(std::make_unique<GpiodTrigger>(config));
  });
}

}  // namespace epipole::hal

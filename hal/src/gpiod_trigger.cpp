#include "epipole/hal/gpiod_trigger.hpp"

#include <gpiod.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <memory>

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
  if (config_.chip.empty()) {
    line_ = gpiod_line_find(config_.line.c_str());
    if (line_ == nullptr) {
      throw Error(cat("trigger ", config_.line, ": no GPIO line of that name on any chip",
                      errno != 0 && errno != ENOENT ? cat(" (", std::strerror(errno), ")") : ""));
    }
  } else {
    chip_ = gpiod_chip_open_lookup(config_.chip.c_str());
    if (chip_ == nullptr) {
      throw Error(cat("trigger ", config_.line, ": cannot open GPIO chip ", config_.chip, ": ",
                      std::strerror(errno)));
    }
    line_ = gpiod_chip_find_line(chip_, config_.line.c_str());
    if (line_ == nullptr) {
      gpiod_chip_close(chip_);
      chip_ = nullptr;
      throw Error(cat("trigger ", config_.line, ": no GPIO line of that name on ", config_.chip));
    }
  }
}

GpiodTrigger::~GpiodTrigger() {
  stop();
  if (chip_ != nullptr) {
    gpiod_chip_close(chip_);
  } else if (line_ != nullptr) {
    gpiod_line_close_chip(line_);
  }
}

void GpiodTrigger::start() {
  if (requested_) return;
  const int r = config_.role == TriggerRole::master
                    ? gpiod_line_request_output(line_, kConsumer, 0)
                    : gpiod_line_request_rising_edge_events(line_, kConsumer);
  if (r != 0) {
    throw Error(cat("trigger ", config_.line, ": cannot request the line as ",
                    config_.role == TriggerRole::master ? "output" : "rising-edge input", ": ",
                    std::strerror(errno)));
  }
  requested_ = true;
  schedule_.start(clock_.now(), period_.load(std::memory_order_acquire));
  next_ = 0;
}

void GpiodTrigger::set_rate(double rate_hz) {
  // Only rate_hz is written: the waiting thread reads the role and the pulse width.
  config_.rate_hz = with_rate(config_, rate_hz).rate_hz;
  period_.store(period_of(rate_hz), std::memory_order_release);
}

void GpiodTrigger::stop() {
  if (!requested_) return;
  gpiod_line_release(line_);
  requested_ = false;
}

EdgeResult GpiodTrigger::wait_edge(Nanoseconds timeout) {
  if (!requested_) return {EdgeStatus::lost, {}};
  timeout = std::max<Nanoseconds>(timeout, 0);
  if (config_.role == TriggerRole::master) {
    const Nanoseconds period = period_.load(std::memory_order_acquire);
    if (period != schedule_.period()) {  // set_rate(): from the last edge fired on
      schedule_.change_period(next_ == 0 ? 0 : next_ - 1, period);
    }
    const Nanoseconds now = clock_.now();
    Nanoseconds edge = schedule_.time(next_);
    if (edge < now) {  // late: skip the missed periods instead of firing a burst
      next_ += static_cast<std::uint32_t>((now - edge + period - 1) / period);
      edge = schedule_.time(next_);
    }
    if (edge > now + timeout) {
      clock_.sleep_until(now + timeout);
      return {EdgeStatus::timeout, {}};
    }
    clock_.sleep_until(edge);
    if (gpiod_line_set_value(line_, 1) != 0) return {EdgeStatus::lost, {}};
    const Nanoseconds fired = clock_.now();
    clock_.sleep_until(fired + config_.pulse_width);
    if (gpiod_line_set_value(line_, 0) != 0) return {EdgeStatus::lost, {}};
    return {EdgeStatus::ok, TriggerEdge{next_++, fired}};
  }
  const timespec ts{static_cast<time_t>(timeout / kPerSecond),
                    static_cast<long>(timeout % kPerSecond)};
  const int r = gpiod_line_event_wait(line_, &ts);
  if (r == 0) return {EdgeStatus::timeout, {}};
  gpiod_line_event event{};
  if (r < 0 || gpiod_line_event_read(line_, &event) != 0) return {EdgeStatus::lost, {}};
  const Nanoseconds stamp = static_cast<Nanoseconds>(event.ts.tv_sec) * kPerSecond +
                            static_cast<Nanoseconds>(event.ts.tv_nsec);
  return {EdgeStatus::ok, TriggerEdge{next_++, stamp}};
}

void register_gpiod(BackendRegistry& registry) {
  registry.add_trigger("gpiod", [](const TriggerConfig& config, const BackendContext&) {
    return std::unique_ptr<TriggerLine>(std::make_unique<GpiodTrigger>(config));
  });
}

}  // namespace epipole::hal

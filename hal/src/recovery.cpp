#include "epipole/hal/recovery.hpp"

#include <algorithm>

#include "epipole/core/error.hpp"
#include "epipole/hal/device_missing.hpp"

namespace epipole::hal {

Backoff::Backoff(BackoffConfig config) : config_(config), delay_(config.initial) {
  require(config_.initial > 0 && config_.max >= config_.initial, "back-off: initial delay ",
          config_.initial, " ns and maximum ", config_.max, " ns are impossible");
}

void Backoff::failed(Nanoseconds now) {
  next_attempt_ = now + delay_;
  delay_ = std::min(delay_ * 2, config_.max);
}

void Backoff::succeeded() {
  delay_ = config_.initial;
  next_attempt_ = 0;
}

// ----------------------------------------------------------------------------------------------

RecoveringCamera::RecoveringCamera(CameraSource& camera, Clock& clock, RecoveryConfig config)
    : camera_(camera), clock_(clock), config_(config), backoff_(config.backoff) {
  require(config_.timeouts_before_reopen >= 0, "camera ", camera_.name(),
          ": timeouts before reopen must not be negative");
  last_error_.reserve(256);
}

bool RecoveringCamera::try_reopen() {
  ++counters_.reopen_attempts;
  try {
    camera_.reopen();
    // Backends apply their config() again when they reopen; a camera that came back another
    // way (replaced, reset) gets the run-time values here.
    if (exposure_set_) camera_.set_exposure(exposure_, gain_);
    if (!camera_.streaming()) camera_.start();
  } catch (const Error& e) {
    ++counters_.reopen_failures;
    last_error_ = e.what();  // may allocate, but only on the failure path
    backoff_.failed(clock_.now());
    return false;
  }
  ++counters_.reopens;
  // The back-off is reset by the first frame, not by the reopen: a device that opens but
  // delivers nothing is reopened less and less often.
  backoff_.failed(clock_.now());
  lost_ = false;
  timeouts_in_a_row_ = 0;
  if (partner_ != nullptr && partner_->lost_ && !partner_->defer_reopen_) partner_->try_reopen();
  return true;
}

void RecoveringCamera::pair_with(RecoveringCamera& partner) {
  require(&partner != this, "camera ", name(), " cannot be its own stereo partner");
  partner_ = &partner;
  partner.partner_ = this;
}

bool RecoveringCamera::trigger_was_quiet(Nanoseconds waited_from) const {
  if (trigger_ == nullptr || camera_.config().trigger != TriggerMode::external) return false;
  const std::optional<Nanoseconds> newest = trigger_->newest(clock_.id());
  return !newest || *newest < waited_from;
}

void RecoveringCamera::start() {
  try {
    camera_.start();
  } catch (const DeviceMissing& e) {
    ++counters_.losses;
    last_error_ = e.what();
    lost_ = true;
    delivered_since_reopen_ = false;
    backoff_.failed(clock_.now());  // the first look again after the initial delay
  }
}

void RecoveringCamera::reopen() {
  lost_ = true;
  delivered_since_reopen_ = false;
  if (!try_reopen()) throw Error(last_error_);
}

void RecoveringCamera::set_exposure(Nanoseconds exposure, double gain) {
  camera_.set_exposure(exposure, gain);
  exposure_set_ = true;
  exposure_ = exposure;
  gain_ = gain;
}

AcquireResult RecoveringCamera::acquire(Nanoseconds timeout) {
  const Nanoseconds deadline = clock_.now() + std::max<Nanoseconds>(timeout, 0);
  if (lost_) {
    if (defer_reopen_) return {AcquireStatus::device_lost, {}};
    if (!backoff_.due(clock_.now())) {
      clock_.sleep_until(std::min(deadline, backoff_.next_attempt()));
      if (!backoff_.due(clock_.now())) return {AcquireStatus::device_lost, {}};
    }
    if (!try_reopen()) return {AcquireStatus::device_lost, {}};
  }
  const Nanoseconds waited_from = clock_.now();
  const AcquireResult r = camera_.acquire(std::max<Nanoseconds>(deadline - waited_from, 0));
  switch (r.status) {
    case AcquireStatus::ok:
    case AcquireStatus::corrupt:
      if (r.status == AcquireStatus::corrupt) ++counters_.corrupt;
      timeouts_in_a_row_ = 0;
      if (!delivered_since_reopen_) {
        delivered_since_reopen_ = true;
        backoff_.succeeded();
      }
      return r;
    case AcquireStatus::timeout:
      if (timeout <= 0) return r;  // a poll that found nothing waiting is no fault
      ++counters_.timeouts;
      if (trigger_was_quiet(waited_from)) {  // no edge, no frame: the trigger stopped
        ++counters_.trigger_waits;
        timeouts_in_a_row_ = 0;
        return r;
      }
      if (config_.timeouts_before_reopen == 0 ||
          ++timeouts_in_a_row_ < config_.timeouts_before_reopen) {
        return r;
      }
      break;
    case AcquireStatus::device_lost:
      break;
  }
  ++counters_.losses;
  lost_ = true;
  timeouts_in_a_row_ = 0;
  // A device that delivered since it was last opened is tried again at once; one that did not
  // waits for its back-off, which grows with every reopen that brought no frame.
  if (delivered_since_reopen_) backoff_.succeeded();
  delivered_since_reopen_ = false;
  if (!defer_reopen_ && backoff_.due(clock_.now())) try_reopen();
  return {AcquireStatus::device_lost, {}};
}

// ----------------------------------------------------------------------------------------------

RecoveringSerialPort::RecoveringSerialPort(SerialPort& port, Clock& clock, BackoffConfig config)
    : port_(port), clock_(clock), backoff_(config), connected_(port.is_open()) {}

void RecoveringSerialPort::reopen() {
  try {
    port_.reopen();
  } catch (...) {
    connected_.store(port_.is_open(), std::memory_order_relaxed);  // closed, by contract
    throw;
  }
  connected_.store(true, std::memory_order_relaxed);
}

void RecoveringSerialPort::close() {
  port_.close();
  connected_.store(false, std::memory_order_relaxed);
}

bool RecoveringSerialPort::ensure_open() {
  if (port_.is_open()) return true;
  if (!backoff_.due(clock_.now())) return false;
  ++counters_.reopen_attempts;
  try {
    port_.reopen();
  } catch (const Error&) {
    ++counters_.reopen_failures;
    backoff_.failed(clock_.now());
    return false;
  }
  ++counters_.reopens;
  reopens_.store(counters_.reopens, std::memory_order_relaxed);
  connected_.store(true, std::memory_order_relaxed);
  backoff_.succeeded();
  return true;
}

void RecoveringSerialPort::note(IoStatus status) {
  if (status == IoStatus::timeout) ++counters_.timeouts;
  if (status == IoStatus::hung_up) {
    ++counters_.losses;
    close();
    backoff_.succeeded();
  }
}

IoResult RecoveringSerialPort::read(std::span<std::byte> buffer, Nanoseconds timeout) {
  if (!ensure_open()) return {IoStatus::closed, 0};
  const IoResult r = port_.read(buffer, timeout);
  note(r.status);
  return r;
}

IoResult RecoveringSerialPort::write(std::span<const std::byte> data, Nanoseconds timeout) {
  if (!ensure_open()) return {IoStatus::closed, 0};
  const IoResult r = port_.write(data, timeout);
  note(r.status);
  return r;
}

}  // namespace epipole::hal

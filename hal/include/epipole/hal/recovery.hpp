#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "epipole/hal/camera.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/hal/trigger.hpp"

namespace epipole::hal {

struct BackoffConfig {
  Nanoseconds initial = 100'000'000;  // the first retry after this
  Nanoseconds max = 5'000'000'000;    // the delay doubles up to this
};

// Exponential back-off on a Clock (a VirtualClock in tests).
class Backoff {
 public:
  explicit Backoff(BackoffConfig config = {});
  // The time of the next attempt, after a failure at `now`.
  void failed(Nanoseconds now);
  void succeeded();
  bool due(Nanoseconds now) const { return now >= next_attempt_; }
  Nanoseconds next_attempt() const { return next_attempt_; }
  Nanoseconds current_delay() const { return delay_; }

 private:
  BackoffConfig config_;
  Nanoseconds delay_;
  Nanoseconds next_attempt_ = 0;
};

// Counters for the health message.
struct RecoveryCounters {
  std::uint64_t timeouts = 0;  // acquire (or read) timed out
  // Of the timeouts, those with no trigger edge during the wait (an externally triggered camera
  // that follows a trigger record): the trigger stopped, not the camera. Never a reason to reopen.
  std::uint64_t trigger_waits = 0;
  std::uint64_t corrupt = 0;  // a camera delivered a damaged frame (not a timeout, not a loss)
  std::uint64_t losses = 0;   // the device went away (or too many timeouts in a row)
  std::uint64_t reopen_attempts = 0;
  std::uint64_t reopen_failures = 0;
  std::uint64_t reopens = 0;  // successful
};

struct RecoveryConfig {
  BackoffConfig backoff;
  // This many timeouts in a row count as a lost device (0: timeouts never do).
  int timeouts_before_reopen = 3;
};

// A camera that reopens its device with exponential back-off when it is lost, keeps timing out
// or is not there when it starts, without restarting anything but its partner (pair_with). While it
// is recovering, acquire() waits for the next attempt (at most the timeout) and reports
// device_lost. It is recovering from the loss until a frame comes again (recovering()): a device
// that opens but delivers nothing (it fails every dequeue, or never gets a frame) is lost again at
// once, and each such reopen waits twice as long as the one before, up to the back-off's maximum;
// the first frame resets the back-off. A corrupt frame is counted apart and passed on: the device
// still streams, so it ends a run of timeouts and never makes it reopen. An externally
// triggered camera given the trigger's record (follow_trigger) counts a timeout with no edge
// during the wait as a wait for the trigger, never as a fault: a trigger that stops (an
// autopilot disarmed) reopens nothing. set_exposure() goes to the camera, and the last values
// set are applied again after every reopen.
class RecoveringCamera final : public CameraSource {
 public:
  RecoveringCamera(CameraSource& camera, Clock& clock, RecoveryConfig config = {});
  const std::string& name() const override { return camera_.name(); }
  const CameraConfig& config() const override { return camera_.config(); }
  // A camera that is not there yet (DeviceMissing) starts lost: acquire() waits for it.
  void start() override;
  void stop() override { camera_.stop(); }
  bool streaming() const override { return camera_.streaming(); }
  AcquireResult acquire(Nanoseconds timeout) override;
  void release(const Frame& frame) override { camera_.release(frame); }
  std::optional<Nanoseconds> edge_delay() const override { return camera_.edge_delay(); }
  std::optional<Nanoseconds> shortest_frame_period() const override {
    return camera_.shortest_frame_period();
  }
  std::size_t working_set_bytes() const override { return camera_.working_set_bytes(); }
  void reopen() override;
  void set_exposure(Nanoseconds exposure, double gain) override;

  // While deferred, a loss that acquire() finds is reported (device_lost) but the device is not
  // reopened, nor waited for: a reopen unmaps the buffers of frames lent before it, which their
  // holder may still be reading (the frame loop, looking for the next pair while the current one
  // is processed). The first acquire() after defer_reopen(false) reopens it.
  void defer_reopen(bool defer) { defer_reopen_ = defer; }
  // The edges of the trigger that fires this camera (null: none); it must outlive the camera.
  void follow_trigger(const TriggerRecord* record) { trigger_ = record; }
  // The other camera of the stereo pair (both ways; it must outlive this one). When one of them
  // comes back while the other is lost too (a driver reloaded, a hub that lost power), the other
  // is reopened at once, not at its own back-off: the two streams start back to back, as they did
  // at start-up. Free-running cameras keep the phase they start with, and frames of two streams
  // started a random time apart would never pair within the tolerance.
  void pair_with(RecoveringCamera& partner);

  const RecoveryCounters& counters() const { return counters_; }
  bool recovering() const { return lost_ || !delivered_since_reopen_; }
  const std::string& last_error() const { return last_error_; }

 private:
  bool try_reopen();
  bool trigger_was_quiet(Nanoseconds waited_from) const;

  CameraSource& camera_;
  Clock& clock_;
  RecoveryConfig config_;
  Backoff backoff_;
  RecoveryCounters counters_;
  int timeouts_in_a_row_ = 0;
  bool lost_ = false;
  bool delivered_since_reopen_ = true;  // false from a loss until the next frame
  bool defer_reopen_ = false;
  const TriggerRecord* trigger_ = nullptr;
  RecoveringCamera* partner_ = nullptr;
  bool exposure_set_ = false;  // set_exposure() was called: its values outlive a reopen
  Nanoseconds exposure_ = 0;
  double gain_ = 0.0;
  std::string last_error_;
};

// A serial port that reopens itself after a hang-up, with back-off. read()/write() report
// hung_up (or closed while waiting for the next attempt) and never throw.
class RecoveringSerialPort final : public SerialPort {
 public:
  RecoveringSerialPort(SerialPort& port, Clock& clock, BackoffConfig config = {});
  IoResult read(std::span<std::byte> buffer, Nanoseconds timeout) override;
  IoResult write(std::span<const std::byte> data, Nanoseconds timeout) override;
  bool is_open() const override { return port_.is_open(); }
  void reopen() override;
  void close() override;
  // Only for the thread that reads and writes the port.
  const RecoveryCounters& counters() const { return counters_; }
  // The successful reopens so far, for any thread.
  std::uint64_t reopens() const { return reopens_.load(std::memory_order_relaxed); }
  // Whether the port is open, for any thread (is_open() is for the one that uses the port).
  bool connected() const { return connected_.load(std::memory_order_relaxed); }

 private:
  bool ensure_open();
  void note(IoStatus status);

  SerialPort& port_;
  Clock& clock_;
  Backoff backoff_;
  RecoveryCounters counters_;
  std::atomic<std::uint64_t> reopens_{0};  // counters_.reopens, published to other threads
  std::atomic<bool> connected_;            // port_.is_open(), published to other threads
};

}  // namespace epipole::hal

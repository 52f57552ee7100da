#include "epipole/hal/stereo_pairing.hpp"

#include <algorithm>

#include "epipole/core/error.hpp"

namespace epipole::hal {

StereoPairer::StereoPairer(CameraSource& left, CameraSource& right, PairingConfig config,
                           const TriggerRecord* trigger)
    : left_(left), right_(right), config_(config), trigger_(trigger) {
  require(config_.tolerance >= 0, "stereo pairing (", left_.name(), ", ", right_.name(),
          "): timestamp tolerance ", config_.tolerance, " ns is negative");
  require(config_.trigger_period == 0 || 2 * config_.tolerance < config_.trigger_period,
          "stereo pairing (", left_.name(), ", ", right_.name(), "): timestamp tolerance ",
          config_.tolerance, " ns is not below half the trigger period ", config_.trigger_period,
          " ns, so frames of neighbouring triggers could pair");
  if (trigger_ != nullptr) {
    require(config_.edge_tolerance >= 0, "stereo pairing (", left_.name(), ", ", right_.name(),
            "): edge tolerance ", config_.edge_tolerance, " ns is negative");
    require(config_.trigger_period == 0 || 2 * config_.edge_tolerance < config_.trigger_period,
            "stereo pairing (", left_.name(), ", ", right_.name(), "): edge tolerance ",
            config_.edge_tolerance, " ns is not below half the trigger period ",
            config_.trigger_period, " ns, so a frame could fit two trigger edges");
  }
}

bool StereoPairer::on_trigger(const Frame& left, const Frame& right) const {
  if (trigger_ == nullptr) return true;
  const std::optional<TriggerEdge> edge = trigger_->find(left.sequence);
  if (!edge) return false;
  const Nanoseconds expected = edge->timestamp + config_.edge_delay;
  auto fits = [&](Nanoseconds t) {
    return (t > expected ? t - expected : expected - t) <= config_.edge_tolerance;
  };
  return fits(left.timestamp) && fits(right.timestamp);
}

void StereoPairer::drop_front(Side side, std::uint64_t& counter) {
  Queue& q = queue(side);
  camera(side).release(q.front());
  q.head = (q.head + 1) % kCapacity;
  --q.size;
  ++counter;
}

bool StereoPairer::push(Side side, const Frame& frame) {
  Queue& q = queue(side);
  const bool left = side == Side::left;
  ++(left ? counters_.pushed_left : counters_.pushed_right);
  // A sequence that does not increase is a duplicate or garbled: refuse it.
  if (q.has_last && static_cast<std::int32_t>(frame.sequence - q.last) <= 0) {
    camera(side).release(frame);
    ++(left ? counters_.out_of_order_left : counters_.out_of_order_right);
    return ready_;
  }
  q.has_last = true;
  q.last = frame.sequence;
  if (q.size == kCapacity)
    drop_front(side, left ? counters_.unpaired_left : counters_.unpaired_right);
  q.frames[(q.head + q.size) % kCapacity] = frame;
  ++q.size;
  match();
  return ready_;
}

void StereoPairer::match() {
  while (!ready_ && left_q_.size > 0 && right_q_.size > 0) {
    const Frame& l = left_q_.front();
    const Frame& r = right_q_.front();
    const auto d = static_cast<std::int32_t>(l.sequence - r.sequence);
    if (d < 0) {
      drop_front(Side::left, counters_.unpaired_left);  // right is past it: it cannot pair
    } else if (d > 0) {
      drop_front(Side::right, counters_.unpaired_right);
    } else {
      const Nanoseconds dt =
          l.timestamp > r.timestamp ? l.timestamp - r.timestamp : r.timestamp - l.timestamp;
      if (dt > config_.tolerance || l.clock != r.clock) {
        drop_front(Side::left, counters_.mismatched_left);
        drop_front(Side::right, counters_.mismatched_right);
        continue;
      }
      if (!on_trigger(l, r)) {
        drop_front(Side::left, counters_.off_trigger_left);
        drop_front(Side::right, counters_.off_trigger_right);
        continue;
      }
      pair_ = {l, r};
      left_q_.head = (left_q_.head + 1) % kCapacity;
      --left_q_.size;
      right_q_.head = (right_q_.head + 1) % kCapacity;
      --right_q_.size;
      ready_ = true;
      ++counters_.pairs;
    }
  }
}

StereoPair StereoPairer::take() {
  require(ready_, "stereo pairing: take() without a ready pair");
  ready_ = false;
  const StereoPair pair = pair_;
  match();
  return pair;
}

void StereoPairer::release(const StereoPair& pair) {
  left_.release(pair.left);
  right_.release(pair.right);
}

void StereoPairer::reset(Side side) {
  Queue& q = queue(side);
  while (q.size > 0) {
    drop_front(side, side == Side::left ? counters_.unpaired_left : counters_.unpaired_right);
  }
  q.has_last = false;
}

void StereoPairer::count_corrupt(Side side) {
  ++(side == Side::left ? counters_.corrupt_left : counters_.corrupt_right);
}

// ----------------------------------------------------------------------------------------------

StereoGrabber::StereoGrabber(CameraSource& left, CameraSource& right, Clock& clock,
                             PairingConfig config, const TriggerRecord* trigger)
    : left_(left), right_(right), clock_(clock), pairer_(left, right, config, trigger) {}

PairResult StereoGrabber::next(Nanoseconds timeout) {
  const Nanoseconds deadline = clock_.now() + std::max<Nanoseconds>(timeout, 0);
  while (true) {
    if (pairer_.has_pair()) return {PairStatus::ok, pairer_.take(), Side::left};
    // Past the deadline the cameras are still asked once more, without waiting: with a
    // timeout of 0, next() takes whatever pair is already there.
    const Nanoseconds left_time = std::max<Nanoseconds>(deadline - clock_.now(), 0);
    // Acquire on the side that has nothing waiting (the left one first).
    const Side side = pairer_.waiting(Side::left) == 0 ? Side::left : Side::right;
    CameraSource& camera = side == Side::left ? left_ : right_;
    const AcquireResult r = camera.acquire(left_time);
    if (r.status == AcquireStatus::ok) {
      pairer_.push(side, r.frame);
    } else if (r.status == AcquireStatus::device_lost) {
      pairer_.reset(side);
      return {PairStatus::device_lost, {}, side};
    } else if (r.status == AcquireStatus::corrupt) {
      pairer_.count_corrupt(side);  // the camera took its buffer back; wait for the next frame
    } else {
      return {PairStatus::timeout, {}, side};
    }
  }
}

}  // namespace epipole::hal

#include "epipole/hal/stereo_pairing.hpp"

#include <algorithm>

#include "epipole/core/error.hpp"

namespace epipole::hal {

StereoPairer::StereoPairer(CameraSource& left, CameraSource& right, PairingConfig config,
                           const TriggerRecord* trigger)
    : left_(left), right_(right), config_(config), trigger_(trigger) {
  require(config_.tolerance >= 0, "stereo pairing (", left_.name(), ", ", right_.name(),
          "): timestamp tolerance ", config_.tolerance, " ns is negative");
  require(config_.match_sequences || trigger_ == nullptr, "stereo pairing (", left_.name(), ", ",
          right_.name(), "): pairing by time alone cannot check the trigger record (sequences)");
  if (trigger_ != nullptr) {
    require(config_.edge_tolerance >= 0, "stereo pairing (", left_.name(), ", ", right_.name(),
            "): edge tolerance ", config_.edge_tolerance, " ns is negative");
  }
  check_period(config_.trigger_period);
}

void StereoPairer::check_period(Nanoseconds period) const {
  require(period >= 0, "stereo pairing (", left_.name(), ", ", right_.name(), "): period ", period,
          " ns is negative");
  require(period == 0 || 2 * config_.tolerance < period, "stereo pairing (", left_.name(), ", ",
          right_.name(), "): timestamp tolerance ", config_.tolerance,
          " ns is not below half the trigger period ", period,
          " ns, so frames of neighbouring triggers could pair");
  require(period == 0 || trigger_ == nullptr || 2 * config_.edge_tolerance < period,
          "stereo pairing (", left_.name(), ", ", right_.name(), "): edge tolerance ",
          config_.edge_tolerance, " ns is not below half the trigger period ", period,
          " ns, so a frame could fit two trigger edges");
}

void StereoPairer::set_trigger_period(Nanoseconds period) {
  check_period(period);
  config_.trigger_period = period;
}

bool StereoPairer::on_trigger(const Frame& left, const Frame& right) const {
  if (trigger_ == nullptr) return true;
  const std::optional<TriggerEdge> edge = trigger_->find(left.sequence);
  if (!edge) return false;
  // Times on different clocks say nothing of each other: the sequence numbers pair them.
  if (edge->clock != left.clock || edge->clock != right.clock) return true;
  const Nanoseconds expected = edge->timestamp + config_.edge_delay;
  auto fits = [&](Nanoseconds t) {
    return (t > expected ? t - expected : expected - t) <= config_.edge_tolerance;
  };
  return fits(left.timestamp) && fits(right.timestamp);
}

void StereoPairer::note_seen(Side side, std::uint32_t number) {
  if (config_.match_sequences || side == Side::left) ledger_.seen(side, number);
}

void StereoPairer::drop_front(Side side, std::uint64_t& counter) {
  Queue& q = queue(side);
  camera(side).release(q.front());
  q.head = (q.head + 1) % kCapacity;
  --q.size;
  ++counter;
}

bool StereoPairer::push(Side side, const Frame& camera_frame) {
  Queue& q = queue(side);
  Frame frame = camera_frame;
  if (config_.match_sequences && q.numbered) frame.sequence += q.offset;
  ++counters_.of(side).pushed;
  // A sequence that does not increase is a duplicate or garbled: refuse it. Pairing by time,
  // so is a timestamp that does not increase.
  if (q.has_last && (static_cast<std::int32_t>(frame.sequence - q.last) <= 0 ||
                     (!config_.match_sequences && frame.timestamp <= q.last_time))) {
    camera(side).release(frame);
    ++counters_.of(side).out_of_order;
    return ready_;
  }
  q.has_last = true;
  q.last = frame.sequence;
  q.last_time = frame.timestamp;
  if (!config_.match_sequences || q.numbered) note_seen(side, frame.sequence);
  if (q.size == kCapacity) drop_front(side, counters_.of(side).unpaired);
  q.frames[(q.head + q.size) % kCapacity] = frame;
  ++q.size;
  match();
  return ready_;
}

void StereoPairer::take_fronts() {
  pair_ = {left_q_.front(), right_q_.front()};
  left_q_.head = (left_q_.head + 1) % kCapacity;
  --left_q_.size;
  right_q_.head = (right_q_.head + 1) % kCapacity;
  --right_q_.size;
  ready_ = true;
  ++counters_.pairs;
}

// Each side's frames come in time order. Of the two oldest frames, the earlier one (`early`)
// can pair only with the later one (`late`): every other frame of late's side is later still.
// Late may have a nearer partner in the frame after early, if that is already here; one that
// has not come yet is no nearer when the tolerance is below half the frame period. Drops the
// oldest frames until the two fronts match (true) or a side runs out (false). Frames on
// different clocks never match: both go.
bool StereoPairer::fronts_match_by_time() {
  while (left_q_.size > 0 && right_q_.size > 0) {
    const Frame& l = left_q_.front();
    const Frame& r = right_q_.front();
    if (l.clock != r.clock) {
      // Renumbering a reopened side, the left number may still be its camera's own.
      if (!config_.match_sequences || left_q_.numbered) ledger_.damaged(l.sequence);
      drop_front(Side::left, counters_.left().mismatched);
      drop_front(Side::right, counters_.right().mismatched);
      continue;
    }
    const Side early = l.timestamp <= r.timestamp ? Side::left : Side::right;
    std::uint64_t& unpaired = counters_.of(early).unpaired;
    const Queue& q = queue(early);
    const Nanoseconds late_time = early == Side::left ? r.timestamp : l.timestamp;
    const Nanoseconds dt = late_time - q.front().timestamp;
    const auto distance = [&](const Frame& f) {
      return f.timestamp > late_time ? f.timestamp - late_time : late_time - f.timestamp;
    };
    if (dt > config_.tolerance || (q.size > 1 && distance(q.second()) < dt)) {
      drop_front(early, unpaired);
      continue;
    }
    return true;
  }
  return false;
}

void StereoPairer::match_by_time() {
  while (!ready_ && fronts_match_by_time()) take_fronts();
}

void StereoPairer::number(Side side, std::uint32_t offset) {
  Queue& q = queue(side);
  q.numbered = true;
  q.offset = offset;
  for (std::size_t i = 0; i < q.size; ++i) {
    Frame& f = q.frames[(q.head + i) % kCapacity];
    f.sequence += offset;
    note_seen(side, f.sequence);
  }
  q.last += offset;
  ++counters_.of(side).renumbered;
}

// Numbers the frames of a reopened side (or both) again; false while they must wait for a
// match, by time as free-running cameras pair.
bool StereoPairer::renumber() {
  if (left_q_.numbered && right_q_.numbered) return true;
  // Both reopened, with the trigger's record: each side on its own, by the edge of its time.
  if (trigger_ != nullptr && !left_q_.numbered && !right_q_.numbered) {
    for (const Side side : {Side::left, Side::right}) {
      Queue& q = queue(side);
      while (!q.numbered && q.size > 0) {
        const Frame& f = q.front();
        const auto edge =
            trigger_->find_near(f.timestamp - config_.edge_delay, config_.edge_tolerance, f.clock);
        if (edge) {
          number(side, edge->sequence - f.sequence);
          numbers_are_the_triggers_ = true;
        } else {
          drop_front(side, counters_.of(side).off_trigger);
        }
      }
    }
    return left_q_.numbered && right_q_.numbered;
  }
  if (!fronts_match_by_time()) return false;
  const std::uint32_t l = left_q_.front().sequence;
  const std::uint32_t r = right_q_.front().sequence;
  if (!left_q_.numbered && !right_q_.numbered) {
    // Both reopened, no record: the pairs' numbers go on after the last the ledger counted.
    const std::uint32_t next = ledger_.restart();
    numbers_are_the_triggers_ = false;
    number(Side::left, next - l);
    number(Side::right, next - r);
  } else if (!left_q_.numbered) {
    number(Side::left, r - l);
  } else {
    number(Side::right, l - r);
  }
  return true;
}

void StereoPairer::match() {
  if (!config_.match_sequences) {
    match_by_time();
    return;
  }
  if (!renumber()) return;
  while (!ready_ && left_q_.size > 0 && right_q_.size > 0) {
    const Frame& l = left_q_.front();
    const Frame& r = right_q_.front();
    const auto d = static_cast<std::int32_t>(l.sequence - r.sequence);
    if (d < 0) {
      drop_front(Side::left, counters_.left().unpaired);  // right is past it: it cannot pair
    } else if (d > 0) {
      drop_front(Side::right, counters_.right().unpaired);
    } else {
      const Nanoseconds dt =
          l.timestamp > r.timestamp ? l.timestamp - r.timestamp : r.timestamp - l.timestamp;
      if (dt > config_.tolerance || l.clock != r.clock) {
        ledger_.damaged(l.sequence);
        drop_front(Side::left, counters_.left().mismatched);
        drop_front(Side::right, counters_.right().mismatched);
        continue;
      }
      if (!on_trigger(l, r)) {
        ledger_.damaged(l.sequence);
        drop_front(Side::left, counters_.left().off_trigger);
        drop_front(Side::right, counters_.right().off_trigger);
        continue;
      }
      take_fronts();
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
    drop_front(side, counters_.of(side).unpaired);
  }
  q.has_last = false;
  if (config_.match_sequences) q.numbered = false;
}

void StereoPairer::count_corrupt(Side side, std::uint32_t camera_sequence) {
  ++counters_.of(side).corrupt;
  const Queue& q = queue(side);
  if (!config_.match_sequences) {
    if (side == Side::left) ledger_.damaged(camera_sequence);
  } else if (q.numbered) {
    ledger_.damaged(camera_sequence + q.offset);
  }
}

// ----------------------------------------------------------------------------------------------

StereoGrabber::StereoGrabber(CameraSource& left, CameraSource& right, Clock& clock,
                             PairingConfig config, const TriggerRecord* trigger)
    : left_(left), right_(right), clock_(clock), pairer_(left, right, config, trigger) {}

// Acquires from one side and hands the pairer what came: a frame, a loss (that side's frames
// are dropped) or a damaged frame (counted; the camera took its buffer back).
AcquireStatus StereoGrabber::acquire(Side side, Nanoseconds timeout) {
  CameraSource& camera = side == Side::left ? left_ : right_;
  const AcquireResult r = camera.acquire(timeout);
  if (r.status == AcquireStatus::ok) {
    pairer_.push(side, r.frame);
  } else if (r.status == AcquireStatus::device_lost) {
    pairer_.reset(side);
  } else if (r.status == AcquireStatus::corrupt) {
    pairer_.count_corrupt(side, r.frame.sequence);
  }
  return r.status;
}

PairResult StereoGrabber::next(Nanoseconds timeout) {
  const Nanoseconds deadline = clock_.now() + std::max<Nanoseconds>(timeout, 0);
  while (true) {
    if (pairer_.has_pair()) return {PairStatus::ok, pairer_.take(), Side::left};
    // Past the deadline the cameras are still asked once more, without waiting: with a
    // timeout of 0, next() takes whatever pair is already there.
    const Nanoseconds left_time = std::max<Nanoseconds>(deadline - clock_.now(), 0);
    // Acquire on the side that has nothing waiting (the left one first).
    const Side side = pairer_.waiting(Side::left) == 0 ? Side::left : Side::right;
    const AcquireStatus status = acquire(side, left_time);
    if (status == AcquireStatus::device_lost) {
      // The other camera is still read, without waiting: its buffers keep moving, and its own
      // loss is found (and its reopening begun) now, not once this one is back.
      acquire(side == Side::left ? Side::right : Side::left, 0);
      return {PairStatus::device_lost, {}, side};
    }
    if (status == AcquireStatus::timeout) return {PairStatus::timeout, {}, side};
    // ok, or corrupt: wait for the next frame
  }
}

}  // namespace epipole::hal

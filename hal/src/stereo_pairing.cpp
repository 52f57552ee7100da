#include "epipole/hal/stereo_pairing.hpp"

#include <algorithm>

#include "epipole/core/error.hpp"

namespace epipole::hal {

StereoPairer::StereoPairer(CameraSource& left, CameraSource& right, PairingConfig config,
                           const TriggerRecord* trigger)
    : left_(left), right_(right), config_(config), trigger_(trigger), delay_(config.edge_delay) {
  require(config_.tolerance >= 0, "stereo pairing (", left_.name(), ", ", right_.name(),
          "): timestamp tolerance ", config_.tolerance, " ns is negative");
  if (trigger_ != nullptr) {
    require(config_.edge_tolerance >= 0, "stereo pairing (", left_.name(), ", ", right_.name(),
            "): edge tolerance ", config_.edge_tolerance, " ns is negative");
    require(delay_.has_value() || config_.trigger_period > 0, "stereo pairing (", left_.name(),
            ", ", right_.name(),
            "): the edge delay is learned within one trigger period, which is not known");
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

StereoPairer::EdgeAt StereoPairer::edge_at(const Frame& frame) const {
  const std::optional<Nanoseconds> newest = trigger_->newest(frame.clock);
  if (delay_) {
    const Nanoseconds at = frame.timestamp - *delay_;
    if (const auto edge = trigger_->find_near(at, config_.edge_tolerance, frame.clock)) {
      return {EdgeAt::found, *edge};
    }
    // The edge's window is not over in the record yet: the edge may still be added.
    return {newest && *newest > at + config_.edge_tolerance ? EdgeAt::none : EdgeAt::not_yet, {}};
  }
  // Learning: frames are stamped within [-1/4, 3/4) of a period after their edge.
  const Nanoseconds period = config_.trigger_period;
  const auto edge = trigger_->latest_at(frame.timestamp + period / 4, frame.clock);
  if (edge && frame.timestamp - edge->timestamp < period - period / 4) {
    return {EdgeAt::found, *edge};
  }
  return {newest && *newest > frame.timestamp ? EdgeAt::none : EdgeAt::not_yet, {}};
}

std::optional<std::uint32_t> StereoPairer::trigger_number(Side side, const Frame& frame) const {
  if (trigger_ == nullptr) {
    return side == Side::left ? std::optional<std::uint32_t>(frame.sequence) : std::nullopt;
  }
  const EdgeAt e = edge_at(frame);
  return e.kind == EdgeAt::found ? std::optional<std::uint32_t>(e.edge.sequence) : std::nullopt;
}

void StereoPairer::note_seen(Side side, const Frame& frame) {
  if (const auto n = trigger_number(side, frame)) ledger_.seen(side, *n);
}

void StereoPairer::drop_front(Side side, std::uint64_t& counter) {
  Queue& q = queue(side);
  note_seen(side, q.front());
  camera(side).release(q.front());
  q.head = (q.head + 1) % kCapacity;
  --q.size;
  ++counter;
}

bool StereoPairer::push(Side side, const Frame& frame) {
  Queue& q = queue(side);
  ++counters_.of(side).pushed;
  // A timestamp that does not increase is a duplicate or garbled: refuse it. Free running, so
  // is a sequence (it numbers the pairs).
  if (q.has_last &&
      (frame.timestamp <= q.last_time ||
       (trigger_ == nullptr && static_cast<std::int32_t>(frame.sequence - q.last) <= 0))) {
    camera(side).release(frame);
    ++counters_.of(side).out_of_order;
    return ready_;
  }
  q.has_last = true;
  q.last = frame.sequence;
  q.last_time = frame.timestamp;
  if (q.size == kCapacity) drop_front(side, counters_.of(side).unpaired);
  q.frames[(q.head + q.size) % kCapacity] = frame;
  ++q.size;
  match();
  return ready_;
}

void StereoPairer::take_fronts(const std::optional<TriggerEdge>& edge) {
  pair_ = {left_q_.front(), right_q_.front(), edge};
  if (edge) pair_.left.sequence = pair_.right.sequence = edge->sequence;
  left_q_.head = (left_q_.head + 1) % kCapacity;
  --left_q_.size;
  right_q_.head = (right_q_.head + 1) % kCapacity;
  --right_q_.size;
  ready_ = true;
  ++counters_.pairs;
  if (edge || trigger_ == nullptr) {
    ledger_.seen(Side::left, pair_.left.sequence);
    ledger_.seen(Side::right, pair_.left.sequence);
  }
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
      if (const auto n = trigger_number(Side::left, l)) ledger_.damaged(*n);
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

void StereoPairer::learn(Nanoseconds delay) {
  samples_[sample_count_++] = delay;
  if (sample_count_ < kLearnPairs) return;
  const auto middle = samples_.begin() + kLearnPairs / 2;
  std::nth_element(samples_.begin(), middle, samples_.end());
  delay_ = *middle;
  sample_count_ = 0;
  ++counters_.delay_learned;
}

void StereoPairer::match() {
  while (!ready_ && fronts_match_by_time()) {
    if (trigger_ == nullptr) {
      take_fronts(std::nullopt);
      return;
    }
    const Frame& l = left_q_.front();
    EdgeAt e = edge_at(l);
    if (e.kind == EdgeAt::not_yet) {
      // The trigger thread may record the edge a little after the frames came: the newest pair
      // waits for it until a later frame comes.
      if (left_q_.size == 1 && right_q_.size == 1) return;
      e.kind = EdgeAt::none;
    }
    const bool learning = !delay_.has_value();
    if (e.kind == EdgeAt::none) {
      if (!learning && !config_.edge_delay && ++edgeless_in_a_row_ >= kRelearnAfter) {
        delay_.reset();  // the frames' delay changed (another exposure, a slower readout)
        edgeless_in_a_row_ = 0;
      }
      drop_front(Side::left, counters_.left().off_trigger);
      drop_front(Side::right, counters_.right().off_trigger);
      continue;
    }
    edgeless_in_a_row_ = 0;
    if (has_last_edge_ && static_cast<std::int32_t>(e.edge.sequence - last_edge_) <= 0) {
      drop_front(Side::left, counters_.left().out_of_order);  // that edge has its pair
      drop_front(Side::right, counters_.right().out_of_order);
      continue;
    }
    if (learning) learn(l.timestamp - e.edge.timestamp);
    has_last_edge_ = true;
    last_edge_ = e.edge.sequence;
    take_fronts(e.edge);
  }
}

void StereoPairer::retry() {
  if (!ready_) match();
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
}

void StereoPairer::count_corrupt(Side side, const Frame& frame) {
  ++counters_.of(side).corrupt;
  if (const auto n = trigger_number(side, frame)) ledger_.damaged(*n);
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
    pairer_.count_corrupt(side, r.frame);
  }
  return r.status;
}

PairResult StereoGrabber::next(Nanoseconds timeout) {
  const Nanoseconds deadline = clock_.now() + std::max<Nanoseconds>(timeout, 0);
  while (true) {
    pairer_.retry();
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

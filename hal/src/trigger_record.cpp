#include "epipole/hal/trigger.hpp"

namespace epipole::hal {

void TriggerRecord::set_min_gap(Nanoseconds min_gap) {
  const std::lock_guard<std::mutex> lock(mutex_);
  min_gap_ = min_gap;
}

bool TriggerRecord::add(const TriggerEdge& edge) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (last_ && last_->clock == edge.clock && edge.timestamp - last_->timestamp < min_gap_) {
    ++bounces_;
    return false;
  }
  TriggerEdge numbered = edge;
  numbered.sequence = static_cast<std::uint32_t>(added_);
  slots_[numbered.sequence % kCapacity] = {numbered, true};
  last_ = numbered;
  ++added_;
  return true;
}

std::optional<TriggerEdge> TriggerRecord::find(std::uint32_t sequence) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  const Slot& slot = slots_[sequence % kCapacity];
  if (!slot.valid || slot.edge.sequence != sequence) return std::nullopt;
  return slot.edge;
}

std::optional<TriggerEdge> TriggerRecord::find_near(Nanoseconds time, Nanoseconds tolerance,
                                                    ClockId clock) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::optional<TriggerEdge> nearest;
  Nanoseconds best = tolerance;
  for (const Slot& slot : slots_) {
    if (!slot.valid || slot.edge.clock != clock) continue;
    const Nanoseconds d =
        slot.edge.timestamp > time ? slot.edge.timestamp - time : time - slot.edge.timestamp;
    if (d <= best) {
      best = d;
      nearest = slot.edge;
    }
  }
  return nearest;
}

std::optional<TriggerEdge> TriggerRecord::latest_at(Nanoseconds time, ClockId clock) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::optional<TriggerEdge> latest;
  for (const Slot& slot : slots_) {
    if (!slot.valid || slot.edge.clock != clock || slot.edge.timestamp > time) continue;
    if (!latest || slot.edge.timestamp > latest->timestamp) latest = slot.edge;
  }
  return latest;
}

std::optional<Nanoseconds> TriggerRecord::newest(ClockId clock) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!last_ || last_->clock != clock) return std::nullopt;
  return last_->timestamp;
}

std::uint64_t TriggerRecord::added() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return added_;
}

std::uint64_t TriggerRecord::bounces() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return bounces_;
}

// ----------------------------------------------------------------------------------------------

void EdgeSchedule::start(Nanoseconds first_edge, Nanoseconds period) {
  segments_[0] = {0, first_edge, period};
  first_ = 0;
  count_ = 1;
}

void EdgeSchedule::change_period(std::uint32_t anchor, Nanoseconds period) {
  const Segment& last = newest();
  // An anchor before the current rate began would rewrite edges already fired at that rate.
  if (static_cast<std::int32_t>(anchor - last.first) < 0) anchor = last.first;
  if (anchor == last.first) {
    segments_[(first_ + count_ - 1) % kSegments].period = period;
    return;
  }
  const Segment next{anchor, time(anchor), period};
  if (count_ == kSegments) {  // the oldest rate is forgotten
    first_ = (first_ + 1) % kSegments;
    --count_;
  }
  segments_[(first_ + count_) % kSegments] = next;
  ++count_;
}

Nanoseconds EdgeSchedule::time(std::uint32_t sequence) const {
  for (std::size_t i = count_; i-- > 0;) {
    const Segment& s = segments_[(first_ + i) % kSegments];
    if (sequence >= s.first || i == 0) {
      return s.time +
             (static_cast<Nanoseconds>(sequence) - static_cast<Nanoseconds>(s.first)) * s.period;
    }
  }
  return 0;
}

std::uint32_t EdgeSchedule::edges_until(Nanoseconds t) const {
  for (std::size_t i = count_; i-- > 0;) {
    const Segment& s = segments_[(first_ + i) % kSegments];
    if (t >= s.time) return s.first + static_cast<std::uint32_t>((t - s.time) / s.period) + 1;
  }
  return oldest();
}

}  // namespace epipole::hal

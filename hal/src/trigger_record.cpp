#include "epipole/hal/trigger.hpp"

namespace epipole::hal {

void TriggerRecord::add(const TriggerEdge& edge) {
  const std::lock_guard<std::mutex> lock(mutex_);
  slots_[edge.sequence % kCapacity] = {edge, true};
  ++added_;
}

std::optional<TriggerEdge> TriggerRecord::find(std::uint32_t sequence) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  const Slot& slot = slots_[sequence % kCapacity];
  if (!slot.valid || slot.edge.sequence != sequence) return std::nullopt;
  return slot.edge;
}

std::uint64_t TriggerRecord::added() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return added_;
}

void TriggerRecord::clear() {
  const std::lock_guard<std::mutex> lock(mutex_);
  slots_.fill({});
  added_ = 0;
}

}  // namespace epipole::hal

#include "epipole/hal/trigger_ledger.hpp"

#include <algorithm>

namespace epipole::hal {

namespace {
// How far `number` is past `from`, numbers wrapping at 2^32.
std::int64_t ahead(std::uint32_t number, std::uint32_t from) {
  return static_cast<std::int32_t>(number - from);
}
}  // namespace

void TriggerLedger::seen(Side side, std::uint32_t number) {
  mark(number, side == Side::left ? kLeft : kRight);
}

void TriggerLedger::damaged(std::uint32_t number) {
  mark(number, kDamaged);
}

void TriggerLedger::stale(std::uint32_t number) {
  mark(number, kStale);
  settle_before(number + 1);
}

void TriggerLedger::published(std::uint32_t number) {
  mark(number, kPublished);
  settle_before(number + 1);
  at_published_ = account_;
}

void TriggerLedger::mark(std::uint32_t number, std::uint8_t marks) {
  const std::int64_t distance = ahead(number, next_);
  if (distance < 0) return;  // settled already: a frame that came after its trigger was given up
  if (distance >= kWindow) settle_before(number - kWindow + 1);
  // Every number the slot could hold before this one is settled now: it is empty or this one's.
  Slot& slot = slots_[number % kWindow];
  slot.number = number;
  slot.marks |= marks;
}

// Only the numbers in [next_, next_ + kWindow) can have marks (mark() settles the older ones
// first), so a longer gap settles the window's numbers one by one and the rest, which no frame
// reached, at once.
void TriggerLedger::settle_before(std::uint32_t end) {
  const std::int64_t gap = ahead(end, next_);
  if (gap <= 0) return;
  const std::int64_t one_by_one = gap < kWindow ? gap : kWindow;
  for (std::int64_t i = 0; i < one_by_one; ++i) {
    settle(slots_[next_ % kWindow], next_);
    ++next_;
  }
  account_.both_sides += static_cast<std::uint64_t>(gap - one_by_one);
  next_ = end;
}

void TriggerLedger::settle(Slot& slot, std::uint32_t number) {
  const std::uint8_t marks = slot.number == number ? slot.marks : 0;
  if ((marks & kPublished) != 0) {
    ++account_.published;
  } else if ((marks & kStale) != 0) {
    ++account_.stale;
  } else if ((marks & kDamaged) != 0) {
    ++account_.corrupt;
  } else if ((marks & (kLeft | kRight)) != 0) {
    ++account_.one_side;
  } else {
    ++account_.both_sides;
  }
  slot.marks = 0;
}

}  // namespace epipole::hal

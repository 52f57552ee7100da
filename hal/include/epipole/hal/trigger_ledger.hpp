#pragma once

#include <array>
#include <cstdint>

#include "epipole/hal/side.hpp"

namespace epipole::hal {

// What became of the triggers up to the newest pair the frame loop published: each trigger
// number is settled once, into exactly one of these, so that
// published + dropped() = the triggers fired up to (and with) the newest published pair.
struct TriggerAccount {
  std::uint64_t published = 0;
  // Paired, but a newer pair was already there: the loop could not follow the trigger.
  std::uint64_t stale = 0;
  // One camera's frame of that trigger came and never paired: the other side lost it (a
  // driver's overrun, a reopen, a frame too late for its partner).
  std::uint64_t one_side = 0;
  // No frame of that trigger came from either camera (overrun or lost on both sides).
  std::uint64_t both_sides = 0;
  // A frame came damaged (the driver flagged it, or it was short), or both frames came and
  // failed the pair's checks (their times, the trigger's edge).
  std::uint64_t corrupt = 0;

  std::uint64_t dropped() const { return stale + one_side + both_sides + corrupt; }
  friend bool operator==(const TriggerAccount&, const TriggerAccount&) = default;
};

// Keeps the TriggerAccount: told which trigger numbers reached the pairer from which side,
// which were damaged, and which pairs were published or skipped, it settles each number once
// no frame of it can still come: when a pair after it is published or skipped, or when a frame
// a whole window later arrives (frames of one trigger never arrive that far apart: the pairer
// holds only a few per side). Numbers count up from `first` (0: a trigger's, as V4L2 and the
// simulated cameras number frames from the start of streaming); they may wrap. Fixed memory,
// never allocates.
class TriggerLedger {
 public:
  explicit TriggerLedger(std::uint32_t first = 0) : next_(first) {}

  void seen(Side side, std::uint32_t number);
  void damaged(std::uint32_t number);
  // A pair the frame loop skipped for a newer one, or published; every number before it is
  // settled too.
  void stale(std::uint32_t number);
  void published(std::uint32_t number);

  // Everything settled so far (triggers a window behind the newest frame can be settled before a
  // pair after them is published).
  const TriggerAccount& account() const { return account_; }
  // The account as it stood when the newest pair was published: exactly the triggers up to and
  // with it, as the health message reports them.
  const TriggerAccount& at_newest_published() const { return at_published_; }
  // The first number not settled yet.
  std::uint32_t next() const { return next_; }

 private:
  static constexpr std::uint32_t kWindow = 64;
  enum Mark : std::uint8_t {
    kLeft = 1,
    kRight = 2,
    kDamaged = 4,
    kStale = 8,
    kPublished = 16,
  };
  struct Slot {
    std::uint32_t number = 0;
    std::uint8_t marks = 0;  // 0: the slot holds nothing
  };

  void mark(std::uint32_t number, std::uint8_t marks);
  void settle_before(std::uint32_t end);
  void settle(Slot& slot, std::uint32_t number);

  std::array<Slot, kWindow> slots_{};
  std::uint32_t next_;
  TriggerAccount account_;
  TriggerAccount at_published_;
};

}  // namespace epipole::hal

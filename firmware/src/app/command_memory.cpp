#include "epipole/firmware/command_memory.hpp"

namespace epipole::firmware {

const CommandMemory::Entry* CommandMemory::resent(std::uint16_t sequence,
                                                  const protocol::Message& message,
                                                  hal::Nanoseconds now) const {
  for (const Entry& e : entries_) {
    if (e.valid && e.sequence == sequence && now - e.at <= kResendWindow && e.message == message) {
      return &e;
    }
  }
  return nullptr;
}

void CommandMemory::remember(std::uint16_t sequence, const protocol::Message& message,
                             hal::Nanoseconds now, CommandVerdict verdict, bool pending) {
  // A number remembered already is a command the robot reused: only the newest stands.
  for (Entry& e : entries_) {
    if (e.valid && e.sequence == sequence) e.valid = false;
  }
  entries_[next_] = {sequence, message, now, verdict, pending, true};
  next_ = (next_ + 1) % kSize;
}

void CommandMemory::settle(std::uint16_t sequence, CommandVerdict verdict) {
  for (Entry& e : entries_) {
    if (e.valid && e.pending && e.sequence == sequence) {
      e.verdict = verdict;
      e.pending = false;
    }
  }
}

}  // namespace epipole::firmware

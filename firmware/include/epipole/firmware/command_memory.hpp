#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/hal/clock.hpp"

namespace epipole::firmware {

// What a command's ack says.
struct CommandVerdict {
  protocol::AckStatus status = protocol::AckStatus::ok;
  protocol::AckReason reason = protocol::AckReason::none;
  friend bool operator==(const CommandVerdict&, const CommandVerdict&) = default;
};

// The commands the firmware applied, so that each is applied once: a command that comes again
// with the same number and the same content within kResendWindow of the first (its ack was lost
// and the robot sent it again) is a resend, answered with the first one's result; anything else
// is new (a number reused by a robot that rebooted, with its first frame lost or not, carries
// other content or comes later). A command answered `busy` was not applied and is not
// remembered: sent again, it is applied. Holds the last kSize commands; fixed memory.
class CommandMemory {
 public:
  static constexpr std::size_t kSize = 16;
  static constexpr hal::Nanoseconds kResendWindow = 2'000'000'000;

  struct Entry {
    std::uint16_t sequence = 0;
    protocol::Message message;
    hal::Nanoseconds at = 0;
    CommandVerdict verdict;
    bool pending = false;  // a snapshot being written: its one ack comes when it is
    bool valid = false;
  };

  // The command this one resends, if it is a resend (`now` on the same clock as remember()'s).
  const Entry* resent(std::uint16_t sequence, const protocol::Message& message,
                      hal::Nanoseconds now) const;
  void remember(std::uint16_t sequence, const protocol::Message& message, hal::Nanoseconds now,
                CommandVerdict verdict, bool pending = false);
  // A pending command's result came (a snapshot was written, or failed).
  void settle(std::uint16_t sequence, CommandVerdict verdict);

 private:
  std::array<Entry, kSize> entries_{};
  std::size_t next_ = 0;
};

}  // namespace epipole::firmware

#pragma once

// Every trigger accounted for (docs/protocol.md): at each health message, the pairs published
// and the triggers dropped add up to the triggers up to the newest frame summary before it, and
// the causes add up to the dropped.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <variant>

#include "epipole/firmware/protocol/messages.hpp"

namespace epipole::test {

// `messages`: what the firmware sent, in order; `message_of(m)` is one's protocol::Message.
// Returns the number of health messages checked (those after a frame summary).
template <class Messages, class MessageOf>
int expect_triggers_accounted(const Messages& messages, MessageOf message_of) {
  std::optional<std::uint32_t> newest;
  int checked = 0;
  for (const auto& m : messages) {
    const protocol::Message& message = message_of(m);
    if (const auto* f = std::get_if<protocol::FrameSummary>(&message)) newest = f->frame;
    const auto* h = std::get_if<protocol::Health>(&message);
    if (h == nullptr || !newest) continue;
    EXPECT_EQ(h->frames + h->dropped, *newest + 1) << "health at " << h->uptime_ms << " ms";
    EXPECT_EQ(h->dropped,
              h->dropped_stale + h->dropped_one_side + h->dropped_both_sides + h->dropped_corrupt)
        << "health at " << h->uptime_ms << " ms";
    ++checked;
  }
  return checked;
}

}  // namespace epipole::test

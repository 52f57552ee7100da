#pragma once

#include <cstdint>
#include <string>

#include "epipole/firmware/link.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/hal/clock.hpp"

namespace epipole::firmware {

// What a serial link must carry whatever else it drops: every pair's summary (an obstacle
// distance on a MAVLink link) and, with `odometry` (the stage on), its odometry, and the
// once-a-second health and calibration health (a heartbeat), each at its largest encoding. The
// larger messages (detections, depth grids, points) are dropped and counted when the baud rate
// cannot carry them too.
std::uint64_t essential_bytes_per_second(LinkProtocol protocol, hal::Nanoseconds frame_period,
                                         bool odometry = false);

// Whether the link may give `message` the whole budget (the essential messages above, and the
// acks: rare and small, so not in the reserve).
bool is_essential(const protocol::Message& message);

// What the link keeps in its budget for those (one pair's and one second's): the other messages
// are sent only when as much is left after them.
std::uint64_t essential_reserve_bytes(LinkProtocol protocol, bool odometry = false);

// 8N1: ten bits a byte.
inline std::uint64_t link_bytes_per_second(int baud) {
  return static_cast<std::uint64_t>(baud) / 10;
}

// Empty when a link at `baud` carries the essential messages at that frame period; else why
// not, in one sentence that says what to change.
std::string link_capacity_problem(LinkProtocol protocol, int baud, hal::Nanoseconds frame_period,
                                  bool odometry = false);

}  // namespace epipole::firmware

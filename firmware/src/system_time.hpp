#pragma once

#include <time.h>

#include <cstdint>

namespace epipole::firmware::detail {

// Now on the system clock (CLOCK_REALTIME, ns since the Unix epoch): the time the robot's
// computers share (NTP, PTP), for the outputs' stamps. It steps when the clock is set.
inline std::int64_t system_now_ns() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

}  // namespace epipole::firmware::detail

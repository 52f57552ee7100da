#pragma once

#include <chrono>

#include "epipole/hal/clock.hpp"

namespace epipole::firmware::detail {

// Host time for measuring how long work takes (stage times) and for real-time deadlines, even
// on a board whose clock is not the host's (a virtual one).
inline hal::Nanoseconds steady_now() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace epipole::firmware::detail

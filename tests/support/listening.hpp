#pragma once

// What the tests' DDS subscribers (epipole-ros2-listener, epipole-fastdds-listener) share: how
// long they wait and listen.
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace epipole::test {

using ListenClock = std::chrono::steady_clock;

// Waits until `matched(i)` holds for every topic i (its reader has a writer), or `deadline`:
// false then, after saying which topic on standard error; "ready" on standard error otherwise.
template <class Matched>
bool wait_for_writers(const std::vector<std::string>& topics, ListenClock::time_point deadline,
                      Matched matched) {
  for (std::size_t i = 0; i < topics.size(); ++i) {
    while (!matched(i)) {
      if (ListenClock::now() > deadline) {
        std::fprintf(stderr, "listener: no writer of %s\n", topics[i].c_str());
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  std::fprintf(stderr, "ready\n");
  std::fflush(stderr);
  return true;
}

// Calls `take_all()` (true when it took anything) until nothing came for half a second once
// `started()` holds, or `deadline`.
template <class TakeAll, class Started>
void take_until_quiet(ListenClock::time_point deadline, TakeAll take_all, Started started) {
  auto last = ListenClock::now();
  while (ListenClock::now() < deadline &&
         (!started() || ListenClock::now() - last < std::chrono::milliseconds(500))) {
    if (take_all()) {
      last = ListenClock::now();
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
}

}  // namespace epipole::test

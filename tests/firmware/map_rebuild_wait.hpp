#pragma once

// A correction's map is rebuilt on a thread of SCHED_IDLE, in the time the pairs leave: a test
// that runs pairs back to back, on a machine busy with other tests, waits for it before its next
// pair, so that the map goes in place at that pair, as on a board between two triggers.
#include <chrono>
#include <thread>

#include "epipole/firmware/rig_correction.hpp"

namespace epipole::test {

// True once no map is being rebuilt or a rebuilt one waits for the next pair (at most 60 s).
inline bool wait_for_rebuilt_map(const firmware::RigCorrection& correction) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (correction.rebuilding() && !correction.map_ready()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

}  // namespace epipole::test

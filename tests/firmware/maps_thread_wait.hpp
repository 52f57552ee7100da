#pragma once

// A corrected rig's map is rebuilt, and save_calibration's file written, by the maps thread; at
// SCHED_IDLE (threads.maps: idle, the default) only in the time the pairs leave. A test that runs
// pairs back to back, on a machine busy with other tests, waits for it before its next pair, so
// that the map goes in place at that pair, as on a board between two triggers.
#include <chrono>
#include <thread>

#include "epipole/firmware/rig_correction.hpp"

namespace epipole::test {

// True once the maps thread has nothing left to do (at most 60 s).
inline bool wait_for_maps_thread(const firmware::RigCorrection& correction) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (correction.busy()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

}  // namespace epipole::test

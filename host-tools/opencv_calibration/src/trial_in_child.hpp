// Runs a piece of work in a forked child process first, so that a third-party parser that hangs
// or overflows its stack on some malformed input (OpenCV 4.6's FileStorage: an infinite loop on a
// dedented YAML key, unbounded recursion on deep nesting) ends the child instead of this process.
#pragma once

#include <chrono>
#include <functional>

namespace epipole::tools {

enum class TrialOutcome {
  finished,   // the work returned or threw: running it here is safe
  crashed,    // the child died on a signal or exited with an error (a sanitizer's report)
  timed_out,  // still running after the limit; the child was killed
};

// The work's result is dropped with the child; call it again in this process once it finished.
TrialOutcome trial_in_child(const std::function<void()>& work, std::chrono::seconds limit);

}  // namespace epipole::tools

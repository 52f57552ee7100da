#pragma once

// The bench: the firmware's stages on a board's configuration and images, timed per stage and
// per pair for 1..N threads, beside OpenCV doing the same work, in one run. Behind `epipole
// bench` at a desk and `epipole-bench` on a board (built for aarch64 and armhf with the target's
// OpenCV), which take the same options.
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "epipole/core/simd.hpp"

namespace epipole::tools {

inline constexpr const char* kBenchDescription =
    "Time the firmware's stages and whole pairs on a board's configuration, for 1..N threads, "
    "beside OpenCV doing the same work";

struct BenchOptions {
  std::string board = "board/sim";
  std::string scene;  // the board's simulated scene to take images from (default: its own)
  std::string left;   // or these images, letterboxed to the board's size
  std::string right;
  std::vector<int> threads;            // default: 1 .. the CPUs this process may use
  std::vector<std::string> stages;     // the stages run instead of the board's (names of kStages)
  std::vector<std::string> overrides;  // KEY=VALUE set over the board file's (--set)
  int pairs = 30;
  int warmup = 3;
  // Each pair's rectification done while the one before ends, as the firmware's loop does when
  // the next pair is there (the trigger above what the loop follows); false: pair by pair.
  bool rectify_ahead = true;
  bool epipole = true;  // false: OpenCV's side only (--opencv-only: one side's instruction count)
  bool opencv = true;
  std::string opencv_sgbm = "3way";  // OpenCV's SGM: StereoSGBM's mode, 3way or default
  // The pairs again with the right rectification map rebuilt for each, as a correction of the
  // rig does on the firmware's maps thread: "beside" the pair (do pairs slow down?), or "after"
  // it, waited for (the rebuild's own time, and exact instruction counts under qemu: the two
  // threads never run at once). Empty: not.
  std::string rebuild_map;
  bool json = false;
};

// The bench's options on `command`.
void add_bench_options(CLI::App& command, BenchOptions& options);

// Runs the bench and prints its table (or JSON) on standard output, a progress line on standard
// error when it is a terminal. Throws Error for a board, scene or image that does not load.
void run_bench(BenchOptions options, SimdPath path);

}  // namespace epipole::tools

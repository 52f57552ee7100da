#pragma once

#include <opencv2/core.hpp>

namespace benchmark::internal {
class Benchmark;
}

namespace epipole::bench {

// The frame sizes every stage is timed at: 640x480 and 1280x720, in milliseconds.
void frame_sizes(benchmark::internal::Benchmark* benchmark);

// Middlebury Aloe (left view, gray) resized to the given size with INTER_AREA: the design
// brief's reference image for the per-stage figures.
const cv::Mat& aloe_left(int width, int height);

}  // namespace epipole::bench

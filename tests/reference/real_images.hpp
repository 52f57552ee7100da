#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace epipole::test {

// A real grey image of the data sets, named for test messages.
struct RealImage {
  const char* name;
  cv::Mat gray;
};

// The corner tests' real images: graf1, Aloe's left view at 640x480 (INTER_AREA) and the first
// chessboard view, left01. Throws when one cannot be read.
std::vector<RealImage> corner_test_images();

}  // namespace epipole::test

#pragma once

#include <opencv2/core.hpp>

#include "epipole/core/image.hpp"

namespace epipole::test {

// Our view of an OpenCV 8-bit single-channel matrix: the same pixels, no copy.
inline GrayView view_of(const cv::Mat& mat) {
  CV_Assert(mat.type() == CV_8UC1);
  return {mat.ptr<std::uint8_t>(), mat.cols, mat.rows, static_cast<std::ptrdiff_t>(mat.step1())};
}

}  // namespace epipole::test

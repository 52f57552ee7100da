#pragma once

#include <opencv2/core.hpp>

#include <algorithm>

#include "epipole/core/image.hpp"

namespace epipole::test {

// Our view of an OpenCV 8-bit single-channel matrix: the same pixels, no copy.
inline GrayView view_of(const cv::Mat& mat) {
  CV_Assert(mat.type() == CV_8UC1);
  return {mat.ptr<std::uint8_t>(), mat.cols, mat.rows, static_cast<std::ptrdiff_t>(mat.step1())};
}

// A copy of our image as an OpenCV matrix of the same element type (CV_8U, CV_16S, CV_32F...).
template <typename T>
cv::Mat mat_of(ImageView<const T> view) {
  cv::Mat m(view.height(), view.width(), cv::DataType<T>::type);
  for (int y = 0; y < view.height(); ++y) std::copy_n(view.row(y), view.width(), m.ptr<T>(y));
  return m;
}
template <typename T>
cv::Mat mat_of(const Image<T>& image) {
  return mat_of(image.view());
}

}  // namespace epipole::test

#pragma once

// OpenCV headers over our images' pixels (no copy), for the host tool's calls into OpenCV. A
// view of const pixels is only read by OpenCV; the const_cast is what cv::Mat's constructor
// asks for.
#include <opencv2/core.hpp>

#include <cstdint>

#include "epipole/core/image.hpp"

namespace epipole::tools {

namespace detail {
template <typename T>
cv::Mat mat_over(ImageView<T> image, int type) {
  using Pixel = std::remove_const_t<T>;
  return {image.height(), image.width(), type, const_cast<Pixel*>(image.data()),  // NOLINT
          static_cast<std::size_t>(image.stride()) * sizeof(Pixel)};
}
}  // namespace detail

inline cv::Mat mat_of(GrayView image) {
  return detail::mat_over(image, CV_8UC1);
}
inline cv::Mat mat_of(ImageView<const std::int16_t> image) {
  return detail::mat_over(image, CV_16SC1);
}
// To draw on: colours are cv::Scalar(red, green, blue).
inline cv::Mat mat_of(ImageView<Rgb8> image) {
  static_assert(sizeof(Rgb8) == 3, "RGB pixels are packed: OpenCV sees them as CV_8UC3");
  return detail::mat_over(image, CV_8UC3);
}

}  // namespace epipole::tools

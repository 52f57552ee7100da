#pragma once

// JPEG pictures for the live view's page, with libjpeg-turbo's TurboJPEG API: gray images and
// RGB ones, into a buffer allocated once for the largest picture (nothing is allocated per
// picture).
#include <cstddef>
#include <cstdint>
#include <span>

#include "epipole/core/image.hpp"

namespace epipole::firmware::view {

class JpegEncoder {
 public:
  // Pictures of at most width x height pixels.
  JpegEncoder(int width, int height);
  ~JpegEncoder();
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  // The picture's bytes, valid until the next call. Throws Error when TurboJPEG fails.
  std::span<const std::uint8_t> gray(GrayView image, int quality);
  std::span<const std::uint8_t> rgb(const std::uint8_t* pixels, int width, int height,
                                    std::size_t stride, int quality);
  std::size_t working_set_bytes() const { return capacity_; }

 private:
  std::span<const std::uint8_t> encode(const std::uint8_t* pixels, int width, int height,
                                       std::size_t stride, bool colour, int quality);
  void* handle_ = nullptr;  // tjhandle
  unsigned char* buffer_ = nullptr;
  std::size_t capacity_ = 0;
  int width_, height_;
};

}  // namespace epipole::firmware::view

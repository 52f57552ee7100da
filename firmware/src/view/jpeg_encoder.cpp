#include "view/jpeg_encoder.hpp"

#include <turbojpeg.h>

#include "epipole/core/error.hpp"

namespace epipole::firmware::view {

JpegEncoder::JpegEncoder(int width, int height)
    : handle_(tjInitCompress()), width_(width), height_(height) {
  require(handle_ != nullptr, "view: TurboJPEG: ", tjGetErrorStr2(nullptr));
  capacity_ = tjBufSize(width, height, TJSAMP_444);  // the largest a picture can take
  buffer_ = tjAlloc(static_cast<int>(capacity_));
  require(buffer_ != nullptr, "view: TurboJPEG: no memory for a ", capacity_, "-byte picture");
}

JpegEncoder::~JpegEncoder() {
  tjFree(buffer_);
  tjDestroy(handle_);
}

std::span<const std::uint8_t> JpegEncoder::gray(GrayView image, int quality) {
  return encode(image.row(0), image.width(), image.height(),
                static_cast<std::size_t>(image.stride()), false, quality);
}

std::span<const std::uint8_t> JpegEncoder::rgb(const std::uint8_t* pixels, int width, int height,
                                               std::size_t stride, int quality) {
  return encode(pixels, width, height, stride, true, quality);
}

std::span<const std::uint8_t> JpegEncoder::encode(const std::uint8_t* pixels, int width, int height,
                                                  std::size_t stride, bool colour, int quality) {
  require(width <= width_ && height <= height_, "view: a ", width, "x", height,
          " picture is larger than ", width_, "x", height_);
  unsigned char* out = buffer_;
  unsigned long size = capacity_;
  const int rc = tjCompress2(handle_, pixels, width, static_cast<int>(stride), height,
                             colour ? TJPF_RGB : TJPF_GRAY, &out, &size,
                             colour ? TJSAMP_420 : TJSAMP_GRAY, quality, TJFLAG_NOREALLOC);
  require(rc == 0, "view: TurboJPEG: ", tjGetErrorStr2(handle_));
  return {buffer_, static_cast<std::size_t>(size)};
}

}  // namespace epipole::firmware::view

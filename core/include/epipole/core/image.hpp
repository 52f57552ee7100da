#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <numeric>
#include <type_traits>

#include "epipole/core/error.hpp"

namespace epipole {

// A non-owning view of a 2-D plane of T. The stride is in elements (not bytes) and may exceed
// the width (padding, a sub-image, a V4L2 buffer with bytesperline > width). Copying a view
// never copies pixels.
template <typename T>
class ImageView {
 public:
  using value_type = T;

  constexpr ImageView() = default;
  constexpr ImageView(T* data, int width, int height, std::ptrdiff_t stride)
      : data_(data), width_(width), height_(height), stride_(stride) {
    require(width >= 0 && height >= 0, "image size ", width, "x", height, " is negative");
    require(stride >= width, "image stride ", stride, " is smaller than its width ", width);
    require(data != nullptr || width == 0 || height == 0, "image data is null");
  }

  // Views of T convert to views of const T.
  template <typename U>
  requires std::is_same_v<const U, T>
  constexpr ImageView(const ImageView<U>& other)  // NOLINT(google-explicit-constructor)
      : data_(other.data()),
        width_(other.width()),
        height_(other.height()),
        stride_(other.stride()) {}

  constexpr T* data() const { return data_; }
  constexpr int width() const { return width_; }
  constexpr int height() const { return height_; }
  constexpr std::ptrdiff_t stride() const { return stride_; }
  constexpr bool empty() const { return width_ == 0 || height_ == 0; }

  constexpr T* row(int y) const { return data_ + y * stride_; }
  constexpr T& operator()(int x, int y) const { return data_[y * stride_ + x]; }

  // The rectangle [x, x+w) x [y, y+h), which must lie inside this view.
  ImageView sub(int x, int y, int w, int h) const {
    if (x < 0 || y < 0 || w < 0 || h < 0 || x + w > width_ || y + h > height_) {
      throw Error(cat("sub-image ", w, "x", h, "+", x, "+", y, " is outside the ", width_, "x",
                      height_, " image"));
    }
    return ImageView(data_ + y * stride_ + x, w, h, stride_);
  }

 private:
  T* data_ = nullptr;
  int width_ = 0;
  int height_ = 0;
  std::ptrdiff_t stride_ = 0;
};

template <typename T, typename U>
bool same_size(const ImageView<T>& a, const ImageView<U>& b) {
  return a.width() == b.width() && a.height() == b.height();
}

// An image that owns its pixels. The storage is allocated once, at construction, with rows
// aligned to kRowAlignment bytes; it never grows. Move-only, so that no copy allocates by
// accident; clone() is the explicit copy.
template <typename T>
class Image {
 public:
  static constexpr std::size_t kRowAlignment = 64;

  Image() = default;
  Image(int width, int height) : width_(width), height_(height) {
    require(width >= 0 && height >= 0, "image size ", width, "x", height, " is negative");
    // The smallest element count whose byte size is a multiple of kRowAlignment.
    constexpr auto step =
        static_cast<std::ptrdiff_t>(kRowAlignment / std::gcd(kRowAlignment, sizeof(T)));
    stride_ = (width + step - 1) / step * step;
    const std::size_t bytes = static_cast<std::size_t>(stride_) * height * sizeof(T);
    if (bytes > 0) {
      pixels_.reset(static_cast<T*>(::operator new (bytes, std::align_val_t{kRowAlignment})));
      // Zeroed: the pages are resident from the start, not faulted in when a pair first
      // writes them (core/resident.hpp), and the padding past each row is defined.
      std::memset(static_cast<void*>(pixels_.get()), 0, bytes);
    }
  }

  Image(Image&&) noexcept = default;
  Image& operator=(Image&&) noexcept = default;
  Image(const Image&) = delete;
  Image& operator=(const Image&) = delete;

  Image clone() const {
    Image copy(width_, height_);
    for (int y = 0; y < height_; ++y) {
      std::copy_n(view().row(y), width_, copy.view().row(y));
    }
    return copy;
  }

  int width() const { return width_; }
  int height() const { return height_; }
  std::ptrdiff_t stride() const { return stride_; }
  bool empty() const { return width_ == 0 || height_ == 0; }
  std::size_t size_bytes() const { return static_cast<std::size_t>(stride_) * height_ * sizeof(T); }

  ImageView<T> view() { return {pixels_.get(), width_, height_, stride_}; }
  ImageView<const T> view() const { return {pixels_.get(), width_, height_, stride_}; }
  T& operator()(int x, int y) { return pixels_.get()[y * stride_ + x]; }
  const T& operator()(int x, int y) const { return pixels_.get()[y * stride_ + x]; }

 private:
  struct AlignedDelete {
    void operator()(T* p) const { ::operator delete (p, std::align_val_t{kRowAlignment}); }
  };
  std::unique_ptr<T[], AlignedDelete> pixels_;
  int width_ = 0;
  int height_ = 0;
  std::ptrdiff_t stride_ = 0;
};

// An interleaved 8-bit colour pixel, for pictures meant for people (overlays, colour maps).
struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb8&, const Rgb8&) = default;
};

using GrayView = ImageView<const std::uint8_t>;
using MutableGrayView = ImageView<std::uint8_t>;
using GrayImage = Image<std::uint8_t>;
using RgbImage = Image<Rgb8>;

}  // namespace epipole

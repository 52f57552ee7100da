#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "epipole/core/image.hpp"

namespace epipole::test {

// Kinds of synthetic content that stress different branches of the kernels.
enum class Pattern {
  noise,      // uniform 0..255: many candidates, every branch
  saturated,  // mostly 0 and 255: saturation edge cases of v +- threshold
  blobs,      // textured squares on a textured background: realistic corner counts
};

// A test image living at a chosen byte offset inside a larger buffer, so views can be
// unaligned and have any stride.
class BufferImage {
 public:
  BufferImage(int width, int height, std::ptrdiff_t stride, std::size_t offset);
  MutableGrayView view() { return {buffer_.data() + offset_, width_, height_, stride_}; }
  GrayView cview() const { return {buffer_.data() + offset_, width_, height_, stride_}; }

 private:
  std::vector<std::uint8_t> buffer_;
  int width_;
  int height_;
  std::ptrdiff_t stride_;
  std::size_t offset_;
};

void fill(MutableGrayView image, Pattern pattern, std::uint32_t seed);

}  // namespace epipole::test

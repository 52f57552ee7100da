#include "random_image.hpp"

#include <algorithm>

namespace epipole::test {

BufferImage::BufferImage(int width, int height, std::ptrdiff_t stride, std::size_t offset)
    : buffer_(offset + static_cast<std::size_t>(stride) * height + 64, 0xA5),
      width_(width),
      height_(height),
      stride_(stride),
      offset_(offset) {}

void fill(MutableGrayView image, Pattern pattern, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  switch (pattern) {
    case Pattern::noise:
      for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) image(x, y) = static_cast<std::uint8_t>(byte(rng));
      }
      break;
    case Pattern::saturated:
      for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
          const int r = byte(rng);
          image(x, y) = static_cast<std::uint8_t>(r < 100 ? 0 : r < 200 ? 255 : byte(rng));
        }
      }
      break;
    case Pattern::blobs: {
      // Flat squares with a little texture, so that corner scores rarely tie.
      std::uniform_int_distribution<int> grain(0, 15);
      for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x)
          image(x, y) = static_cast<std::uint8_t>(60 + grain(rng));
      }
      const int count = 1 + image.width() * image.height() / 400;
      for (int i = 0; i < count; ++i) {
        const int cx = byte(rng) % std::max(1, image.width());
        const int cy = byte(rng) % std::max(1, image.height());
        const int half = 2 + byte(rng) % 6;
        const int level = byte(rng);
        for (int y = std::max(0, cy - half); y < std::min(image.height(), cy + half); ++y) {
          for (int x = std::max(0, cx - half); x < std::min(image.width(), cx + half); ++x) {
            image(x, y) = static_cast<std::uint8_t>(std::min(255, level + grain(rng)));
          }
        }
      }
      break;
    }
  }
}

}  // namespace epipole::test

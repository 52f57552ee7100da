#include "epipole/core/image.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace epipole {
namespace {

TEST(Image, RowsAreAlignedAndPadded) {
  Image<std::uint8_t> a(13, 5);
  EXPECT_EQ(a.width(), 13);
  EXPECT_EQ(a.height(), 5);
  EXPECT_EQ(a.stride(), 64);
  for (int y = 0; y < a.height(); ++y) {
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a.view().row(y)) % 64, 0u);
  }
  Image<std::int16_t> b(33, 2);
  EXPECT_EQ(b.stride(), 64);
  Image<Rgb8> c(10, 2);
  EXPECT_EQ(c.stride() * static_cast<std::ptrdiff_t>(sizeof(Rgb8)) % 64, 0);
  EXPECT_GE(c.stride(), 10);
}

TEST(Image, ViewsShareThePixels) {
  GrayImage image(8, 4);
  MutableGrayView view = image.view();
  view(3, 2) = 77;
  EXPECT_EQ(image(3, 2), 77);
  GrayView constant = view;
  EXPECT_EQ(constant(3, 2), 77);
  const auto sub = view.sub(2, 1, 4, 2);
  EXPECT_EQ(sub(1, 1), 77);
  EXPECT_EQ(sub.stride(), view.stride());
}

TEST(Image, CloneCopiesPixels) {
  GrayImage image(5, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) image(x, y) = static_cast<std::uint8_t>(x + 10 * y);
  const GrayImage copy = image.clone();
  EXPECT_NE(copy.view().data(), image.view().data());
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) EXPECT_EQ(copy(x, y), image(x, y));
}

TEST(Image, RejectsImpossibleGeometry) {
  std::uint8_t pixels[16] = {};
  EXPECT_THROW(GrayView(pixels, 4, 4, 3), Error);   // stride < width
  EXPECT_THROW(GrayView(pixels, -1, 4, 4), Error);  // negative size
  EXPECT_THROW(GrayView(nullptr, 4, 4, 4), Error);  // no pixels
  EXPECT_NO_THROW(GrayView(nullptr, 0, 0, 0));      // the empty view
  const GrayView view(pixels, 4, 4, 4);
  EXPECT_THROW(view.sub(2, 2, 3, 1), Error);
  EXPECT_THROW(view.sub(-1, 0, 1, 1), Error);
  EXPECT_THROW(GrayImage(-2, 3), Error);
}

}  // namespace
}  // namespace epipole

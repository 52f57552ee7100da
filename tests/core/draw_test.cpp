#include "epipole/core/draw.hpp"

#include <gtest/gtest.h>

namespace epipole {
namespace {

int count(const RgbImage& image, Rgb8 color) {
  int n = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) n += image(x, y) == color;
  return n;
}

TEST(Draw, GrayToRgbCopiesEveryPixel) {
  GrayImage gray(3, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) gray(x, y) = static_cast<std::uint8_t>(x * 50 + y);
  RgbImage rgb(3, 2);
  gray_to_rgb(gray.view(), rgb.view());
  EXPECT_EQ(rgb(2, 1), (Rgb8{101, 101, 101}));
  RgbImage wrong(4, 2);
  EXPECT_THROW(gray_to_rgb(gray.view(), wrong.view()), Error);
}

TEST(Draw, ShapesAreClippedAndClosed) {
  RgbImage image(20, 10);
  const Rgb8 red{255, 0, 0};
  draw_line(image.view(), 0, 0, 19, 0, red);
  EXPECT_EQ(count(image, red), 20);
  draw_rectangle(image.view(), 2, 2, 5, 4, red);  // 2*5 + 2*2 border pixels
  EXPECT_EQ(count(image, red), 20 + 14);
  draw_circle(image.view(), 0, 0, 50, red);        // entirely outside: nothing, no crash
  draw_line(image.view(), -10, 10, 30, -10, red);  // enters and leaves the image
  EXPECT_GT(count(image, red), 34);
}

}  // namespace
}  // namespace epipole

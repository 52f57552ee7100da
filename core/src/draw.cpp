#include "epipole/core/draw.hpp"

#include <cstdlib>

#include "epipole/core/error.hpp"

namespace epipole {

namespace {
void plot(ImageView<Rgb8> image, int x, int y, Rgb8 color) {
  if (x >= 0 && y >= 0 && x < image.width() && y < image.height()) image(x, y) = color;
}
}  // namespace

void gray_to_rgb(GrayView gray, ImageView<Rgb8> rgb) {
  require(same_size(gray, rgb), "gray_to_rgb: ", gray.width(), "x", gray.height(), " vs ",
          rgb.width(), "x", rgb.height());
  for (int y = 0; y < gray.height(); ++y) {
    const std::uint8_t* in = gray.row(y);
    Rgb8* out = rgb.row(y);
    for (int x = 0; x < gray.width(); ++x) out[x] = {in[x], in[x], in[x]};
  }
}

// Bresenham's line.
void draw_line(ImageView<Rgb8> image, int x0, int y0, int x1, int y1, Rgb8 color) {
  const int dx = std::abs(x1 - x0);
  const int dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1;
  const int sy = y0 < y1 ? 1 : -1;
  int error = dx + dy;
  for (;;) {
    plot(image, x0, y0, color);
    if (x0 == x1 && y0 == y1) return;
    const int e2 = 2 * error;
    if (e2 >= dy) {
      error += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      error += dx;
      y0 += sy;
    }
  }
}

// The midpoint circle.
void draw_circle(ImageView<Rgb8> image, int cx, int cy, int radius, Rgb8 color) {
  int x = radius;
  int y = 0;
  int error = 1 - radius;
  while (x >= y) {
    plot(image, cx + x, cy + y, color);
    plot(image, cx + y, cy + x, color);
    plot(image, cx - y, cy + x, color);
    plot(image, cx - x, cy + y, color);
    plot(image, cx - x, cy - y, color);
    plot(image, cx - y, cy - x, color);
    plot(image, cx + y, cy - x, color);
    plot(image, cx + x, cy - y, color);
    ++y;
    if (error < 0) {
      error += 2 * y + 1;
    } else {
      --x;
      error += 2 * (y - x) + 1;
    }
  }
}

void draw_rectangle(ImageView<Rgb8> image, int x, int y, int width, int height, Rgb8 color) {
  const int right = x + width - 1;
  const int bottom = y + height - 1;
  draw_line(image, x, y, right, y, color);
  draw_line(image, right, y, right, bottom, color);
  draw_line(image, right, bottom, x, bottom, color);
  draw_line(image, x, bottom, x, y, color);
}

}  // namespace epipole

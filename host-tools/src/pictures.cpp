#include "pictures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "epipole/core/draw.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::tools {

namespace {

// A 3x5 font: each glyph is 5 rows of 3 bits (bit 2 = left column).
using Glyph = std::array<std::uint8_t, 5>;
constexpr std::array<Glyph, 10> kDigits = {{{7, 5, 5, 5, 7},
                                            {2, 6, 2, 2, 7},
                                            {7, 1, 7, 4, 7},
                                            {7, 1, 7, 1, 7},
                                            {5, 5, 7, 1, 1},
                                            {7, 4, 7, 1, 7},
                                            {7, 4, 7, 5, 7},
                                            {7, 1, 1, 1, 1},
                                            {7, 5, 7, 5, 7},
                                            {7, 5, 7, 1, 7}}};
constexpr int kFontScale = 2;

Glyph glyph_of(char c) {
  if (c >= '0' && c <= '9') return kDigits[static_cast<std::size_t>(c - '0')];
  switch (c) {
    case '.':
      return {0, 0, 0, 0, 2};
    case '-':
      return {0, 0, 7, 0, 0};
    case ':':
      return {0, 2, 0, 2, 0};
    case 'm':
      return {0, 0, 7, 7, 5};
    case 'x':
      return {0, 5, 2, 5, 0};
    case '%':
      return {5, 1, 2, 4, 5};
    default:
      return {0, 0, 0, 0, 0};
  }
}

}  // namespace

Rgb8 colour_of(double t) {
  t = std::clamp(t, 0.0, 1.0);
  const auto ramp = [](double v) {
    return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);
  };
  return {ramp(1.5 - std::abs(4.0 * t - 3.0)), ramp(1.5 - std::abs(4.0 * t - 2.0)),
          ramp(1.5 - std::abs(4.0 * t - 1.0))};
}

void draw_text(ImageView<Rgb8> image, int x, int y, std::string_view text, Rgb8 colour) {
  for (const char c : text) {
    const Glyph glyph = glyph_of(c);
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < 3; ++col) {
        if ((glyph[static_cast<std::size_t>(row)] >> (2 - col) & 1) == 0) continue;
        for (int dy = 0; dy < kFontScale; ++dy) {
          for (int dx = 0; dx < kFontScale; ++dx) {
            const int px = x + col * kFontScale + dx;
            const int py = y + row * kFontScale + dy;
            if (px >= 0 && py >= 0 && px < image.width() && py < image.height()) {
              image(px, py) = colour;
            }
          }
        }
      }
    }
    x += 4 * kFontScale;
  }
}

int text_width(std::string_view text) {
  return static_cast<int>(text.size()) * 4 * kFontScale;
}

RgbImage disparity_picture(ImageView<const std::int16_t> disparity, int max_disparity) {
  constexpr int kLegend = 40;
  const int width = disparity.width();
  const int height = disparity.height();
  RgbImage picture(width, height + kLegend);
  const ImageView<Rgb8> view = picture.view();
  for (int y = 0; y < height + kLegend; ++y) std::fill_n(view.row(y), width, Rgb8{});
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int d = disparity(x, y);
      if (d == vision::kInvalidDisparity) continue;
      view(x, y) = colour_of(d / (16.0 * max_disparity));
    }
  }
  const int margin = 8;
  const int bar_width = std::max(1, width - 2 * margin);
  const int bar_top = height + 6;
  for (int i = 0; i < bar_width; ++i) {
    const Rgb8 c = colour_of(static_cast<double>(i) / std::max(1, bar_width - 1));
    for (int y = bar_top; y < bar_top + 12; ++y) view(margin + i, y) = c;
  }
  const Rgb8 white{255, 255, 255};
  constexpr int kTicks = 4;
  for (int t = 0; t <= kTicks; ++t) {
    const std::string label = std::to_string(max_disparity * t / kTicks);
    const int x = margin + (bar_width - 1) * t / kTicks;
    draw_line(view, x, bar_top + 12, x, bar_top + 16, white);
    const int label_x =
        std::clamp(x - text_width(label) / 2, 0, std::max(0, width - text_width(label)));
    draw_text(view, label_x, bar_top + 18, label, white);
  }
  return picture;
}

}  // namespace epipole::tools

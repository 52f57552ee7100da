#pragma once

#include <cstdint>
#include <string_view>

#include "epipole/core/image.hpp"

namespace epipole::tools {

// Pictures for people: colour scales, labels, disparity with a legend.

// A colour for t in [0, 1]: blue (far) through green and yellow to red (near).
Rgb8 colour_of(double t);

// Text in a small bitmap font (digits, '.', '-', ':', ' ', 'm', 'x', '%'), scale 2: 8 pixels a
// character, 10 high. Clipped to the image.
void draw_text(ImageView<Rgb8> image, int x, int y, std::string_view text, Rgb8 colour);
int text_width(std::string_view text);
constexpr int kTextHeight = 10;

// The disparity (x16, vision::kInvalidDisparity: black) in colour above a legend: a colour bar
// from 0 to max_disparity pixels with labelled ticks.
RgbImage disparity_picture(ImageView<const std::int16_t> disparity, int max_disparity);

}  // namespace epipole::tools

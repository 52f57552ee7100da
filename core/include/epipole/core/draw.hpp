#pragma once

#include "epipole/core/image.hpp"

namespace epipole {

// Drawing for pictures meant for people (host tool, simulation output). Shapes are clipped to
// the image; nothing here allocates.

// Copies a gray image into an RGB one of the same size.
void gray_to_rgb(GrayView gray, ImageView<Rgb8> rgb);

void draw_line(ImageView<Rgb8> image, int x0, int y0, int x1, int y1, Rgb8 color);
void draw_circle(ImageView<Rgb8> image, int cx, int cy, int radius, Rgb8 color);
void draw_rectangle(ImageView<Rgb8> image, int x, int y, int width, int height, Rgb8 color);

}  // namespace epipole

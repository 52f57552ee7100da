#pragma once

#include <cstdint>

#include "epipole/core/image.hpp"

namespace epipole::hal {

// How an image of one size is fitted into the simulated cameras' size: scaled by one factor
// (so a rectified pair stays rectified, its disparities scaled by `scale`) and centred, the
// margins filled.
struct Letterbox {
  double scale = 1;
  int x = 0, y = 0;           // where the scaled image starts
  int width = 0, height = 0;  // the scaled image's size
};
Letterbox letterbox_geometry(int from_width, int from_height, int to_width, int to_height);

// The image fitted into width x height: area averaging when it shrinks, bilinear when it grows,
// unchanged when the sizes agree. Start-up code (allocates the result).
GrayImage letterbox(GrayView image, int width, int height, std::uint8_t fill = 0);

// The right view of a scene whose left view is `left`, at a constant disparity (pixels):
// right(x, y) = left(x + disparity, y), the border column repeated.
GrayImage synthesize_right(GrayView left, int disparity);

}  // namespace epipole::hal

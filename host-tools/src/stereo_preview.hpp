#pragma once

#include "epipole/core/image.hpp"

namespace epipole::tools {

// A rectified pair side by side (left | right) with a horizontal line every `spacing` rows
// across both, so that a point can be followed from one image to the other: on a well
// rectified pair it stays on the same line.
RgbImage side_by_side_preview(GrayView left, GrayView right, int spacing = 32);

}  // namespace epipole::tools

#include "stereo_preview.hpp"

#include <algorithm>

#include "epipole/core/draw.hpp"
#include "epipole/core/error.hpp"

namespace epipole::tools {

RgbImage side_by_side_preview(GrayView left, GrayView right, int spacing) {
  require(same_size(left, right), "preview: the rectified images differ in size (", left.width(),
          "x", left.height(), " and ", right.width(), "x", right.height(), ")");
  require(spacing >= 1, "preview: line spacing must be >= 1");
  RgbImage picture(2 * left.width(), left.height());
  gray_to_rgb(left, picture.view().sub(0, 0, left.width(), left.height()));
  gray_to_rgb(right, picture.view().sub(left.width(), 0, right.width(), right.height()));
  constexpr Rgb8 kColors[] = {{0, 255, 0}, {255, 64, 64}, {64, 160, 255}};
  int line = 0;
  for (int y = spacing / 2; y < picture.height(); y += spacing, ++line) {
    draw_line(picture.view(), 0, y, picture.width() - 1, y, kColors[line % 3]);
  }
  return picture;
}

}  // namespace epipole::tools

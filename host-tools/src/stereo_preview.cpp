#include "stereo_preview.hpp"

#include <opencv2/imgproc.hpp>

#include "epipole/core/error.hpp"
#include "pictures.hpp"

namespace epipole::tools {

RgbImage side_by_side_preview(GrayView left, GrayView right, int spacing) {
  require(same_size(left, right), "preview: the rectified images differ in size (", left.width(),
          "x", left.height(), " and ", right.width(), "x", right.height(), ")");
  require(spacing >= 1, "preview: line spacing must be >= 1");
  RgbImage picture = side_by_side(left, right);
  cv::Mat out = mat_of(picture.view());
  const cv::Scalar colours[] = {{0, 255, 0}, {255, 64, 64}, {64, 160, 255}};
  int line = 0;
  for (int y = spacing / 2; y < picture.height(); y += spacing, ++line) {
    cv::line(out, {0, y}, {picture.width() - 1, y}, colours[line % 3]);
  }
  return picture;
}

}  // namespace epipole::tools

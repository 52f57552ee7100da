#include "stereo_preview.hpp"

#include <opencv2/imgproc.hpp>

#include "epipole/core/error.hpp"
#include "pictures.hpp"

namespace epipole::tools {

RgbImage side_by_side_preview(GrayView left, GrayView right, int spacing) {
  require(same_size(left, right), "preview: the rectified images differ in size (", left.width(),
          "x", left.height(), " and ", right.width(), "x", right.height(), ")");
  require(spacing >= 1, "preview: line spacing must be >= 1");
  const int w = left.width();
  RgbImage picture(2 * w, left.height());
  cv::Mat out = canvas(picture.view());
  canvas(rgb_picture(left).view()).copyTo(out.colRange(0, w));
  canvas(rgb_picture(right).view()).copyTo(out.colRange(w, 2 * w));
  const cv::Scalar colours[] = {{0, 255, 0}, {255, 64, 64}, {64, 160, 255}};
  int line = 0;
  for (int y = spacing / 2; y < picture.height(); y += spacing, ++line) {
    cv::line(out, {0, y}, {picture.width() - 1, y}, colours[line % 3]);
  }
  return picture;
}

}  // namespace epipole::tools

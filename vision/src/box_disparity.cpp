#include "epipole/vision/box_disparity.hpp"

#include <algorithm>
#include <cstring>

#include "epipole/core/error.hpp"

namespace epipole::vision {

BoxDisparity::BoxDisparity(int max_disparity) : bins_(16 * max_disparity) {
  require(max_disparity >= 1 && max_disparity <= 2048, "box disparity range ", max_disparity,
          " is outside [1, 2048]");
  histogram_ = std::make_unique<std::uint32_t[]>(static_cast<std::size_t>(bins_));
}

std::optional<std::int16_t> BoxDisparity::median(ImageView<const std::int16_t> disparity, int x,
                                                 int y, int width, int height) {
  const int x0 = std::max(x, 0);
  const int y0 = std::max(y, 0);
  const int x1 = std::min(x + std::max(width, 0), disparity.width());
  const int y1 = std::min(y + std::max(height, 0), disparity.height());
  std::uint32_t* const histogram = histogram_.get();
  std::uint32_t count = 0;
  int low = bins_;
  int high = -1;
  for (int v = y0; v < y1; ++v) {
    const std::int16_t* row = disparity.row(v);
    for (int u = x0; u < x1; ++u) {
      const int d = row[u];
      if (d < 0 || d >= bins_) continue;
      ++histogram[d];
      ++count;
      low = std::min(low, d);
      high = std::max(high, d);
    }
  }
  if (count == 0) return std::nullopt;
  const std::uint32_t rank = (count - 1) / 2;
  std::uint32_t seen = 0;
  int median = low;
  for (int d = low; d <= high; ++d) {
    if (seen <= rank && rank < seen + histogram[d]) median = d;
    seen += histogram[d];
    histogram[d] = 0;  // leave the histogram zero for the next box
  }
  return static_cast<std::int16_t>(median);
}

}  // namespace epipole::vision

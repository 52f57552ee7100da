#include "epipole/vision/disparity_quality.hpp"

#include <cmath>

#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::vision {

DisparityQuality disparity_quality(ImageView<const std::int16_t> disparity,
                                   ImageView<const float> truth,
                                   ImageView<const std::uint8_t> mask) {
  require(same_size(disparity, truth), "the disparity is ", disparity.width(), "x",
          disparity.height(), " but the ground truth is ", truth.width(), "x", truth.height());
  require(mask.empty() || same_size(mask, truth), "the mask is ", mask.width(), "x", mask.height(),
          " but the ground truth is ", truth.width(), "x", truth.height());
  std::int64_t known = 0, valid = 0, bad1 = 0, bad2 = 0, bad4 = 0, d1 = 0;
  double error_sum = 0;
  for (int y = 0; y < truth.height(); ++y) {
    for (int x = 0; x < truth.width(); ++x) {
      const float t = truth(x, y);
      if (!(t > 0) || !std::isfinite(t) || (!mask.empty() && mask(x, y) == 0)) continue;
      ++known;
      const int d = disparity(x, y);
      if (d < 0) {
        ++bad1, ++bad2, ++bad4, ++d1;
        continue;
      }
      ++valid;
      const double e = std::abs(static_cast<double>(d) / kDisparityScale - static_cast<double>(t));
      error_sum += e;
      bad1 += e > 1 ? 1 : 0;
      bad2 += e > 2 ? 1 : 0;
      bad4 += e > 4 ? 1 : 0;
      d1 += e > 3 && e > 0.05 * static_cast<double>(t) ? 1 : 0;
    }
  }
  DisparityQuality q;
  q.known = known;
  q.valid = valid;
  if (known == 0) return q;
  const auto share = [known](std::int64_t n) {
    return static_cast<double>(n) / static_cast<double>(known);
  };
  q.bad1 = share(bad1);
  q.bad2 = share(bad2);
  q.bad4 = share(bad4);
  q.d1 = share(d1);
  q.density = share(valid);
  q.mean_error = valid > 0 ? error_sum / static_cast<double>(valid) : 0.0;
  return q;
}

}  // namespace epipole::vision

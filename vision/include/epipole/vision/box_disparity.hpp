#pragma once

// The disparity of a detection: the median of the valid disparities inside its box, with fixed
// memory (a histogram over the disparity range, allocated at construction). Converting it to
// metres needs the calibration, which vision does not know: firmware/detection_depth.hpp.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>

#include "epipole/core/image.hpp"

namespace epipole::vision {

class BoxDisparity {
 public:
  // Disparities x16 in [0, 16 * max_disparity) are valid (StereoMatcher's output range); the
  // rest, kInvalidDisparity included, are not. Throws Error unless 1 <= max_disparity <= 2048.
  explicit BoxDisparity(int max_disparity);

  // The median (the lower one of an even count: rank (n - 1) / 2 in increasing order) of the
  // valid disparities x16 of `disparity` in the box [x, x + width) x [y, y + height), clipped
  // to the image; nullopt when the box holds none. Never allocates.
  std::optional<std::int16_t> median(ImageView<const std::int16_t> disparity, int x, int y,
                                     int width, int height);

  int max_disparity() const { return bins_ / 16; }
  std::size_t working_set_bytes() const { return static_cast<std::size_t>(bins_) * 4; }

 private:
  int bins_;
  std::unique_ptr<std::uint32_t[]> histogram_;  // all zero between calls
};

}  // namespace epipole::vision

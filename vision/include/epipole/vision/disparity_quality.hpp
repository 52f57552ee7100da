#pragma once

// How a disparity map compares with ground truth, in the figures of the Middlebury and KITTI
// stereo benchmarks. Every share is over the pixels with ground truth (and inside the mask when
// one is given); a pixel without a disparity counts as wrong in bad1/bad2/bad4 and D1, as
// OpenCV's own stereo regression test counts it, and the density says how many had one.
#include <cstdint>

#include "epipole/core/image.hpp"

namespace epipole::vision {

struct DisparityQuality {
  std::int64_t known = 0;  // pixels with ground truth (in the mask)
  std::int64_t valid = 0;  // of those, with a disparity
  double bad1 = 0;         // missing, or off by more than 1 px
  double bad2 = 0;         // ... by more than 2 px
  double bad4 = 0;         // ... by more than 4 px
  double d1 = 0;           // KITTI's D1: missing, or off by more than 3 px and 5 % of the truth
  double density = 0;      // valid / known
  double mean_error = 0;   // mean |disparity - truth| over the valid pixels, px
};

// disparity: x16 (stereo.hpp's kDisparityScale), below 0 missing. truth: in pixels, 0 or below
// (or not finite) unknown. mask: empty, or the pixels to count are those where it is nonzero.
// Throws Error when the sizes differ.
DisparityQuality disparity_quality(ImageView<const std::int16_t> disparity,
                                   ImageView<const float> truth,
                                   ImageView<const std::uint8_t> mask = {});

}  // namespace epipole::vision

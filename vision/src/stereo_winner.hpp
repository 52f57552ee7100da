#pragma once

// The pieces of the winner take all that every kernel path shares (inline: they run per pixel).
#include <algorithm>
#include <cstdint>

#include "epipole/vision/stereo.hpp"
#include "stereo_kernels.hpp"

namespace epipole::vision::kernels {

// Uniqueness: a disparity (other than best +-1) whose cost is below
// uniqueness_limit(min_cost, uniqueness_ratio(u)) ~ min_cost * 100 / (100 - u) makes the pixel
// ambiguous. ratio = 2^16 * 100 / (100 - u), fixed point, so no division per pixel.
inline std::uint32_t uniqueness_ratio(int uniqueness) {
  return static_cast<std::uint32_t>(65536 * 100 / (100 - uniqueness));
}
inline int uniqueness_limit(int min_cost, std::uint32_t ratio) {
  return static_cast<int>((static_cast<std::uint64_t>(min_cost) * ratio) >> 16);
}

// How clearly the winner's cost `at` beats the lowest cost `other` of the disparities outside
// best +-1 (the cost curve's second minimum): 255 * (other - at) / other, rounded; 0 when both
// are 0. The ratio, not the difference, so that it means the same for SGM's and BM's sums.
inline std::uint8_t confidence_of(int at, int other) {
  if (other <= 0) return 0;
  return static_cast<std::uint8_t>(((other - at) * 255 + other / 2) / other);
}

// Parabolic sub-pixel position: d*16 + offset from the three costs around d.
inline int subpixel(int d, int disparities, int below, int at, int above) {
  if (d <= 0 || d >= disparities - 1) return d * kDisparityScale;
  const int denom = std::max(below + above - 2 * at, 1);
  return d * kDisparityScale + ((below - above) * kDisparityScale + denom) / (2 * denom);
}

// The winner of pixel x (best < 0: none) with its sub-pixel position from its D sums s, and
// its confidence from `other` (confidence_of); a disparity beyond the left border (d > x) is
// none.
inline void store_winner(const WtaRow& wta, int x, int best, const std::uint16_t* s, int D,
                         int other) {
  if (best < 0 || best > x) {
    wta.disparity[x] = kInvalidDisparity;
    wta.best[x] = -1;
    if (wta.confidence != nullptr) wta.confidence[x] = 0;
    return;
  }
  if (wta.confidence != nullptr) wta.confidence[x] = confidence_of(s[best], other);
  const int below = best > 0 ? s[best - 1] : 0;
  const int above = best < D - 1 ? s[best + 1] : 0;
  wta.disparity[x] = static_cast<std::int16_t>(subpixel(best, D, below, s[best], above));
  wta.best[x] = static_cast<std::int16_t>(best);
}

}  // namespace epipole::vision::kernels

#pragma once

// The nearest of a set of descriptors to a query, among the corners in a rectangle of the image:
// the search the sparse stereo matcher (along rows) and the window matcher (around a predicted
// place) share. Internal to vision.
#include <algorithm>
#include <cstdint>
#include <span>

#include "epipole/vision/sparse_stereo.hpp"
#include "sparse_stereo_kernels.hpp"

namespace epipole::vision {

struct NearestDescriptor {
  static constexpr int kNone = SparseStereoMatcher::kDescriptorBytes * 8 + 1;
  int index = -1;  // the nearest corner, -1 none
  int distance = kNone;
  int second = kNone;  // the second nearest's distance
  // The sparse stereo's tests: at most max_distance, and below ratio % of the second nearest
  // (a lone candidate passes).
  bool passes(int max_distance, int ratio) const {
    return index >= 0 && distance <= max_distance &&
           (second == kNone || distance * 100 < ratio * second);
  }
};

// Among corners sorted by (y, x) (`xs` their columns, `row_start` the first of each row and one
// past the last row, `descriptors` kDescriptorBytes each), those on rows row_lo..row_hi (clamped
// to the image) and columns x_lo..x_hi; the first in (row, column) order among equals.
// `distances` holds as many entries as a row can have corners.
inline NearestDescriptor nearest_descriptor(const std::uint8_t* query,
                                            std::span<const std::int16_t> xs,
                                            std::span<const std::uint32_t> row_start,
                                            const std::uint8_t* descriptors, int row_lo, int row_hi,
                                            int x_lo, int x_hi, kernels::HammingKernel* hamming,
                                            std::uint16_t* distances) {
  constexpr std::size_t kBytes = SparseStereoMatcher::kDescriptorBytes;
  const int last_row = static_cast<int>(row_start.size()) - 2;
  NearestDescriptor out;
  for (int row = std::max(0, row_lo); row <= std::min(last_row, row_hi); ++row) {
    const auto row_begin = xs.begin() + row_start[static_cast<std::size_t>(row)];
    const auto row_end = xs.begin() + row_start[static_cast<std::size_t>(row) + 1];
    const auto first = std::lower_bound(row_begin, row_end, static_cast<std::int16_t>(x_lo));
    const auto last = std::upper_bound(first, row_end, static_cast<std::int16_t>(x_hi));
    const int begin = static_cast<int>(first - xs.begin());
    const int n = static_cast<int>(last - first);
    if (n == 0) continue;
    hamming(query, descriptors + static_cast<std::size_t>(begin) * kBytes, n, distances);
    for (int k = 0; k < n; ++k) {
      const int d = distances[k];
      if (d < out.distance) {
        out.second = out.distance;
        out.distance = d;
        out.index = begin + k;
      } else if (d < out.second) {
        out.second = d;
      }
    }
  }
  return out;
}

}  // namespace epipole::vision

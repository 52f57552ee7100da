// The hole filling of disparity_filters.hpp, eight pixels at a time: valid stretches are skipped
// and long holes measured with one compare per eight, holes filled with eight-wide stores. The
// decision for each hole is the reference's.
#include <algorithm>

#include "epipole/core/neon.hpp"
#include "epipole/vision/disparity_filters.hpp"

namespace epipole::vision::kernels {

namespace {

// Each lane all ones where the disparity is invalid (negative).
inline uint64x2_t invalid_lanes(const std::int16_t* p) {
  return vreinterpretq_u64_s16(vshrq_n_s16(vld1q_s16(p), 15));
}
inline bool any_invalid(const std::int16_t* p) {
  const uint64x2_t m = invalid_lanes(p);
  return (vgetq_lane_u64(m, 0) | vgetq_lane_u64(m, 1)) != 0;
}
inline bool all_invalid(const std::int16_t* p) {
  const uint64x2_t m = invalid_lanes(p);
  return (vgetq_lane_u64(m, 0) & vgetq_lane_u64(m, 1)) == ~std::uint64_t{0};
}

}  // namespace

void fill_holes_row_neon(std::int16_t* row, int width, int max_hole) {
  int x = 0;
  for (;;) {
    while (x + 8 <= width && !any_invalid(row + x)) x += 8;
    while (x < width && row[x] >= 0) ++x;
    if (x >= width) return;
    const int begin = x;
    while (x + 8 <= width && all_invalid(row + x)) x += 8;
    while (x < width && row[x] < 0) ++x;
    if (begin == 0 || x == width || x - begin > max_hole) continue;
    const std::int16_t farther = std::min(row[begin - 1], row[x]);
    const int16x8_t fill = vdupq_n_s16(farther);
    int i = begin;
    for (; i + 8 <= x; i += 8) vst1q_s16(row + i, fill);
    for (; i < x; ++i) row[i] = farther;
  }
}

}  // namespace epipole::vision::kernels

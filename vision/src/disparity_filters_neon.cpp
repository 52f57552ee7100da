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

// The temporal filter of disparity_filters.hpp, eight pixels at a time. (now - last) * weight
// is formed in 16 bits: exact where it is used (steps of at most 7 px x16 = 112, weights up to
// 256), wrapping harmlessly where the lane is not taken.
void temporal_row_neon(std::int16_t* now, std::int16_t* last, int width, int weight,
                       int max_step_x16) {
  const int16x8_t zero = vdupq_n_s16(0);
  const int16x8_t w = vdupq_n_s16(static_cast<std::int16_t>(weight));
  const int16x8_t half = vdupq_n_s16(128);
  const int16x8_t step = vdupq_n_s16(static_cast<std::int16_t>(max_step_x16));
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const int16x8_t n = vld1q_s16(now + x);
    const int16x8_t l = vld1q_s16(last + x);
    const int16x8_t difference = vsubq_s16(n, l);
    const uint16x8_t blend = vandq_u16(vandq_u16(vcgeq_s16(n, zero), vcgeq_s16(l, zero)),
                                       vcleq_s16(vabsq_s16(difference), step));
    const int16x8_t moved = vshrq_n_s16(vaddq_s16(vmulq_s16(difference, w), half), 8);
    const int16x8_t out = vbslq_s16(blend, vaddq_s16(l, moved), n);
    vst1q_s16(now + x, out);
    vst1q_s16(last + x, out);
  }
  temporal_row_ref(now + x, last + x, width - x, weight, max_step_x16);
}

}  // namespace epipole::vision::kernels

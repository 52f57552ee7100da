// FAST-9, 16 pixels at a time with NEON. The segment test is done in vectors; the score of the
// (few) corners found is the scalar fast_score, so results equal fast_row_ref bit for bit.
// Only intrinsics that exist on both AArch64 and ARMv7 are used.
#include <cstring>

#include "epipole/core/neon.hpp"
#include "epipole/vision/fast.hpp"
#include "fast_columns.hpp"

namespace epipole::vision::kernels {

namespace {

inline bool any_set(uint8x16_t mask) {
  const uint8x8_t folded = vorr_u8(vget_low_u8(mask), vget_high_u8(mask));
  return vget_lane_u64(vreinterpret_u64_u8(folded), 0) != 0;
}

}  // namespace

int fast_row_neon(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns) {
  std::ptrdiff_t circle[25];
  fast_circle_offsets(stride, circle);
  std::memset(scores, 0, static_cast<std::size_t>(width));

  const uint8x16_t t = vdupq_n_u8(static_cast<std::uint8_t>(threshold));
  const uint8x16_t arc_minus_one = vdupq_n_u8(8);
  int count = 0;
  int x = 3;
  // A vector reads columns x-3 .. x+18, all of which must lie inside the row.
  for (; x + 16 + 3 <= width; x += 16) {
    const std::uint8_t* p = row + x;
    const uint8x16_t v = vld1q_u8(p);
    // Saturation keeps the tests exact: v + t = 255 admits no brighter pixel, v - t = 0 no
    // darker one.
    const uint8x16_t bright_above = vqaddq_u8(v, t);
    const uint8x16_t dark_below = vqsubq_u8(v, t);

    // Quick rejection: a 9-arc always covers two neighbouring compass points (0, 4, 8, 12).
    const uint8x16_t c0 = vld1q_u8(p + circle[0]);
    const uint8x16_t c4 = vld1q_u8(p + circle[4]);
    const uint8x16_t c8 = vld1q_u8(p + circle[8]);
    const uint8x16_t c12 = vld1q_u8(p + circle[12]);
    const uint8x16_t b0 = vcgtq_u8(c0, bright_above), d0 = vcltq_u8(c0, dark_below);
    const uint8x16_t b4 = vcgtq_u8(c4, bright_above), d4 = vcltq_u8(c4, dark_below);
    const uint8x16_t b8 = vcgtq_u8(c8, bright_above), d8 = vcltq_u8(c8, dark_below);
    const uint8x16_t b12 = vcgtq_u8(c12, bright_above), d12 = vcltq_u8(c12, dark_below);
    const uint8x16_t bright_pairs = vorrq_u8(vorrq_u8(vandq_u8(b0, b4), vandq_u8(b4, b8)),
                                             vorrq_u8(vandq_u8(b8, b12), vandq_u8(b12, b0)));
    const uint8x16_t dark_pairs = vorrq_u8(vorrq_u8(vandq_u8(d0, d4), vandq_u8(d4, d8)),
                                           vorrq_u8(vandq_u8(d8, d12), vandq_u8(d12, d0)));
    if (!any_set(vorrq_u8(bright_pairs, dark_pairs))) continue;

    // Longest run of brighter (darker) circle pixels, walking the circle 25 steps so that
    // runs through pixel 0 are seen whole. A run counter is (run + 1) & mask.
    uint8x16_t bright_run = vdupq_n_u8(0), dark_run = vdupq_n_u8(0);
    uint8x16_t bright_max = vdupq_n_u8(0), dark_max = vdupq_n_u8(0);
    for (int k = 0; k < 25; ++k) {
      const uint8x16_t c = vld1q_u8(p + circle[k]);
      const uint8x16_t is_bright = vcgtq_u8(c, bright_above);
      const uint8x16_t is_dark = vcltq_u8(c, dark_below);
      bright_run = vandq_u8(vsubq_u8(bright_run, is_bright), is_bright);
      dark_run = vandq_u8(vsubq_u8(dark_run, is_dark), is_dark);
      bright_max = vmaxq_u8(bright_max, bright_run);
      dark_max = vmaxq_u8(dark_max, dark_run);
    }
    const uint8x16_t is_corner = vcgtq_u8(vmaxq_u8(bright_max, dark_max), arc_minus_one);
    if (!any_set(is_corner)) continue;

    std::uint8_t lanes[16];
    vst1q_u8(lanes, is_corner);
    for (int i = 0; i < 16; ++i) {
      if (lanes[i] == 0) continue;
      scores[x + i] = static_cast<std::uint8_t>(fast_score(p + i, circle, threshold));
      columns[count++] = x + i;
    }
  }

  // The last columns, fewer than a vector: the reference code.
  count += fast_columns_ref(row, circle, x, width - 3, threshold, scores, columns + count);
  return count;
}

}  // namespace epipole::vision::kernels

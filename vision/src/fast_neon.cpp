// FAST-9, 16 pixels at a time with NEON, segment test and score together.
//
// For a pixel v with circle pixels p_k, let below_k = max(v - p_k, 0) and
// above_k = max(p_k - v, 0), and let contrast = the largest, over the 16 arcs of 9 contiguous
// circle pixels and over both sides, of the smallest below_k (above_k) on the arc. Then:
//   - the pixel is a corner at threshold t exactly when contrast > t (some arc has every
//     p_k < v - t, or every p_k > v + t), and
//   - for a corner, OpenCV's score (the largest threshold at which it is still a corner) is
//     contrast - 1.
// Saturation cannot change either answer: it only clips values <= 0, and a corner's contrast
// is > t >= 0. So these results equal fast_row_ref (OpenCV's formulation) bit for bit.
// Only intrinsics that exist on both AArch64 and ARMv7 are used.
#include <algorithm>
#include <cstring>

#include "epipole/core/neon.hpp"
#include "epipole/vision/fast.hpp"
#include "fast_columns.hpp"

namespace epipole::vision::kernels {

namespace {

inline bool any_set(uint8x16_t mask) {
  const uint64x2_t halves = vreinterpretq_u64_u8(mask);
  return (vgetq_lane_u64(halves, 0) | vgetq_lane_u64(halves, 1)) != 0;
}

// One bit per lane of a comparison mask (lane i -> bit i).
inline unsigned lane_bits(uint8x16_t mask) {
  static constexpr std::uint8_t kWeights[16] = {1, 2, 4, 8, 16, 32, 64, 128,
                                                1, 2, 4, 8, 16, 32, 64, 128};
  const uint8x16_t bits = vandq_u8(mask, vld1q_u8(kWeights));
  uint8x8_t sum = vpadd_u8(vget_low_u8(bits), vget_high_u8(bits));
  sum = vpadd_u8(sum, sum);
  sum = vpadd_u8(sum, sum);
  return vget_lane_u16(vreinterpret_u16_u8(sum), 0);
}

// max over the 16 circular arcs of 9 of the min over the arc, per lane. Arc minima are built by
// doubling: pairs, fours, eights, then one more pixel.
inline uint8x16_t best_arc(const uint8x16_t d[16]) {
  uint8x16_t m2[22];
#pragma GCC unroll 22
  for (int k = 0; k < 22; ++k) m2[k] = vminq_u8(d[k & 15], d[(k + 1) & 15]);
  uint8x16_t m4[20];
#pragma GCC unroll 20
  for (int k = 0; k < 20; ++k) m4[k] = vminq_u8(m2[k], m2[k + 2]);
  uint8x16_t best = vdupq_n_u8(0);
#pragma GCC unroll 16
  for (int k = 0; k < 16; ++k) {
    const uint8x16_t m8 = vminq_u8(m4[k], m4[k + 4]);
    best = vmaxq_u8(best, vminq_u8(m8, d[(k + 8) & 15]));
  }
  return best;
}

}  // namespace

int fast_row_neon(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns) {
  std::ptrdiff_t circle[25];
  fast_circle_offsets(stride, circle);
  std::memset(scores, 0, static_cast<std::size_t>(width));

  const uint8x16_t t = vdupq_n_u8(static_cast<std::uint8_t>(threshold));
  const uint8x16_t one = vdupq_n_u8(1);
  int count = 0;
  // A vector at x reads columns x-3 .. x+18, all of which must lie inside the row. The last
  // vector is moved left to end at the last interior column; lanes already done are skipped.
  if (width - 6 < 16) {  // narrower than one vector plus the borders
    return fast_columns_ref(row, circle, 3, width - 3, threshold, scores, columns);
  }
  const int last_start = width - 3 - 16;
  for (int next = 3; next < width - 3; next += 16) {
    const int x = std::min(next, last_start);
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
    const bool maybe_bright = any_set(bright_pairs);
    const bool maybe_dark = any_set(dark_pairs);
    if (!maybe_bright && !maybe_dark) continue;

    // Only the sides that passed the quick test are measured; the other contributes 0, which
    // no corner's contrast (> t >= 0) can be beaten by.
    uint8x16_t d[16];
    uint8x16_t contrast = vdupq_n_u8(0);
    if (maybe_dark) {
#pragma GCC unroll 16
      for (int k = 0; k < 16; ++k) d[k] = vqsubq_u8(v, vld1q_u8(p + circle[k]));
      contrast = best_arc(d);
    }
    if (maybe_bright) {
#pragma GCC unroll 16
      for (int k = 0; k < 16; ++k) d[k] = vqsubq_u8(vld1q_u8(p + circle[k]), v);
      contrast = vmaxq_u8(contrast, best_arc(d));
    }
    const uint8x16_t is_corner = vcgtq_u8(contrast, t);
    unsigned corners = lane_bits(is_corner) >> (next - x) << (next - x);
    if (corners == 0) continue;
    std::uint8_t lane_scores[16];
    vst1q_u8(lane_scores, vsubq_u8(contrast, one));
    do {
      const int lane = __builtin_ctz(corners);
      scores[x + lane] = lane_scores[lane];
      columns[count++] = x + lane;
      corners &= corners - 1;
    } while (corners != 0);
  }
  return count;
}

}  // namespace epipole::vision::kernels

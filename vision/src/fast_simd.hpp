#pragma once

// FAST-9 for one row, V::kLanes pixels at a time, segment test and score together; written once
// for any vector vocabulary V (simd/neon_u8.hpp, simd/avx2_u8.hpp).
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
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fast_columns.hpp"
#include "fast_kernels.hpp"

namespace epipole::vision::kernels {

// max over the 16 circular arcs of 9 of the min over the arc, per lane. Arc minima are built by
// doubling: pairs, fours, eights, then one more pixel.
template <class V>
inline typename V::Vec fast_best_arc(const typename V::Vec d[16]) {
  using Vec = typename V::Vec;
  Vec m2[22];
#pragma GCC unroll 22
  for (int k = 0; k < 22; ++k) m2[k] = V::min(d[k & 15], d[(k + 1) & 15]);
  Vec m4[20];
#pragma GCC unroll 20
  for (int k = 0; k < 20; ++k) m4[k] = V::min(m2[k], m2[k + 2]);
  Vec best = V::splat(0);
#pragma GCC unroll 16
  for (int k = 0; k < 16; ++k) {
    const Vec m8 = V::min(m4[k], m4[k + 4]);
    best = V::max(best, V::min(m8, d[(k + 8) & 15]));
  }
  return best;
}

template <class V>
int fast_row_simd(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns) {
  using Vec = typename V::Vec;
  constexpr int kLanes = V::kLanes;
  std::ptrdiff_t circle[25];
  fast_circle_offsets(stride, circle);
  std::memset(scores, 0, static_cast<std::size_t>(width));
  if (width - 6 < kLanes) {  // narrower than one vector plus the borders
    return fast_columns_ref(row, circle, 3, width - 3, threshold, scores, columns);
  }

  const Vec t = V::splat(static_cast<std::uint8_t>(threshold));
  const Vec one = V::splat(1);
  int count = 0;
  // A vector at x reads columns x-3 .. x+kLanes+2, all of which must lie inside the row. The
  // last vector is moved left to end at the last interior column; lanes already done are
  // skipped.
  const int last_start = width - 3 - kLanes;
  for (int next = 3; next < width - 3; next += kLanes) {
    const int x = std::min(next, last_start);
    const std::uint8_t* p = row + x;
    const Vec v = V::load(p);
    // Saturation keeps the tests exact: v + t = 255 admits no brighter pixel, v - t = 0 no
    // darker one.
    const Vec bright_above = V::adds(v, t);
    const Vec dark_below = V::subs(v, t);

    // Quick rejection: a 9-arc always covers two neighbouring compass points (0, 4, 8, 12).
    const Vec c0 = V::load(p + circle[0]);
    const Vec c4 = V::load(p + circle[4]);
    const Vec c8 = V::load(p + circle[8]);
    const Vec c12 = V::load(p + circle[12]);
    const Vec b0 = V::gt(c0, bright_above), d0 = V::lt(c0, dark_below);
    const Vec b4 = V::gt(c4, bright_above), d4 = V::lt(c4, dark_below);
    const Vec b8 = V::gt(c8, bright_above), d8 = V::lt(c8, dark_below);
    const Vec b12 = V::gt(c12, bright_above), d12 = V::lt(c12, dark_below);
    const Vec bright_pairs = V::bit_or(V::bit_or(V::bit_and(b0, b4), V::bit_and(b4, b8)),
                                       V::bit_or(V::bit_and(b8, b12), V::bit_and(b12, b0)));
    const Vec dark_pairs = V::bit_or(V::bit_or(V::bit_and(d0, d4), V::bit_and(d4, d8)),
                                     V::bit_or(V::bit_and(d8, d12), V::bit_and(d12, d0)));
    const bool maybe_bright = V::any(bright_pairs);
    const bool maybe_dark = V::any(dark_pairs);
    if (!maybe_bright && !maybe_dark) continue;

    // Only the sides that passed the quick test are measured; the other contributes 0, which
    // no corner's contrast (> t >= 0) can be beaten by.
    Vec d[16];
    Vec contrast = V::splat(0);
    if (maybe_dark) {
#pragma GCC unroll 16
      for (int k = 0; k < 16; ++k) d[k] = V::subs(v, V::load(p + circle[k]));
      contrast = fast_best_arc<V>(d);
    }
    if (maybe_bright) {
#pragma GCC unroll 16
      for (int k = 0; k < 16; ++k) d[k] = V::subs(V::load(p + circle[k]), v);
      contrast = V::max(contrast, fast_best_arc<V>(d));
    }
    const Vec is_corner = V::gt(contrast, t);
    std::uint32_t corners = V::lane_bits(is_corner) >> (next - x) << (next - x);
    if (corners == 0) continue;
    std::uint8_t lane_scores[kLanes];
    V::store(lane_scores, V::sub(contrast, one));
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

#pragma once

// FAST-9 for one row, V::kLanesB pixels at a time, segment test and score together; written once
// over the byte lanes of the vector vocabulary (simd/neon.hpp, simd/avx2.hpp).
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
inline typename V::B fast_best_arc(const typename V::B d[16]) {
  using B = typename V::B;
  B m2[22];
#pragma GCC unroll 22
  for (int k = 0; k < 22; ++k) m2[k] = V::minb(d[k & 15], d[(k + 1) & 15]);
  B m4[20];
#pragma GCC unroll 20
  for (int k = 0; k < 20; ++k) m4[k] = V::minb(m2[k], m2[k + 2]);
  B best = V::splatb(0);
#pragma GCC unroll 16
  for (int k = 0; k < 16; ++k) {
    const B m8 = V::minb(m4[k], m4[k + 4]);
    best = V::maxb(best, V::minb(m8, d[(k + 8) & 15]));
  }
  return best;
}

template <class V>
int fast_row_simd(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns) {
  using B = typename V::B;
  constexpr int kLanes = V::kLanesB;
  std::ptrdiff_t circle[25];
  fast_circle_offsets(stride, circle);
  std::memset(scores, 0, static_cast<std::size_t>(width));
  if (width - 6 < kLanes) {  // narrower than one vector plus the borders
    return fast_columns_ref(row, circle, 3, width - 3, threshold, scores, columns);
  }

  const B t = V::splatb(static_cast<std::uint8_t>(threshold));
  const B one = V::splatb(1);
  int count = 0;
  // A vector at x reads columns x-3 .. x+kLanes+2, all of which must lie inside the row. The
  // last vector is moved left to end at the last interior column; lanes already done are
  // skipped.
  const int last_start = width - 3 - kLanes;
  for (int next = 3; next < width - 3; next += kLanes) {
    const int x = std::min(next, last_start);
    const std::uint8_t* p = row + x;
    const B v = V::loadb(p);
    // Saturation keeps the tests exact: v + t = 255 admits no brighter pixel, v - t = 0 no
    // darker one.
    const B bright_above = V::addsb(v, t);
    const B dark_below = V::subsb(v, t);

    // Quick rejection: a 9-arc always covers two neighbouring compass points (0, 4, 8, 12).
    const B c0 = V::loadb(p + circle[0]);
    const B c4 = V::loadb(p + circle[4]);
    const B c8 = V::loadb(p + circle[8]);
    const B c12 = V::loadb(p + circle[12]);
    const B b0 = V::gtb(c0, bright_above), d0 = V::ltb(c0, dark_below);
    const B b4 = V::gtb(c4, bright_above), d4 = V::ltb(c4, dark_below);
    const B b8 = V::gtb(c8, bright_above), d8 = V::ltb(c8, dark_below);
    const B b12 = V::gtb(c12, bright_above), d12 = V::ltb(c12, dark_below);
    const B bright_pairs = V::orb(V::orb(V::andb(b0, b4), V::andb(b4, b8)),
                                  V::orb(V::andb(b8, b12), V::andb(b12, b0)));
    const B dark_pairs = V::orb(V::orb(V::andb(d0, d4), V::andb(d4, d8)),
                                V::orb(V::andb(d8, d12), V::andb(d12, d0)));
    const bool maybe_bright = V::anyb(bright_pairs);
    const bool maybe_dark = V::anyb(dark_pairs);
    if (!maybe_bright && !maybe_dark) continue;

    // Only the sides that passed the quick test are measured; the other contributes 0, which
    // no corner's contrast (> t >= 0) can be beaten by.
    B d[16];
    B contrast = V::splatb(0);
    if (maybe_dark) {
#pragma GCC unroll 16
      for (int k = 0; k < 16; ++k) d[k] = V::subsb(v, V::loadb(p + circle[k]));
      contrast = fast_best_arc<V>(d);
    }
    if (maybe_bright) {
#pragma GCC unroll 16
      for (int k = 0; k < 16; ++k) d[k] = V::subsb(V::loadb(p + circle[k]), v);
      contrast = V::maxb(contrast, fast_best_arc<V>(d));
    }
    const B is_corner = V::gtb(contrast, t);
    std::uint32_t corners = V::bitsb(is_corner) >> (next - x) << (next - x);
    if (corners == 0) continue;
    std::uint8_t lane_scores[kLanes];
    V::storeb(lane_scores, V::subb(contrast, one));
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

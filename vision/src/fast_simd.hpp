#pragma once

// FAST-9 for one row, V::kLanesB pixels at a time, segment test and score together; written once
// over the byte lanes of the vector vocabulary (simd/neon.hpp, simd/avx2.hpp).
//
// For a pixel v with circle pixels p_k, let the bright contrast be the largest, over the 16 arcs
// of 9 contiguous circle pixels, of max(min over the arc of p_k - v, 0), and the dark contrast
// the largest of max(v - max over the arc of p_k, 0); contrast is the larger of the two. Then:
//   - the pixel is a corner at threshold t exactly when contrast > t (some arc has every
//     p_k > v + t, or every p_k < v - t), and
//   - for a corner, OpenCV's score (the largest threshold at which it is still a corner) is
//     contrast - 1.
// Saturation cannot change either answer: it only clips values <= 0, and a corner's contrast
// is > t >= 0. So these results equal fast_row_ref (OpenCV's formulation) bit for bit.
// Because v - x and x - v are monotonic in x, the arcs' extremes are taken over the pixels
// themselves and v is subtracted once.
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fast_columns.hpp"
#include "fast_kernels.hpp"

namespace epipole::vision::kernels {

// Per lane, the largest over the 16 circular arcs of 9 of the smallest p[k] on the arc (Min and
// Max are V::minb and V::maxb), or with the roles of Min and Max swapped, the smallest of the
// largest. The two arcs that share the 8 pixels from an even k, those starting at k and k - 1,
// are taken together: their extremes differ only in p[k + 8] and p[k - 1].
template <class V, typename V::B (*Min)(typename V::B, typename V::B),
          typename V::B (*Max)(typename V::B, typename V::B)>
inline typename V::B fast_best_arc(const typename V::B p[16]) {
  using B = typename V::B;
  B m2[8];  // m2[j]: pixels 2j, 2j + 1
#pragma GCC unroll 8
  for (int j = 0; j < 8; ++j) m2[j] = Min(p[2 * j], p[2 * j + 1]);
  B m4[8];  // m4[j]: pixels 2j .. 2j + 3
#pragma GCC unroll 8
  for (int j = 0; j < 8; ++j) m4[j] = Min(m2[j], m2[(j + 1) & 7]);
  B best = Min(Min(m4[0], m4[2]), Max(p[15], p[8]));
#pragma GCC unroll 7
  for (int j = 1; j < 8; ++j) {
    const B m8 = Min(m4[j], m4[(j + 2) & 7]);  // pixels 2j .. 2j + 7
    best = Max(best, Min(m8, Max(p[2 * j - 1], p[(2 * j + 8) & 15])));
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
  if (width - 6 < kLanes) {  // narrower than one vector plus the borders
    std::memset(scores, 0, static_cast<std::size_t>(width));
    return fast_columns_ref(row, circle, 3, width - 3, threshold, scores, columns);
  }
  // Every vector stores its lanes' scores (0 where no corner); the borders get theirs here.
  std::memset(scores, 0, 3);
  std::memset(scores + width - 3, 0, 3);

  const B t = V::splatb(static_cast<std::uint8_t>(threshold));
  const B one = V::splatb(1);
  const B zero = V::splatb(0);
  int count = 0;
  // A vector at x reads columns x-3 .. x+kLanes+2, all of which must lie inside the row. The
  // last vector is moved left to end at the last interior column; lanes already done are
  // scored again (to the same scores) but not listed again.
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
    // (0 or 8) and (4 or 12): one of the pairs 0-4, 4-8, 8-12, 12-0.
    const B bright_pairs = V::andb(V::orb(b0, b8), V::orb(b4, b12));
    const B dark_pairs = V::andb(V::orb(d0, d8), V::orb(d4, d12));
    const bool maybe_bright = V::anyb(bright_pairs);
    const bool maybe_dark = V::anyb(dark_pairs);
    if (!maybe_bright && !maybe_dark) {
      V::storeb(scores + x, zero);
      continue;
    }

    // Only the sides that passed the quick test are measured; the other contributes 0, which
    // no corner's contrast (> t >= 0) can be beaten by.
    B circle_pixels[16];
#pragma GCC unroll 16
    for (int k = 0; k < 16; ++k) circle_pixels[k] = V::loadb(p + circle[k]);
    B contrast = zero;
    if (maybe_dark) {
      contrast = V::subsb(v, fast_best_arc<V, V::maxb, V::minb>(circle_pixels));
    }
    if (maybe_bright) {
      contrast = V::maxb(contrast, V::subsb(fast_best_arc<V, V::minb, V::maxb>(circle_pixels), v));
    }
    const B is_corner = V::gtb(contrast, t);
    V::storeb(scores + x, V::andb(is_corner, V::subb(contrast, one)));
    // The bits of the lanes the vector before already listed (the last vector overlaps it).
    const int listed = (next - x) * V::kBitsPerLaneB;
    for (typename V::LaneBits corners = V::bitsb(is_corner) >> listed << listed; corners != 0;
         corners &= corners - 1) {
      columns[count++] = x + std::countr_zero(corners) / V::kBitsPerLaneB;
    }
  }
  return count;
}

}  // namespace epipole::vision::kernels

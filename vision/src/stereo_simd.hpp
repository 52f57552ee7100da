#pragma once

// The stereo kernels written once over a vector vocabulary of unsigned 16-bit lanes
// (simd/neon_u16.hpp, simd/avx2_u16.hpp). Each gives the same bits as its *_ref in stereo.cpp.
#include <algorithm>
#include <cstdint>

#include "epipole/vision/stereo.hpp"
#include "stereo_census.hpp"

namespace epipole::vision::kernels {

// The census of the kLanes pixels from x, whose columns x - 4 .. x + kLanes + 3 are readable.
template <typename V>
inline void census_vector(const std::uint8_t* const* rows, int x, std::uint16_t* lo,
                          std::uint16_t* hi) {
  using Vec = typename V::Vec;
  Vec l = V::zero();
  Vec h = V::zero();
  for (int b = 0; b < kCensusBits; ++b) {
    const CensusOffset o = kCensusOffsets[b];
    const Vec a = V::load_u8(rows[kCensusRadiusY + o.dy] + x + o.dx);
    const Vec c = V::load_u8(rows[kCensusRadiusY - o.dy] + x - o.dx);
    const Vec bit = V::bit_and(V::gt_small(a, c),
                               V::splat(static_cast<std::uint16_t>(1u << (b < 16 ? b : b - 16))));
    if (b < 16) {
      l = V::bit_or(l, bit);
    } else {
      h = V::bit_or(h, bit);
    }
  }
  V::store(lo, l);
  V::store(hi, h);
}

template <typename V>
void census_row_simd(const std::uint8_t* const* rows, int width, std::uint16_t* lo,
                     std::uint16_t* hi) {
  constexpr int kR = kCensusRadiusX;
  if (width < V::kLanes + 2 * kR) {
    for (int x = 0; x < width; ++x) census_pixel(rows, width, x, lo, hi);
    return;
  }
  // Interior columns [kR, width - kR); the last vector may overlap the previous one.
  const int end = width - kR;
  for (int x = kR; x < end; x += V::kLanes) {
    const int at = std::min(x, end - V::kLanes);
    census_vector<V>(rows, at, lo + at, hi + at);
  }
  // The kR border columns on each side: one vector over a copy of the rows with the columns
  // clamped, the same values census_pixel reads.
  constexpr int kSpan = V::kLanes + 2 * kR;
  std::uint8_t copy[7][kSpan];
  const std::uint8_t* copy_rows[7];
  std::uint16_t l[V::kLanes];
  std::uint16_t h[V::kLanes];
  for (const int first : {0, width - V::kLanes}) {  // image column of lane 0
    for (int r = 0; r < 7; ++r) {
      for (int i = 0; i < kSpan; ++i)
        copy[r][i] = rows[r][std::clamp(first - kR + i, 0, width - 1)];
      copy_rows[r] = copy[r];
    }
    census_vector<V>(copy_rows, kR, l, h);
    const int begin = first == 0 ? 0 : width - kR;
    for (int x = begin; x < begin + kR; ++x) {
      lo[x] = l[x - first];
      hi[x] = h[x - first];
    }
  }
}

template <typename V>
void cost_row_simd(const std::uint16_t* left_lo, const std::uint16_t* left_hi,
                   const std::uint16_t* right_lo, const std::uint16_t* right_hi, int width,
                   int disparities, std::uint16_t* cost) {
  using Vec = typename V::Vec;
  for (int x = 0; x < width; ++x) {
    const Vec l = V::splat(left_lo[x]);
    const Vec h = V::splat(left_hi[x]);
    const std::uint16_t* rl = right_lo + (width - 1 - x);
    const std::uint16_t* rh = right_hi + (width - 1 - x);
    std::uint16_t* out = cost + static_cast<std::ptrdiff_t>(x) * disparities;
    for (int d = 0; d < disparities; d += V::kLanes) {
      V::store(out + d,
               V::popcount2(V::bit_xor(l, V::load(rl + d)), V::bit_xor(h, V::load(rh + d))));
    }
  }
}

// One path step for kLanes disparities at d: c + min(p[d], p[d-1] + P1, p[d+1] + P1,
// min_prev + P2) - min_prev.
template <typename V>
inline typename V::Vec sgm_step(typename V::Vec c, const std::uint16_t* p, typename V::Vec p1,
                                typename V::Vec min_p2, typename V::Vec min_prev) {
  const typename V::Vec best =
      V::min(V::min(V::load(p), min_p2), V::add(V::min(V::load(p - 1), V::load(p + 1)), p1));
  return V::sub(V::add(c, best), min_prev);
}

template <typename V>
void sgm_row_simd(const SgmRow& r) {
  using Vec = typename V::Vec;
  const int D = r.disparities;
  const std::ptrdiff_t stride = D + 16;
  const Vec p1 = V::splat(static_cast<std::uint16_t>(r.p1));
  const std::uint16_t p2 = static_cast<std::uint16_t>(r.p2);
  std::uint16_t* h[2] = {r.scratch + 8, r.scratch + stride + 8};
  for (std::uint16_t* e : h) {
    e[-1] = kSgmPad;
    e[D] = kSgmPad;
  }
  constexpr int kDx[3] = {0, -1, 1};

  // Left to right, with the three paths from the previous row.
  for (int d = 0; d < D; ++d) h[0][d] = 0;
  std::uint16_t h_min = 0;
  for (int x = 0; x < r.width; ++x) {
    const std::uint16_t* c = r.cost + static_cast<std::ptrdiff_t>(x) * D;
    const std::uint16_t* p[3];
    Vec min_prev[3];
    Vec min_p2[3];
    std::uint16_t* q[3];
    Vec mins[4];
    for (int k = 0; k < 3; ++k) {
      p[k] = r.prev[k] + (x + kDx[k] + 1) * stride + 8;
      const std::uint16_t m = r.prev_min[k][x + kDx[k] + 1];
      min_prev[k] = V::splat(m);
      min_p2[k] = V::splat(static_cast<std::uint16_t>(m + p2));
      q[k] = r.cur[k] + (x + 1) * stride + 8;
      mins[k] = V::splat(0xFFFF);
    }
    mins[3] = V::splat(0xFFFF);
    const Vec h_prev = V::splat(h_min);
    const Vec h_p2 = V::splat(static_cast<std::uint16_t>(h_min + p2));
    std::uint16_t* s = r.sums + static_cast<std::ptrdiff_t>(x) * D;
    for (int d = 0; d < D; d += V::kLanes) {
      const Vec cost = V::load(c + d);
      const Vec lr = sgm_step<V>(cost, h[0] + d, p1, h_p2, h_prev);
      V::store(h[1] + d, lr);
      mins[3] = V::min(mins[3], lr);
      Vec sum = lr;
#pragma GCC unroll 3
      for (int k = 0; k < 3; ++k) {
        const Vec v = sgm_step<V>(cost, p[k] + d, p1, min_p2[k], min_prev[k]);
        V::store(q[k] + d, v);
        mins[k] = V::min(mins[k], v);
        sum = V::add(sum, v);
      }
      V::store(s + d, sum);
    }
    for (int k = 0; k < 3; ++k) r.cur_min[k][x + 1] = V::hmin(mins[k]);
    h_min = V::hmin(mins[3]);
    std::uint16_t* t = h[0];
    h[0] = h[1];
    h[1] = t;
  }

  // Right to left.
  for (int d = 0; d < D; ++d) h[0][d] = 0;
  h_min = 0;
  for (int x = r.width - 1; x >= 0; --x) {
    const std::uint16_t* c = r.cost + static_cast<std::ptrdiff_t>(x) * D;
    std::uint16_t* s = r.sums + static_cast<std::ptrdiff_t>(x) * D;
    const Vec h_prev = V::splat(h_min);
    const Vec h_p2 = V::splat(static_cast<std::uint16_t>(h_min + p2));
    Vec m = V::splat(0xFFFF);
    for (int d = 0; d < D; d += V::kLanes) {
      const Vec rl = sgm_step<V>(V::load(c + d), h[0] + d, p1, h_p2, h_prev);
      V::store(h[1] + d, rl);
      m = V::min(m, rl);
      V::store(s + d, V::add(V::load(s + d), rl));
    }
    h_min = V::hmin(m);
    std::uint16_t* t = h[0];
    h[0] = h[1];
    h[1] = t;
  }
}

template <typename V>
void wta_row_simd(std::uint16_t* sums, int width, int D, int uniqueness, std::int16_t* disparity,
                  std::int16_t* best_out, std::uint16_t* right_min, std::uint16_t* right_disp) {
  using Vec = typename V::Vec;
  const Vec iota = V::iota();
  const std::uint32_t ratio = uniqueness_ratio(uniqueness);
  for (int x = 0; x < width; ++x) {
    std::uint16_t* s = sums + static_cast<std::ptrdiff_t>(x) * D;
    // Per lane: the smallest cost and its first disparity.
    Vec m = V::splat(0xFFFF);
    Vec m_index = V::zero();
    for (int d = 0; d < D; d += V::kLanes) {
      const Vec v = V::load(s + d);
      const Vec index = V::add(iota, V::splat(static_cast<std::uint16_t>(d)));
      m_index = V::select(V::gt(m, v), index, m_index);
      m = V::min(m, v);
    }
    const std::uint16_t min_cost = V::hmin(m);
    const int best = V::hmin(V::select(V::eq(m, V::splat(min_cost)), m_index, V::splat(0xFFFF)));
    const int below = best > 0 ? s[best - 1] : 0;
    const int above = best < D - 1 ? s[best + 1] : 0;
    bool unique = true;
    const int limit = uniqueness_limit(min_cost, ratio);
    if (limit > 0) {
      const int threshold = std::min(limit - 1, 0xFFFE);
      // Disparities best - 1 .. best + 1 do not compete: they are set to 0xFFFF, above any
      // threshold, in registers (storing them would stall the loads that follow).
      const Vec first_near = V::splat(static_cast<std::uint16_t>(best - 1));
      const Vec three = V::splat(3);
      const Vec t = V::splat(static_cast<std::uint16_t>(threshold));
      Vec hit = V::zero();
      for (int d = 0; d < D; d += V::kLanes) {
        const Vec index = V::add(iota, V::splat(static_cast<std::uint16_t>(d)));
        const Vec near = V::gt(three, V::sub(index, first_near));
        const Vec v = V::bit_or(V::load(s + d), near);
        hit = V::bit_or(hit, V::eq(V::min(v, t), v));
      }
      unique = !V::any(hit);
    }
    if (!unique || best > x) {
      disparity[x] = kInvalidDisparity;
      best_out[x] = -1;
    } else {
      disparity[x] = static_cast<std::int16_t>(subpixel(best, D, below, min_cost, above));
      best_out[x] = static_cast<std::int16_t>(best);
    }
  }

  // The best disparity of each right pixel: the smallest cost, the smallest d among equal
  // costs, so the order of x does not matter. Consecutive x overlap by all but one value, so x
  // goes in steps of kStep, letting each store retire before an overlapping load.
  constexpr int kStep = 16;
  for (int start = 0; start < kStep; ++start) {
    for (int x = start; x < width; x += kStep) {
      const std::uint16_t* s = sums + static_cast<std::ptrdiff_t>(x) * D;
      std::uint16_t* rm = right_min + (width - 1 - x);
      std::uint16_t* rd = right_disp + (width - 1 - x);
      for (int d = 0; d < D; d += V::kLanes) {
        const Vec v = V::load(s + d);
        const Vec index = V::add(iota, V::splat(static_cast<std::uint16_t>(d)));
        const Vec old = V::load(rm + d);
        const Vec old_d = V::load(rd + d);
        const Vec better = V::bit_or(V::gt(old, v), V::bit_and(V::eq(old, v), V::gt(old_d, index)));
        V::store(rm + d, V::select(better, v, old));
        V::store(rd + d, V::select(better, index, old_d));
      }
    }
  }
}

template <typename V>
void box_columns_simd(std::uint16_t* sums, const std::uint16_t* add, const std::uint16_t* sub,
                      int n) {
  int i = 0;
  if (add != nullptr && sub != nullptr) {
    for (; i + V::kLanes <= n; i += V::kLanes) {
      V::store(sums + i, V::sub(V::add(V::load(sums + i), V::load(add + i)), V::load(sub + i)));
    }
    for (; i < n; ++i) sums[i] = static_cast<std::uint16_t>(sums[i] + add[i] - sub[i]);
  } else if (add != nullptr) {
    for (; i + V::kLanes <= n; i += V::kLanes) {
      V::store(sums + i, V::add(V::load(sums + i), V::load(add + i)));
    }
    for (; i < n; ++i) sums[i] = static_cast<std::uint16_t>(sums[i] + add[i]);
  } else if (sub != nullptr) {
    for (; i + V::kLanes <= n; i += V::kLanes) {
      V::store(sums + i, V::sub(V::load(sums + i), V::load(sub + i)));
    }
    for (; i < n; ++i) sums[i] = static_cast<std::uint16_t>(sums[i] - sub[i]);
  }
}

template <typename V>
void box_row_simd(const std::uint16_t* columns, int width, int D, int radius, std::uint16_t* sums) {
  using Vec = typename V::Vec;
  for (int d = 0; d < D; d += V::kLanes) {
    Vec acc = V::zero();
    for (int x = 0; x <= radius && x < width; ++x) {
      acc = V::add(acc, V::load(columns + static_cast<std::ptrdiff_t>(x) * D + d));
    }
    V::store(sums + d, acc);
    for (int x = 1; x < width; ++x) {
      if (x + radius < width) {
        acc = V::add(acc, V::load(columns + static_cast<std::ptrdiff_t>(x + radius) * D + d));
      }
      if (x - radius - 1 >= 0) {
        acc = V::sub(acc, V::load(columns + static_cast<std::ptrdiff_t>(x - radius - 1) * D + d));
      }
      V::store(sums + static_cast<std::ptrdiff_t>(x) * D + d, acc);
    }
  }
}

}  // namespace epipole::vision::kernels

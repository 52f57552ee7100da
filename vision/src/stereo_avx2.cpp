// The stereo kernels with AVX2, 16 disparities at a time (bytes in SSE registers, 16-bit sums
// in AVX registers): the generic kernels of stereo_simd.hpp; the cost row and SGM's path steps
// 32 disparities at a time in AVX registers (x86 hosts only).
#include "simd/avx2.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

namespace {

// kBits: the census bits compared (kCensusBits, or kSparseCensusBits: planes 0 and 1 alone).
template <int kBits>
void cost_row_bits_avx2(const std::uint8_t* left, const std::uint8_t* right, int width,
                        int disparities, std::uint8_t* cost) {
  using V = simd::Avx2x16;
  constexpr bool kFour = kBits > 16;
  const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2,
                                         1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i low = _mm256_set1_epi8(0x0F);
  // popcount(l ^ r) per byte, r loaded from p.
  const auto count = [&](__m256i l, const std::uint8_t* p) {
    const __m256i v = _mm256_xor_si256(l, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)));
    return _mm256_add_epi8(
        _mm256_shuffle_epi8(table, _mm256_and_si256(v, low)),
        _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(v, 4), low)));
  };
  // The plane pointers in registers: read through the caller's arrays in the loop, they were
  // reloaded and the splats went through the stack, which took half of this kernel's time.
  const std::ptrdiff_t n = width;
  const std::ptrdiff_t padded = n + disparities;
  const std::uint8_t* const l0 = left;
  const std::uint8_t* const l1 = left + n;
  const std::uint8_t* const l2 = left + 2 * n;
  const std::uint8_t* const l3 = left + 3 * n;
  const std::uint8_t* const r0 = right;
  const std::uint8_t* const r1 = right + padded;
  const std::uint8_t* const r2 = right + 2 * padded;
  const std::uint8_t* const r3 = right + 3 * padded;
  for (int x = 0; x < width; ++x) {
    const auto splat = [](std::uint8_t v) { return _mm256_set1_epi8(static_cast<char>(v)); };
    const __m256i l[kCensusBytes] = {splat(l0[x]), splat(l1[x]),
                                     kFour ? splat(l2[x]) : _mm256_setzero_si256(),
                                     kFour ? splat(l3[x]) : _mm256_setzero_si256()};
    const std::ptrdiff_t k = width - 1 - x;
    std::uint8_t* out = cost + static_cast<std::ptrdiff_t>(x) * disparities;
    // Disparities past x (beyond the left border) cost the most: filled below, not computed.
    const int computed = std::min(disparities, x + 1);
    int d = 0;
    for (; d + 32 <= disparities && d < computed; d += 32) {
      __m256i sum = _mm256_add_epi8(count(l[0], r0 + k + d), count(l[1], r1 + k + d));
      if constexpr (kFour) {
        sum =
            _mm256_add_epi8(sum, _mm256_add_epi8(count(l[2], r2 + k + d), count(l[3], r3 + k + d)));
      }
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + d), sum);
    }
    if (d < computed && disparities - d == 16) {  // 16 left
      const auto half = [&](__m256i l_p, const std::uint8_t* r_p) {
        return V::xorb(_mm256_castsi256_si128(l_p), V::loadb(r_p + k + d));
      };
      V::storeb(out + d,
                kFour ? V::popcount4(half(l[0], r0), half(l[1], r1), half(l[2], r2), half(l[3], r3))
                      : V::popcount2(half(l[0], r0), half(l[1], r1)));
    }
    if (x < disparities - 1) {  // beyond the left border
      std::fill(out + x + 1, out + disparities, static_cast<std::uint8_t>(kBits));
    }
  }
}

void cost_row_avx2(const std::uint8_t* left, const std::uint8_t* right, int width, int disparities,
                   int bits, std::uint8_t* cost) {
  with_census_bits(bits, [&](auto compared) {
    cost_row_bits_avx2<compared.value>(left, right, width, disparities, cost);
  });
}

__m256i load32(const std::uint8_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}
void store32(void* p, __m256i v) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
}

// sgm_step (stereo_simd.hpp) for 32 disparities, with min_prev subtracted before the minimum
// rather than after it: min(p[d] - m, min(p[d - 1], p[d + 1]) - m + P1, P2) + c, m = min_prev.
// The same bytes: every path value is at least m (the pads too), so the differences are exact,
// and where a saturating add of the original would saturate, its term is at least p[d] - m here
// as there and is not the minimum. P2 is one constant for every path, which leaves registers
// for the loop (16 on AVX2: the per-path min_prev + P2 spilled).
__m256i sgm_step32(__m256i c, const std::uint8_t* p, __m256i p1, __m256i p2, __m256i min_prev) {
  const __m256i side = _mm256_min_epu8(load32(p - 1), load32(p + 1));
  const __m256i best = _mm256_min_epu8(_mm256_min_epu8(_mm256_sub_epi8(load32(p), min_prev), p2),
                                       _mm256_adds_epu8(_mm256_sub_epi8(side, min_prev), p1));
  return _mm256_add_epi8(best, c);
}

// The smallest of v's 32 bytes in every byte, without leaving the vector unit: it is the
// horizontal path's step from one pixel to the next, and its latency is the loop's.
__m256i broadcast_min32(__m256i v) {
  v = _mm256_min_epu8(v, _mm256_permute2x128_si256(v, v, 0x01));
  v = _mm256_min_epu8(v, _mm256_shuffle_epi32(v, _MM_SHUFFLE(1, 0, 3, 2)));
  v = _mm256_min_epu8(v, _mm256_shuffle_epi32(v, _MM_SHUFFLE(2, 3, 0, 1)));
  v = _mm256_min_epu8(v, _mm256_srli_epi32(v, 16));
  v = _mm256_min_epu8(v, _mm256_srli_epi16(v, 8));
  return _mm256_shuffle_epi8(v, _mm256_setzero_si256());  // byte 0 of each half
}

// The smallest byte of each of a, b, c and d, in bytes 0, 1, 2 and 3: interleaved and halved,
// so that the four reductions share their steps.
std::uint32_t hmin32x4(__m256i a, __m256i b, __m256i c, __m256i d) {
  const __m256i ab = _mm256_min_epu8(_mm256_unpacklo_epi8(a, b), _mm256_unpackhi_epi8(a, b));
  const __m256i cd = _mm256_min_epu8(_mm256_unpacklo_epi8(c, d), _mm256_unpackhi_epi8(c, d));
  const __m256i abcd =
      _mm256_min_epu8(_mm256_unpacklo_epi16(ab, cd), _mm256_unpackhi_epi16(ab, cd));
  __m128i v = _mm_min_epu8(_mm256_castsi256_si128(abcd), _mm256_extracti128_si256(abcd, 1));
  v = _mm_min_epu8(v, _mm_srli_si128(v, 8));
  v = _mm_min_epu8(v, _mm_srli_si128(v, 4));
  return static_cast<std::uint32_t>(_mm_cvtsi128_si32(v));
}

// sgm_first_pass_simd for a range that is a multiple of 32: the same steps, 32 lanes at a time.
// The four paths' bytes are added in 16 bits two at a time: interleaved, then multiplied by 1
// and added pairwise (maddubs), which leaves disparities 0..7 and 16..23 in one register and
// 8..15 and 24..31 in the other until the halves are swapped back. kD: the range when fixed at
// compile time (0: r's).
template <int kD>
void sgm_first_pass_avx2(const SgmRow& r) {
  const int D = kD != 0 ? kD : r.disparities;
  const __m256i p1 = _mm256_set1_epi8(static_cast<char>(r.p1));
  const __m256i p2 = _mm256_set1_epi8(static_cast<char>(r.p2));
  const __m256i ones = _mm256_set1_epi8(1);
  const auto splat = [](int v) { return _mm256_set1_epi8(static_cast<char>(v)); };
  std::uint8_t* h[2];
  sgm_horizontal_rows(r, h);
  int h_min = 0;
  for (int x = r.width - 1; x >= 0; --x) {
    const std::uint8_t* c = r.cost + static_cast<std::ptrdiff_t>(x) * D;
    const SgmDownPaths paths(r, x);
    const std::uint8_t* const* p = paths.prev;
    std::uint8_t* const* q = paths.cur;
    __m256i min_prev[3];
    __m256i mins[4];
    for (int k = 0; k < 3; ++k) {
      min_prev[k] = splat(paths.prev_min[k]);
      mins[k] = splat(0xFF);
    }
    mins[3] = splat(0xFF);
    const __m256i h_prev = splat(h_min);
    std::uint16_t* s = r.sums + static_cast<std::ptrdiff_t>(x) * D;
    for (int d = 0; d < D; d += 32) {
      const __m256i cost = load32(c + d);
      const __m256i rl = sgm_step32(cost, h[0] + d, p1, p2, h_prev);
      store32(h[1] + d, rl);
      mins[3] = _mm256_min_epu8(mins[3], rl);
      __m256i v[3];
#pragma GCC unroll 3
      for (int k = 0; k < 3; ++k) {
        v[k] = sgm_step32(cost, p[k] + d, p1, p2, min_prev[k]);
        store32(q[k] + d, v[k]);
        mins[k] = _mm256_min_epu8(mins[k], v[k]);
      }
      const auto pair_sums = [&](__m256i a, __m256i b, __m256i& low, __m256i& high) {
        low = _mm256_maddubs_epi16(_mm256_unpacklo_epi8(a, b), ones);
        high = _mm256_maddubs_epi16(_mm256_unpackhi_epi8(a, b), ones);
      };
      __m256i low_a, high_a, low_b, high_b;
      pair_sums(rl, v[0], low_a, high_a);
      pair_sums(v[1], v[2], low_b, high_b);
      const __m256i low = _mm256_add_epi16(low_a, low_b);     // 0..7, 16..23
      const __m256i high = _mm256_add_epi16(high_a, high_b);  // 8..15, 24..31
      store32(s + d, _mm256_permute2x128_si256(low, high, 0x20));
      store32(s + d + 16, _mm256_permute2x128_si256(low, high, 0x31));
    }
    const std::uint32_t minima = hmin32x4(mins[0], mins[1], mins[2], mins[3]);
    for (int k = 0; k < 3; ++k) r.cur_min[k][x + 1] = static_cast<std::uint8_t>(minima >> (8 * k));
    h_min = static_cast<int>(minima >> 24);
    std::swap(h[0], h[1]);
  }
}

// sgm_second_pass_simd for a range that is a multiple of 32: the path step 32 lanes at a time,
// the sums and the winner 16 at a time as there.
template <int kD>
void sgm_second_pass_avx2(const SgmRow& r) {
  using V = simd::Avx2x16;
  const int D = kD != 0 ? kD : r.disparities;
  const int width = r.width;
  const __m256i p1 = _mm256_set1_epi8(static_cast<char>(r.p1));
  const __m256i p2 = _mm256_set1_epi8(static_cast<char>(r.p2));
  const std::uint8_t* const cost = r.cost;  // in locals: see sgm_first_pass_simd
  std::uint16_t* const sums = r.sums;
  std::uint8_t* h[2];
  sgm_horizontal_rows(r, h);
  WtaPixels<V, kD, true> wta(r.wta, width, D);  // SGM's sums are at most 5 * 255
  __m256i h_prev = _mm256_setzero_si256();
  for (int x = 0; x < width; ++x) {
    const std::uint8_t* c = cost + static_cast<std::ptrdiff_t>(x) * D;
    std::uint16_t* s = sums + static_cast<std::ptrdiff_t>(x) * D;
    __m256i m = _mm256_set1_epi8(-1);
    __m256i step = _mm256_setzero_si256();  // disparities d & ~31 ..
    wta.pixel(x, s, [&](int d) {
      __m128i half;
      if (d % 32 == 0) {
        step = sgm_step32(load32(c + d), h[0] + d, p1, p2, h_prev);
        store32(h[1] + d, step);
        m = _mm256_min_epu8(m, step);
        half = _mm256_castsi256_si128(step);
      } else {
        half = _mm256_extracti128_si256(step, 1);
      }
      const V::H sum = V::addw(V::loadh(s + d), half);
      V::storeh(s + d, sum);
      return sum;
    });
    h_prev = broadcast_min32(m);
    std::swap(h[0], h[1]);
  }
  wta.finish();
}

void sgm_row_avx2(const SgmRow& r) {
  with_common_range(r.disparities, [&](auto range) {
    if (r.disparities % 32 == 0) {
      sgm_first_pass_avx2<range.value>(r);
      sgm_second_pass_avx2<range.value>(r);
    } else {
      sgm_first_pass_simd<simd::Avx2x16, range.value>(r);
      sgm_second_pass_simd<simd::Avx2x16, range.value>(r);
    }
  });
}

}  // namespace

StereoKernels stereo_kernels_avx2() {
  constexpr CensusLayout kLayout = CensusLayout::planes;
  return {kLayout,      census_row_simd<simd::Avx2x16, kLayout>, cost_row_avx2,
          sgm_row_avx2, box_columns_simd<simd::Avx2x16>,         bm_row_simd<simd::Avx2x16>};
}

}  // namespace epipole::vision::kernels

// The stereo kernels with AVX2, 16 disparities at a time (bytes in SSE registers, 16-bit sums
// in AVX registers): the generic kernels of stereo_simd.hpp; the cost row 32 disparities at a
// time in AVX registers (x86 hosts only).
#include "simd/avx2.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

namespace {

void cost_row_avx2(const std::uint8_t* const* left, const std::uint8_t* const* right, int width,
                   int disparities, std::uint8_t* cost) {
  using V = simd::Avx2x16;
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
  // The plane pointers in registers: read through `left` and `right` in the loop, they were
  // reloaded and the splats went through the stack, which took half of this kernel's time.
  const std::uint8_t* const l0 = left[0];
  const std::uint8_t* const l1 = left[1];
  const std::uint8_t* const l2 = left[2];
  const std::uint8_t* const l3 = left[3];
  const std::uint8_t* const r0 = right[0];
  const std::uint8_t* const r1 = right[1];
  const std::uint8_t* const r2 = right[2];
  const std::uint8_t* const r3 = right[3];
  for (int x = 0; x < width; ++x) {
    const __m256i l[kCensusPlanes] = {
        _mm256_set1_epi8(static_cast<char>(l0[x])), _mm256_set1_epi8(static_cast<char>(l1[x])),
        _mm256_set1_epi8(static_cast<char>(l2[x])), _mm256_set1_epi8(static_cast<char>(l3[x]))};
    const std::ptrdiff_t k = width - 1 - x;
    std::uint8_t* out = cost + static_cast<std::ptrdiff_t>(x) * disparities;
    int d = 0;
    for (; d + 32 <= disparities; d += 32) {
      const __m256i sum =
          _mm256_add_epi8(_mm256_add_epi8(count(l[0], r0 + k + d), count(l[1], r1 + k + d)),
                          _mm256_add_epi8(count(l[2], r2 + k + d), count(l[3], r3 + k + d)));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + d), sum);
    }
    if (d < disparities) {  // 16 left
      const auto half = [&](int p) {
        return V::xorb(_mm256_castsi256_si128(l[p]), V::loadb(right[p] + k + d));
      };
      V::storeb(out + d, V::popcount4(half(0), half(1), half(2), half(3)));
    }
    if (x < disparities - 1) {  // beyond the left border
      std::fill(out + x + 1, out + disparities, static_cast<std::uint8_t>(kMaxCensusCost));
    }
  }
}

}  // namespace

StereoKernels stereo_kernels_avx2() {
  return {census_row_simd<simd::Avx2x16>, cost_row_avx2, sgm_row_simd<simd::Avx2x16>,
          box_columns_simd<simd::Avx2x16>, bm_row_simd<simd::Avx2x16>};
}

}  // namespace epipole::vision::kernels

#pragma once

// 16 unsigned 16-bit lanes per vector with AVX2, in the vocabulary of the stereo kernels
// (stereo_simd.hpp). Only for translation units compiled with -mavx2 (x86 hosts).
#include <immintrin.h>

#include <cstdint>

namespace epipole::vision::simd {

struct Avx2U16 {
  using Vec = __m256i;
  static constexpr int kLanes = 16;

  static Vec load(const std::uint16_t* p) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  }
  static void store(std::uint16_t* p, Vec v) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
  }
  static Vec load_u8(const std::uint8_t* p) {
    return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
  }
  static Vec splat(std::uint16_t v) { return _mm256_set1_epi16(static_cast<short>(v)); }
  static Vec zero() { return _mm256_setzero_si256(); }
  static Vec add(Vec a, Vec b) { return _mm256_add_epi16(a, b); }
  static Vec sub(Vec a, Vec b) { return _mm256_sub_epi16(a, b); }
  static Vec min(Vec a, Vec b) { return _mm256_min_epu16(a, b); }
  static Vec bit_and(Vec a, Vec b) { return _mm256_and_si256(a, b); }
  static Vec bit_or(Vec a, Vec b) { return _mm256_or_si256(a, b); }
  static Vec bit_xor(Vec a, Vec b) { return _mm256_xor_si256(a, b); }
  // Unsigned a > b: a - b (saturating) is not zero.
  static Vec gt(Vec a, Vec b) {
    return _mm256_xor_si256(_mm256_cmpeq_epi16(_mm256_subs_epu16(a, b), _mm256_setzero_si256()),
                            _mm256_set1_epi16(-1));
  }
  static Vec gt_small(Vec a, Vec b) { return _mm256_cmpgt_epi16(a, b); }
  static Vec eq(Vec a, Vec b) { return _mm256_cmpeq_epi16(a, b); }
  static Vec select(Vec mask, Vec a, Vec b) { return _mm256_blendv_epi8(b, a, mask); }
  static Vec iota() {
    return _mm256_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  }
  static Vec popcount2(Vec a, Vec b) {
    const Vec table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2,
                                       1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
    const Vec low = _mm256_set1_epi8(0x0F);
    const Vec bytes = _mm256_add_epi8(
        _mm256_add_epi8(_mm256_shuffle_epi8(table, _mm256_and_si256(a, low)),
                        _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(a, 4), low))),
        _mm256_add_epi8(
            _mm256_shuffle_epi8(table, _mm256_and_si256(b, low)),
            _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(b, 4), low))));
    return _mm256_add_epi16(_mm256_and_si256(bytes, _mm256_set1_epi16(0xFF)),
                            _mm256_srli_epi16(bytes, 8));
  }
  static std::uint16_t hmin(Vec v) {
    const __m128i m = _mm_min_epu16(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    return static_cast<std::uint16_t>(_mm_extract_epi16(_mm_minpos_epu16(m), 0));
  }
  static bool any(Vec mask) { return _mm256_testz_si256(mask, mask) == 0; }
};

}  // namespace epipole::vision::simd

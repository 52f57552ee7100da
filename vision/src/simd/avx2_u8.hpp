#pragma once

// 32 unsigned bytes per vector with AVX2, in the vocabulary of the generic kernels
// (*_simd.hpp). Only for translation units compiled with -mavx2 (x86 hosts); chosen at run time
// when the CPU has AVX2.
#include <immintrin.h>

#include <cstdint>

namespace epipole::vision::simd {

struct Avx2U8 {
  using Vec = __m256i;
  static constexpr int kLanes = 32;

  static Vec load(const std::uint8_t* p) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  }
  static void store(std::uint8_t* p, Vec v) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
  }
  static Vec splat(std::uint8_t v) { return _mm256_set1_epi8(static_cast<char>(v)); }
  static Vec adds(Vec a, Vec b) { return _mm256_adds_epu8(a, b); }
  static Vec subs(Vec a, Vec b) { return _mm256_subs_epu8(a, b); }
  static Vec sub(Vec a, Vec b) { return _mm256_sub_epi8(a, b); }
  // Unsigned a > b: a - b (saturating) is not zero.
  static Vec gt(Vec a, Vec b) {
    const Vec not_greater = _mm256_cmpeq_epi8(_mm256_subs_epu8(a, b), _mm256_setzero_si256());
    return _mm256_xor_si256(not_greater, _mm256_set1_epi8(-1));
  }
  static Vec lt(Vec a, Vec b) { return gt(b, a); }
  static Vec bit_and(Vec a, Vec b) { return _mm256_and_si256(a, b); }
  static Vec bit_or(Vec a, Vec b) { return _mm256_or_si256(a, b); }
  static Vec min(Vec a, Vec b) { return _mm256_min_epu8(a, b); }
  static Vec max(Vec a, Vec b) { return _mm256_max_epu8(a, b); }
  static bool any(Vec mask) { return _mm256_testz_si256(mask, mask) == 0; }
  static std::uint32_t lane_bits(Vec mask) {
    return static_cast<std::uint32_t>(_mm256_movemask_epi8(mask));
  }
};

}  // namespace epipole::vision::simd

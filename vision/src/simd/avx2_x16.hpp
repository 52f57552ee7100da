#pragma once

// 16 lanes with AVX2, in the vocabulary of the stereo kernels (stereo_simd.hpp): B holds 16
// unsigned bytes in an SSE register, H the same 16 lanes as unsigned 16-bit values in an AVX
// register. Only for translation units compiled with -mavx2 (x86 hosts).
#include <immintrin.h>

#include <cstdint>

namespace epipole::vision::simd {

struct Avx2X16 {
  using B = __m128i;
  using H = __m256i;

  // Bytes.
  static B loadb(const std::uint8_t* p) {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  }
  static void storeb(std::uint8_t* p, B v) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
  static B splatb(std::uint8_t v) { return _mm_set1_epi8(static_cast<char>(v)); }
  static B zerob() { return _mm_setzero_si128(); }
  static B minb(B a, B b) { return _mm_min_epu8(a, b); }
  static B addb(B a, B b) { return _mm_add_epi8(a, b); }
  static B subb(B a, B b) { return _mm_sub_epi8(a, b); }
  static B addsb(B a, B b) { return _mm_adds_epu8(a, b); }
  static B xorb(B a, B b) { return _mm_xor_si128(a, b); }
  static B andb(B a, B b) { return _mm_and_si128(a, b); }
  static B maxb(B a, B b) { return _mm_max_epu8(a, b); }
  // Unsigned a > b: a - b saturates to 0 iff a <= b.
  static B gtb(B a, B b) {
    return _mm_xor_si128(_mm_cmpeq_epi8(_mm_subs_epu8(a, b), _mm_setzero_si128()),
                         _mm_set1_epi8(-1));
  }
  static B iotab() { return _mm_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15); }
  // acc with `bit` set in the lanes where a > c (unsigned: a - c saturates to 0 iff a <= c).
  static B set_if_greater(B acc, B a, B c, B bit) {
    const B not_greater = _mm_cmpeq_epi8(_mm_subs_epu8(a, c), _mm_setzero_si128());
    return _mm_or_si128(acc, _mm_andnot_si128(not_greater, bit));
  }
  // Per lane: popcount(a) + popcount(b) + popcount(c) + popcount(d), nibbles looked up with
  // pshufb, two planes per AVX register.
  static B popcount4(B a, B b, B c, B d) {
    const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1,
                                           2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
    const __m256i low = _mm256_set1_epi8(0x0F);
    const auto count = [&](__m256i v) {
      return _mm256_add_epi8(
          _mm256_shuffle_epi8(table, _mm256_and_si256(v, low)),
          _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(v, 4), low)));
    };
    const __m256i sum =
        _mm256_add_epi8(count(_mm256_set_m128i(b, a)), count(_mm256_set_m128i(d, c)));
    return _mm_add_epi8(_mm256_castsi256_si128(sum), _mm256_extracti128_si256(sum, 1));
  }
  static std::uint8_t hminb(B v) {
    const __m128i pairs = _mm_min_epu8(v, _mm_srli_epi16(v, 8));
    const __m128i words = _mm_and_si128(pairs, _mm_set1_epi16(0xFF));
    return static_cast<std::uint8_t>(_mm_extract_epi16(_mm_minpos_epu16(words), 0));
  }

  // 16-bit values.
  static H loadh(const std::uint16_t* p) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  }
  static void storeh(std::uint16_t* p, H v) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
  }
  static H splath(std::uint16_t v) { return _mm256_set1_epi16(static_cast<short>(v)); }
  static H widen(B v) { return _mm256_cvtepu8_epi16(v); }
  static H addw(H a, B b) { return _mm256_add_epi16(a, _mm256_cvtepu8_epi16(b)); }
  static H addh(H a, H b) { return _mm256_add_epi16(a, b); }
  static H subh(H a, H b) { return _mm256_sub_epi16(a, b); }
  static H minh(H a, H b) { return _mm256_min_epu16(a, b); }
  static H orh(H a, H b) { return _mm256_or_si256(a, b); }
  // a > b for values below 0x8000.
  static H gth(H a, H b) { return _mm256_cmpgt_epi16(a, b); }
  static H eqh(H a, H b) { return _mm256_cmpeq_epi16(a, b); }
  static H selecth(H mask, H a, H b) { return _mm256_blendv_epi8(b, a, mask); }
  static H iotah() {
    return _mm256_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  }
  // Lane 15 of prev, then lanes 0..14 of cur: a window moved up by one lane.
  static H shift_in(H prev, H cur) {
    return _mm256_alignr_epi8(cur, _mm256_permute2x128_si256(prev, cur, 0x21), 14);
  }
  static std::uint16_t last(H v) { return static_cast<std::uint16_t>(_mm256_extract_epi16(v, 15)); }
  static std::uint16_t hminh(H v) {
    const __m128i m = _mm_min_epu16(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    return static_cast<std::uint16_t>(_mm_extract_epi16(_mm_minpos_epu16(m), 0));
  }
  // The sum of the lanes, for sums below 2^16.
  static std::uint32_t hsumh(H v) {
    __m128i x = _mm_add_epi16(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    x = _mm_add_epi16(x, _mm_srli_si128(x, 8));
    x = _mm_add_epi16(x, _mm_srli_si128(x, 4));
    x = _mm_add_epi16(x, _mm_srli_si128(x, 2));
    return static_cast<std::uint32_t>(_mm_extract_epi16(x, 0));
  }
  static bool anyh(H mask) { return _mm256_testz_si256(mask, mask) == 0; }
};

}  // namespace epipole::vision::simd

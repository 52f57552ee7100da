#pragma once

// 8 windows per vector with AVX2 (x86 hosts, its own -mavx2 file), in the vocabulary of the
// cascade window kernel (cascade_simd.hpp).
#include <immintrin.h>

#include <cstdint>

namespace epipole::vision::simd {

struct Avx2Cascade {
  static constexpr int kLanes = 8;
  using I = __m256i;
  using F = __m256;
  using M = __m256i;
  struct Acc {
    __m256i low;   // lanes 0..3
    __m256i high;  // lanes 4..7
  };

  static I load(const std::uint32_t* p) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  }
  static I add(I a, I b) { return _mm256_add_epi32(a, b); }
  static I sub(I a, I b) { return _mm256_sub_epi32(a, b); }
  static F to_float(I a) { return _mm256_cvtepi32_ps(a); }
  static F splat(float v) { return _mm256_set1_ps(v); }
  static F mul(F a, F b) { return _mm256_mul_ps(a, b); }
  static F add(F a, F b) { return _mm256_add_ps(a, b); }
  static M less(F a, F b) { return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_LT_OQ)); }
  static M greater_equal(I a, I b) {
    return _mm256_xor_si256(_mm256_cmpgt_epi32(b, a), _mm256_set1_epi32(-1));
  }
  static I mask_to(M m, int value) { return _mm256_and_si256(m, _mm256_set1_epi32(value)); }
  static M bit_and(M a, M b) { return _mm256_and_si256(a, b); }
  static unsigned bits(M m) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(m)));
  }
  static M from_bits(unsigned bits) {
    const __m256i lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    return _mm256_cmpeq_epi32(
        _mm256_and_si256(_mm256_set1_epi32(static_cast<int>(bits)), lane_bits), lane_bits);
  }

  // nf = area * squares - sum^2 exactly in int64 lanes, then OpenCV's double steps in vectors
  // (IEEE square root, division and rounding to float, as the scalar code).
  static void variance(I sum, I squares, double area, F& factor, M& ok) {
    const __m256i area64 = _mm256_set1_epi64x(static_cast<long long>(area));
    __m128 f[2];
    __m128i pass[2];
    for (int half = 0; half < 2; ++half) {
      const __m128i s = half == 0 ? _mm256_castsi256_si128(sum) : _mm256_extracti128_si256(sum, 1);
      const __m128i q =
          half == 0 ? _mm256_castsi256_si128(squares) : _mm256_extracti128_si256(squares, 1);
      const __m256i s64 = _mm256_cvtepi32_epi64(s);
      const __m256i q64 = _mm256_cvtepu32_epi64(q);
      const __m256i nf =
          _mm256_sub_epi64(_mm256_mul_epu32(q64, area64), _mm256_mul_epi32(s64, s64));
      const __m256i positive = _mm256_cmpgt_epi64(nf, _mm256_setzero_si256());
      // 0 <= nf < 2^52 to double: the integer in the mantissa of 2^52, minus 2^52.
      const __m256i magic = _mm256_set1_epi64x(0x4330000000000000LL);
      const __m256d nf_double =
          _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(_mm256_and_si256(nf, positive), magic)),
                        _mm256_castsi256_pd(magic));
      const __m256d one = _mm256_set1_pd(1.0);
      const __m256d inverse = _mm256_div_pd(
          one, _mm256_sqrt_pd(_mm256_blendv_pd(one, nf_double, _mm256_castsi256_pd(positive))));
      const __m128 f32 = _mm256_cvtpd_ps(inverse);
      const __m256d small = _mm256_cmp_pd(_mm256_mul_pd(_mm256_set1_pd(area), _mm256_cvtps_pd(f32)),
                                          _mm256_set1_pd(0.1), _CMP_LT_OQ);
      const __m256i good = _mm256_and_si256(positive, _mm256_castpd_si256(small));
      // The low 32 bits of each 64-bit mask.
      const __m256i packed =
          _mm256_permutevar8x32_epi32(good, _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6));
      pass[half] = _mm256_castsi256_si128(packed);
      f[half] = f32;
    }
    factor = _mm256_set_m128(f[1], f[0]);
    ok = _mm256_set_m128i(pass[1], pass[0]);
  }

  // Bit `code` of a 256-bit subset (32 bytes) for 8 codes in 0..255: byte code >> 3 by two
  // 16-byte table lookups (pshufb), tested against the bit code & 7 (a third lookup).
  static M subset_bit(const std::uint8_t* bytes, I code) {
    const __m256i low_table =
        _mm256_broadcastsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes)));
    const __m256i high_table =
        _mm256_broadcastsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes + 16)));
    const __m256i bit_table =
        _mm256_setr_epi8(1, 2, 4, 8, 16, 32, 64, -128, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 4, 8, 16, 32,
                         64, -128, 0, 0, 0, 0, 0, 0, 0, 0);
    // Indices in the low byte of each lane; the other three bytes 0x80 (pshufb gives 0).
    const __m256i upper_zero = _mm256_set1_epi32(static_cast<int>(0xFFFFFF00u));
    const __m256i byte_index = _mm256_srli_epi32(code, 3);
    const __m256i index =
        _mm256_or_si256(_mm256_and_si256(byte_index, _mm256_set1_epi32(15)), upper_zero);
    const __m256i from_high = _mm256_cmpgt_epi32(byte_index, _mm256_set1_epi32(15));
    const __m256i byte = _mm256_blendv_epi8(_mm256_shuffle_epi8(low_table, index),
                                            _mm256_shuffle_epi8(high_table, index), from_high);
    const __m256i bit = _mm256_shuffle_epi8(
        bit_table, _mm256_or_si256(_mm256_and_si256(code, _mm256_set1_epi32(7)), upper_zero));
    return _mm256_cmpgt_epi32(_mm256_and_si256(byte, bit), _mm256_setzero_si256());
  }

  static Acc acc_zero() { return {_mm256_setzero_si256(), _mm256_setzero_si256()}; }
  static void acc_add(Acc& acc, M mask, std::int64_t delta) {
    const __m256i d = _mm256_set1_epi64x(delta);
    acc.low = _mm256_add_epi64(
        acc.low, _mm256_and_si256(_mm256_cvtepi32_epi64(_mm256_castsi256_si128(mask)), d));
    acc.high = _mm256_add_epi64(
        acc.high, _mm256_and_si256(_mm256_cvtepi32_epi64(_mm256_extracti128_si256(mask, 1)), d));
  }
  static M acc_at_least(const Acc& acc, std::int64_t threshold) {
    const __m256i t = _mm256_set1_epi64x(threshold);
    const __m256i below_low = _mm256_cmpgt_epi64(t, acc.low);
    const __m256i below_high = _mm256_cmpgt_epi64(t, acc.high);
    const __m256i order = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
    const __m256i below =
        _mm256_set_m128i(_mm256_castsi256_si128(_mm256_permutevar8x32_epi32(below_high, order)),
                         _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(below_low, order)));
    return _mm256_xor_si256(below, _mm256_set1_epi32(-1));
  }
};

}  // namespace epipole::vision::simd

#pragma once

// The NEON vocabulary's names (simd/neon.hpp) on AVX2, for the native x86 kernels: translation
// units compiled with -mavx2 only, chosen at run time when the CPU has AVX2. Suffixes as there
// (b: unsigned bytes, h: 16-bit lanes beside them, i/f/m: 32-bit integer, float and mask lanes).
// AVX2 fills a register with 32 bytes where NEON has 16, so it has two shapes of the one
// vocabulary:
//   Avx2:    32 bytes (B), 8 words (I, F, M): kernels whose lanes are independent pixels or
//            windows (FAST, the cascade);
//   Avx2x16: 16 bytes (B) beside 16 halves (H) in a full register: kernels that widen bytes to
//            16-bit sums lane for lane (stereo).
#include <immintrin.h>

#include <cstdint>
#include <utility>

namespace epipole::vision::simd {

struct Avx2 {
  // Bytes: 32 unsigned lanes.
  using B = __m256i;
  static constexpr int kLanesB = 32;

  static B loadb(const std::uint8_t* p) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  }
  static void storeb(std::uint8_t* p, B v) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
  }
  static B splatb(std::uint8_t v) { return _mm256_set1_epi8(static_cast<char>(v)); }
  static B addsb(B a, B b) { return _mm256_adds_epu8(a, b); }
  static B subsb(B a, B b) { return _mm256_subs_epu8(a, b); }
  static B subb(B a, B b) { return _mm256_sub_epi8(a, b); }
  // Unsigned a > b: a - b (saturating) is not zero.
  static B gtb(B a, B b) {
    const B not_greater = _mm256_cmpeq_epi8(_mm256_subs_epu8(a, b), _mm256_setzero_si256());
    return _mm256_xor_si256(not_greater, _mm256_set1_epi8(-1));
  }
  static B ltb(B a, B b) { return gtb(b, a); }
  static B andb(B a, B b) { return _mm256_and_si256(a, b); }
  static B orb(B a, B b) { return _mm256_or_si256(a, b); }
  static B minb(B a, B b) { return _mm256_min_epu8(a, b); }
  static B maxb(B a, B b) { return _mm256_max_epu8(a, b); }
  static bool anyb(B mask) { return _mm256_testz_si256(mask, mask) == 0; }
  // A comparison mask as bits: lane i -> bit i (kBitsPerLaneB apart).
  using LaneBits = std::uint32_t;
  static constexpr int kBitsPerLaneB = 1;
  static LaneBits bitsb(B mask) { return static_cast<std::uint32_t>(_mm256_movemask_epi8(mask)); }

  // Words: 8 lanes of 32-bit integers (I), floats (F) and masks (M).
  static constexpr int kLanesI = 8;
  using I = __m256i;
  using F = __m256;
  using M = __m256i;
  // A fixed-point sum per lane as high * 2^shift + low (the shift is the caller's).
  struct Acc {
    __m256i low;
    __m256i high;
  };

  static I loadi(const std::uint32_t* p) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  }
  static I loadi_bytes(const std::uint8_t* p) {
    return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  }
  static I addi(I a, I b) { return _mm256_add_epi32(a, b); }
  static I subi(I a, I b) { return _mm256_sub_epi32(a, b); }
  static F tof(I a) { return _mm256_cvtepi32_ps(a); }
  static F splatf(float v) { return _mm256_set1_ps(v); }
  // a + b * c
  static I mul_addi(I a, I b, std::int32_t c) {
    return _mm256_add_epi32(a, _mm256_mullo_epi32(b, _mm256_set1_epi32(c)));
  }

  // A cascade stump's StumpParams (weight, threshold bits, delta low, delta high), read from
  // memory as each is used: a broadcast load is one instruction.
  using Params = const std::int32_t*;
  static Params load_params(const std::int32_t* p) { return p; }
  static I mul_add_weight(I a, I b, Params p) { return mul_addi(a, b, p[0]); }
  static F threshold(Params p) { return _mm256_castsi256_ps(_mm256_set1_epi32(p[1])); }
  static F mulf(F a, F b) { return _mm256_mul_ps(a, b); }
  static F addf(F a, F b) { return _mm256_add_ps(a, b); }
  static M ltf(F a, F b) { return _mm256_castps_si256(_mm256_cmp_ps(a, b, _CMP_LT_OQ)); }
  static M gei(I a, I b) {
    return _mm256_xor_si256(_mm256_cmpgt_epi32(b, a), _mm256_set1_epi32(-1));
  }
  static I zeroi() { return _mm256_setzero_si256(); }
  // bits >> 1 (logical) with bit 31 set in the lanes of `mask` (whose lanes are -1 or 0).
  static I push_bit_high(I bits, M mask) {
    return _mm256_or_si256(_mm256_srli_epi32(bits, 1), _mm256_slli_epi32(mask, 31));
  }
  static M andm(M a, M b) { return _mm256_and_si256(a, b); }
  static unsigned bitsm(M m) {
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(m)));
  }
  static M from_bitsm(unsigned bits) {
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

  // Bit `code` of a 256-bit subset (32 bytes) for 8 codes held in the top byte of each lane
  // (`bits`): byte code >> 3 by two 16-byte table lookups (pshufb), tested against the bit
  // code & 7 (a third lookup).
  static M subset_bit(const std::uint8_t* bytes, I bits) {
    const __m256i code = _mm256_srli_epi32(bits, 24);
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
  // Adds the delta's parts to the low and high sums in the lanes of `mask`.
  static void acc_add(Acc& acc, M mask, Params p) {
    acc.low = _mm256_add_epi32(acc.low, _mm256_and_si256(mask, _mm256_set1_epi32(p[2])));
    acc.high = _mm256_add_epi32(acc.high, _mm256_and_si256(mask, _mm256_set1_epi32(p[3])));
  }
  // high * 2^shift + low >= threshold, per lane, in 64 bits.
  static M acc_at_least(const Acc& acc, int shift, std::int64_t threshold) {
    const __m128i s = _mm_cvtsi32_si128(shift);
    const __m256i t = _mm256_set1_epi64x(threshold);
    const auto below = [&](__m128i high, __m128i low) {
      const __m256i sum = _mm256_add_epi64(_mm256_sll_epi64(_mm256_cvtepi32_epi64(high), s),
                                           _mm256_cvtepi32_epi64(low));
      return _mm256_cmpgt_epi64(t, sum);
    };
    const __m256i below_low =
        below(_mm256_castsi256_si128(acc.high), _mm256_castsi256_si128(acc.low));
    const __m256i below_high =
        below(_mm256_extracti128_si256(acc.high, 1), _mm256_extracti128_si256(acc.low, 1));
    const __m256i order = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
    const __m256i below_all =
        _mm256_set_m128i(_mm256_castsi256_si128(_mm256_permutevar8x32_epi32(below_high, order)),
                         _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(below_low, order)));
    return _mm256_xor_si256(below_all, _mm256_set1_epi32(-1));
  }
};

struct Avx2x16 {
  // Bytes: 16 unsigned lanes, in an SSE register.
  using B = __m128i;
  static constexpr int kLanesB = 16;
  static B loadb(const std::uint8_t* p) {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  }
  static void storeb(std::uint8_t* p, B v) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
  static B splatb(std::uint8_t v) { return _mm_set1_epi8(static_cast<char>(v)); }
  static B load_splatb(const std::uint8_t* p) { return splatb(*p); }
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
  // Per lane: popcount(a) + popcount(b).
  static B popcount2(B a, B b) {
    const __m128i table = _mm_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
    const __m256i low = _mm256_set1_epi8(0x0F);
    const __m256i v = _mm256_set_m128i(b, a);
    const __m256i table2 = _mm256_broadcastsi128_si256(table);
    const __m256i sum = _mm256_add_epi8(
        _mm256_shuffle_epi8(table2, _mm256_and_si256(v, low)),
        _mm256_shuffle_epi8(table2, _mm256_and_si256(_mm256_srli_epi16(v, 4), low)));
    return _mm_add_epi8(_mm256_castsi256_si128(sum), _mm256_extracti128_si256(sum, 1));
  }
  static std::uint8_t hminb(B v) {
    const __m128i pairs = _mm_min_epu8(v, _mm_srli_epi16(v, 8));
    const __m128i words = _mm_and_si128(pairs, _mm_set1_epi16(0xFF));
    return static_cast<std::uint8_t>(_mm_extract_epi16(_mm_minpos_epu16(words), 0));
  }

  // Halves: the same 16 lanes as unsigned 16-bit values, in an AVX register.
  using H = __m256i;
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
  static H maxh(H a, H b) { return _mm256_max_epu16(a, b); }
  static H orh(H a, H b) { return _mm256_or_si256(a, b); }
  // a > b for values below 0x8000.
  static H gth(H a, H b) { return _mm256_cmpgt_epi16(a, b); }
  static H eqh(H a, H b) { return _mm256_cmpeq_epi16(a, b); }
  static H selecth(H mask, H a, H b) { return _mm256_blendv_epi8(b, a, mask); }
  static H iotah() {
    return _mm256_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  }
  static std::uint16_t hminh(H v) {
    const __m128i m = _mm_min_epu16(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
    return static_cast<std::uint16_t>(_mm_extract_epi16(_mm_minpos_epu16(m), 0));
  }
  static bool anyh(H mask) { return _mm256_testz_si256(mask, mask) == 0; }
  // The smallest of 16 lanes of values below 2048 (`m`) and, among the lanes that hold it, the
  // smallest of `index` (below 256, and lane L's equal to L modulo 16) in one reduction: keys
  // m << 5 | index >> 3 order by value, then by the index's group of 8; the two halves' minimum
  // keeps that, and phminposuw gives the first of the 8 lanes with the smallest key.
  static std::pair<int, int> min_first_small(H m, H index) {
    const H keys = _mm256_or_si256(_mm256_slli_epi16(m, 5), _mm256_srli_epi16(index, 3));
    const __m128i folded =
        _mm_min_epu16(_mm256_castsi256_si128(keys), _mm256_extracti128_si256(keys, 1));
    const int r = _mm_cvtsi128_si32(_mm_minpos_epu16(folded));
    return {(r & 0xFFFF) >> 5, (r & 31) << 3 | ((r >> 16) & 7)};
  }
};

}  // namespace epipole::vision::simd

#pragma once

// The vector vocabulary of the NEON kernels (native on ARM, SIMDe elsewhere): the generic
// kernels (*_simd.hpp) are written once over it, and simd/avx2.hpp gives the same names on x86.
// A name's suffix says the lanes it works on:
//   b: 16 unsigned bytes (B)           h: the same 16 lanes as unsigned 16-bit values (H)
//   i, f, m: 4 lanes of 32-bit integers (I), floats (F) and masks (M)
// Only intrinsics that exist on both AArch64 and ARMv7 are used (no float64 or 64-bit compare
// vectors: ARMv7 has neither), except in the AArch64 forms of the across-lane reductions
// (`across`), the mask bits (`bitsb`), the cascade's variance, subset lookup and stage test, each
// beside a portable one.
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "epipole/core/neon.hpp"

// The AArch64 forms that SIMDe has too, so that host tests run them (the across-lane reductions
// and the float64x2 variance stay on ARMv7's code under SIMDe).
#if defined(__aarch64__) || !(defined(__ARM_NEON) || defined(__ARM_NEON__))
#define EPIPOLE_NEON_A64_FORMS 1
#else
#define EPIPOLE_NEON_A64_FORMS 0
#endif

namespace epipole::vision::simd {

// Across-lane reductions: one instruction on AArch64 (UMINV, UMAXV, ADDV), a ladder of
// pairwise steps on ARMv7.
namespace across {
#if defined(__aarch64__)
inline std::uint8_t min_u8(uint8x16_t v) {
  return vminvq_u8(v);
}
inline std::uint16_t min_u16(uint16x8_t v) {
  return vminvq_u16(v);
}
inline std::uint32_t sum_u32(uint32x4_t v) {
  return vaddvq_u32(v);
}
inline bool any_u8(uint8x16_t v) {
  return vmaxvq_u8(v) != 0;
}
#else
inline std::uint8_t min_u8(uint8x16_t v) {
  uint8x8_t m = vmin_u8(vget_low_u8(v), vget_high_u8(v));
  m = vpmin_u8(m, m);
  m = vpmin_u8(m, m);
  m = vpmin_u8(m, m);
  return vget_lane_u8(m, 0);
}
inline std::uint16_t min_u16(uint16x8_t v) {
  uint16x4_t m = vmin_u16(vget_low_u16(v), vget_high_u16(v));
  m = vpmin_u16(m, m);
  m = vpmin_u16(m, m);
  return vget_lane_u16(m, 0);
}
inline std::uint32_t sum_u32(uint32x4_t v) {
  const uint32x2_t pair = vadd_u32(vget_low_u32(v), vget_high_u32(v));
  return vget_lane_u32(vpadd_u32(pair, pair), 0);
}
inline bool any_u8(uint8x16_t v) {
  const uint64x2_t halves = vreinterpretq_u64_u8(v);
  return (vgetq_lane_u64(halves, 0) | vgetq_lane_u64(halves, 1)) != 0;
}
#endif
}  // namespace across

struct Neon {
  // Bytes: 16 unsigned lanes.
  using B = uint8x16_t;
  static constexpr int kLanesB = 16;
  static B loadb(const std::uint8_t* p) { return vld1q_u8(p); }
  static void storeb(std::uint8_t* p, B v) { vst1q_u8(p, v); }
  static B splatb(std::uint8_t v) { return vdupq_n_u8(v); }
  static B load_splatb(const std::uint8_t* p) { return vld1q_dup_u8(p); }
  static B zerob() { return vdupq_n_u8(0); }
  static B minb(B a, B b) { return vminq_u8(a, b); }
  static B addb(B a, B b) { return vaddq_u8(a, b); }    // wrapping
  static B subb(B a, B b) { return vsubq_u8(a, b); }    // wrapping
  static B addsb(B a, B b) { return vqaddq_u8(a, b); }  // saturating
  static B subsb(B a, B b) { return vqsubq_u8(a, b); }  // saturating
  static B orb(B a, B b) { return vorrq_u8(a, b); }
  static B xorb(B a, B b) { return veorq_u8(a, b); }
  static B andb(B a, B b) { return vandq_u8(a, b); }
  static B maxb(B a, B b) { return vmaxq_u8(a, b); }
  static B gtb(B a, B b) { return vcgtq_u8(a, b); }
  static B ltb(B a, B b) { return vcltq_u8(a, b); }
  static B selectb(B mask, B a, B b) { return vbslq_u8(mask, a, b); }
  static bool anyb(B mask) { return across::any_u8(mask); }
#if EPIPOLE_NEON_A64_FORMS
  // A comparison mask as bits: lane i -> bit 4 i (kBitsPerLaneB apart). One narrowing shift
  // gives each lane a nibble, fewer instructions than packing one bit a lane.
  using LaneBits = std::uint64_t;
  static constexpr int kBitsPerLaneB = 4;
  static LaneBits bitsb(B mask) {
    const uint8x8_t nibbles = vshrn_n_u16(vreinterpretq_u16_u8(mask), 4);
    return vget_lane_u64(vreinterpret_u64_u8(nibbles), 0) & 0x1111111111111111u;
  }
#else
  // ARMv7: lane i -> bit i, pairwise additions of the lanes' weights (64-bit words cost two
  // registers there).
  using LaneBits = std::uint32_t;
  static constexpr int kBitsPerLaneB = 1;
  static LaneBits bitsb(B mask) {
    static constexpr std::uint8_t kWeights[16] = {1, 2, 4, 8, 16, 32, 64, 128,
                                                  1, 2, 4, 8, 16, 32, 64, 128};
    const uint8x16_t bits = vandq_u8(mask, vld1q_u8(kWeights));
    uint8x8_t sum = vpadd_u8(vget_low_u8(bits), vget_high_u8(bits));
    sum = vpadd_u8(sum, sum);
    sum = vpadd_u8(sum, sum);
    return vget_lane_u16(vreinterpret_u16_u8(sum), 0);
  }
#endif
  static B iotab() {
    static constexpr std::uint8_t kIota[16] = {0, 1, 2,  3,  4,  5,  6,  7,
                                               8, 9, 10, 11, 12, 13, 14, 15};
    return vld1q_u8(kIota);
  }
  // acc with the bits of `bit` set where a > c (they must be clear in acc, as the census's are:
  // each set once in a vector that starts at zero): one BIT.
  static B set_if_greater(B acc, B a, B c, B bit) {
    return vbslq_u8(bit, vcgtq_u8(a, c), acc);
  }
  // Per lane: popcount(a) + popcount(b) + popcount(c) + popcount(d).
  static B popcount4(B a, B b, B c, B d) {
    return vaddq_u8(vaddq_u8(vcntq_u8(a), vcntq_u8(b)), vaddq_u8(vcntq_u8(c), vcntq_u8(d)));
  }
  // Per lane: popcount(a) + popcount(b).
  static B popcount2(B a, B b) {
    return vaddq_u8(vcntq_u8(a), vcntq_u8(b));
  }
  // The 16 lanes in reverse order.
  static B reverseb(B v) {
    const B halves = vrev64q_u8(v);
    return vextq_u8(halves, halves, 8);
  }
  static std::uint8_t hminb(B v) {
    return across::min_u8(v);
  }

  // Census words (a pixel's census as 4 bytes, little-endian): 16 pixels' bytes as 4 vectors
  // of 16 (byte p of each in acc[p]) stored as 16 words, one ST4.
  static void store_interleaved4(std::uint8_t* p, const B (&acc)[4]) {
    vst4q_u8(p, (uint8x16x4_t{{acc[0], acc[1], acc[2], acc[3]}}));
  }
  // The word at p (any alignment) in each of the 4 word lanes: as bytes, p's four in each
  // word lane (little-endian, as every target here is).
  static B load_splat_word(const std::uint8_t* p) {
    static_assert(std::endian::native == std::endian::little);
    std::uint32_t word;
    std::memcpy(&word, p, sizeof word);
    return vreinterpretq_u8_u32(vdupq_n_u32(word));
  }
#if EPIPOLE_NEON_A64_FORMS
  // The Hamming distances between `word` (load_splat_word) and the 16 words from p, as 16
  // bytes. AArch64 only (full-width ADDP): ARMv7 keeps the census in planes.
  static B popcount_words16(B word, const std::uint8_t* p) {
    const B c0 = vcntq_u8(veorq_u8(word, vld1q_u8(p)));
    const B c1 = vcntq_u8(veorq_u8(word, vld1q_u8(p + 16)));
    const B c2 = vcntq_u8(veorq_u8(word, vld1q_u8(p + 32)));
    const B c3 = vcntq_u8(veorq_u8(word, vld1q_u8(p + 48)));
    return vpaddq_u8(vpaddq_u8(c0, c1), vpaddq_u8(c2, c3));
  }
  // The same over the words' bytes 0 and 1 alone (byte0, byte1: splat), one LD4 that takes the
  // 16 words apart into their bytes.
  static B popcount_low2_words16(B byte0, B byte1, const std::uint8_t* p) {
    const uint8x16x4_t bytes = vld4q_u8(p);
    return popcount2(veorq_u8(byte0, bytes.val[0]), veorq_u8(byte1, bytes.val[1]));
  }
#endif

  // Halves: the same 16 lanes as unsigned 16-bit values, in two registers.
  using H = uint16x8x2_t;
  static H loadh(const std::uint16_t* p) {
    return {{vld1q_u16(p), vld1q_u16(p + 8)}};
  }
  static void storeh(std::uint16_t* p, H v) {
    vst1q_u16(p, v.val[0]);
    vst1q_u16(p + 8, v.val[1]);
  }
  static H splath(std::uint16_t v) {
    return {{vdupq_n_u16(v), vdupq_n_u16(v)}};
  }
  static H widen(B v) {
    return {{vmovl_u8(vget_low_u8(v)), vmovl_u8(vget_high_u8(v))}};
  }
  static H addw(H a, B b) {
    return {{vaddw_u8(a.val[0], vget_low_u8(b)), vaddw_u8(a.val[1], vget_high_u8(b))}};
  }
  static H addh(H a, H b) {
    return {{vaddq_u16(a.val[0], b.val[0]), vaddq_u16(a.val[1], b.val[1])}};
  }
  static H subh(H a, H b) {
    return {{vsubq_u16(a.val[0], b.val[0]), vsubq_u16(a.val[1], b.val[1])}};
  }
  static H minh(H a, H b) {
    return {{vminq_u16(a.val[0], b.val[0]), vminq_u16(a.val[1], b.val[1])}};
  }
  static H maxh(H a, H b) {
    return {{vmaxq_u16(a.val[0], b.val[0]), vmaxq_u16(a.val[1], b.val[1])}};
  }
  static H orh(H a, H b) {
    return {{vorrq_u16(a.val[0], b.val[0]), vorrq_u16(a.val[1], b.val[1])}};
  }
  // a > b for values below 0x8000.
  static H gth(H a, H b) {
    return {{vcgtq_u16(a.val[0], b.val[0]), vcgtq_u16(a.val[1], b.val[1])}};
  }
  static H eqh(H a, H b) {
    return {{vceqq_u16(a.val[0], b.val[0]), vceqq_u16(a.val[1], b.val[1])}};
  }
  static H selecth(H mask, H a, H b) {
    return {
        {vbslq_u16(mask.val[0], a.val[0], b.val[0]), vbslq_u16(mask.val[1], a.val[1], b.val[1])}};
  }
  // A mask of 16-bit lanes (each 0 or 0xFFFF) as the same 16 lanes of bytes: the even bytes,
  // one UZP1 (VUZP on ARMv7).
  static B narrow_maskh(H mask) {
#if EPIPOLE_NEON_A64_FORMS
    return vuzp1q_u8(vreinterpretq_u8_u16(mask.val[0]), vreinterpretq_u8_u16(mask.val[1]));
#else
    return vuzpq_u8(vreinterpretq_u8_u16(mask.val[0]), vreinterpretq_u8_u16(mask.val[1])).val[0];
#endif
  }
  static H iotah() {
    static constexpr std::uint16_t kIota[16] = {0, 1, 2,  3,  4,  5,  6,  7,
                                                8, 9, 10, 11, 12, 13, 14, 15};
    return loadh(kIota);
  }
  static std::uint16_t hminh(H v) {
    return across::min_u16(vminq_u16(v.val[0], v.val[1]));
  }
  static bool anyh(H mask) {
    const uint64x2_t halves = vreinterpretq_u64_u16(vorrq_u16(mask.val[0], mask.val[1]));
    return (vgetq_lane_u64(halves, 0) | vgetq_lane_u64(halves, 1)) != 0;
  }

  // Words: 4 lanes of 32-bit integers (I), floats (F) and masks (M).
  static constexpr int kLanesI = 4;
  using I = int32x4_t;
  using F = float32x4_t;
  using M = uint32x4_t;
  // A fixed-point sum per lane as high * 2^shift + low (the shift is the caller's).
  struct Acc {
    int32x4_t low;
    int32x4_t high;
  };

  // Consecutive entries of an integral row.
  static I loadi(const std::uint32_t* p) {
    return vreinterpretq_s32_u32(vld1q_u32(p));
  }
  // The same from a byte address (a load at base + a byte offset needs no shift; the lanes are
  // the same as vld1q_u32's on little-endian ARM, which every supported board is).
  static I loadi_bytes(const std::uint8_t* p) {
    return vreinterpretq_s32_u8(vld1q_u8(p));
  }
  static I addi(I a, I b) {
    return vaddq_s32(a, b);
  }
  static I subi(I a, I b) {
    return vsubq_s32(a, b);
  }
  static F tof(I a) {
    return vcvtq_f32_s32(a);
  }
  static F splatf(float v) {
    return vdupq_n_f32(v);
  }
  // a + b * c
  static I mul_addi(I a, I b, std::int32_t c) {
    return vmlaq_n_s32(a, b, c);
  }

  // A cascade stump's StumpParams in one register: weight, threshold bits, delta low, delta high.
  using Params = int32x4_t;
  static Params load_params(const std::int32_t* p) {
    return vld1q_s32(p);
  }
  // a + b * weight (an MLA by element).
  static I mul_add_weight(I a, I b, Params p) {
    return vmlaq_s32(a, b, vdupq_lane_s32(vget_low_s32(p), 0));
  }
  static F threshold(Params p) {
    return vdupq_lane_f32(vreinterpret_f32_s32(vget_low_s32(p)), 1);
  }
  static F mulf(F a, F b) {
    return vmulq_f32(a, b);
  }
  static F addf(F a, F b) {
    return vaddq_f32(a, b);
  }
  static M ltf(F a, F b) {
    return vcltq_f32(a, b);
  }
  static M gei(I a, I b) {
    return vcgeq_s32(a, b);
  }
  static I zeroi() {
    return vdupq_n_s32(0);
  }
  // bits >> 1 (logical) with bit 31 set in the lanes of `mask` (one SRI).
  static I push_bit_high(I bits, M mask) {
    return vreinterpretq_s32_u32(vsriq_n_u32(mask, vreinterpretq_u32_s32(bits), 1));
  }
  static M andm(M a, M b) {
    return vandq_u32(a, b);
  }
  // Lanes 0..3 as bits 0..3.
  static unsigned bitsm(M m) {
    static constexpr std::uint32_t kBits[4] = {1, 2, 4, 8};
    return across::sum_u32(vandq_u32(m, vld1q_u32(kBits)));
  }
  static M from_bitsm(unsigned bits) {
    static constexpr std::uint32_t kBits[4] = {1, 2, 4, 8};
    return vtstq_u32(vdupq_n_u32(bits), vld1q_u32(kBits));
  }

  // The variance normalisation of 4 windows (see variance_factor): nf exactly in int64 lanes,
  // then OpenCV's double square root and division.
  static void variance(I sum, I squares, double area, F& factor, M& ok) {
    const auto area32 = static_cast<std::uint32_t>(area);
    const uint32x4_t sq = vreinterpretq_u32_s32(squares);
    const int64x2_t nf_low = vsubq_s64(vreinterpretq_s64_u64(vmull_n_u32(vget_low_u32(sq), area32)),
                                       vmull_s32(vget_low_s32(sum), vget_low_s32(sum)));
    const int64x2_t nf_high =
        vsubq_s64(vreinterpretq_s64_u64(vmull_n_u32(vget_high_u32(sq), area32)),
                  vmull_s32(vget_high_s32(sum), vget_high_s32(sum)));
#if defined(__aarch64__)
    // In float64x2 lanes: the same correctly rounded operations as the scalar code. A lane with
    // nf <= 0 fails and keeps the factor 1 (its root is taken of 1, raising no exception).
    const auto half = [area](int64x2_t nf, float32x2_t& f, uint32x2_t& pass) {
      const uint64x2_t positive = vcgtzq_s64(nf);
      const float64x2_t one = vdupq_n_f64(1.0);
      const float64x2_t root = vsqrtq_f64(vbslq_f64(positive, vcvtq_f64_s64(nf), one));
      const float64x2_t inverse = vdivq_f64(one, root);
      f = vbsl_f32(vmovn_u64(positive), vcvt_f32_f64(inverse), vdup_n_f32(1.0f));
      const uint64x2_t small = vcltq_f64(vmulq_n_f64(vcvt_f64_f32(f), area), vdupq_n_f64(0.1));
      pass = vmovn_u64(vandq_u64(positive, small));
    };
    float32x2_t f_low;
    float32x2_t f_high;
    uint32x2_t pass_low;
    uint32x2_t pass_high;
    half(nf_low, f_low, pass_low);
    half(nf_high, f_high, pass_high);
    factor = vcombine_f32(f_low, f_high);
    ok = vcombine_u32(pass_low, pass_high);
#else
    // Per lane: ARMv7 has no float64 vectors (SIMDe follows it here).
    std::int64_t nf[4];
    vst1q_s64(nf, nf_low);
    vst1q_s64(nf + 2, nf_high);
    float f[4];
    std::uint32_t pass[4];
    for (int k = 0; k < 4; ++k) {
      f[k] = 1.0f;
      pass[k] = 0;
      if (nf[k] > 0) {
        f[k] = static_cast<float>(1.0 / std::sqrt(static_cast<double>(nf[k])));
        pass[k] = area * static_cast<double>(f[k]) < 0.1 ? ~0u : 0u;
      }
    }
    factor = vld1q_f32(f);
    ok = vld1q_u32(pass);
#endif
  }

  // Bit `code` of a 256-bit subset (32 bytes) for 4 codes held in the top byte of each lane
  // (`bits`; the other bits are 0).
#if EPIPOLE_NEON_A64_FORMS
  // AArch64 (and SIMDe): the lanes' byte code >> 3 looked up in 32-bit lanes (index bytes 1 to 3
  // out of range, so 0), tested against the bit 1 << (code & 7).
  static M subset_bit(const std::uint8_t* subset, I bits) {
    const uint32x4_t b = vreinterpretq_u32_s32(bits);
    const uint8x16x2_t table = {{vld1q_u8(subset), vld1q_u8(subset + 16)}};
    const uint32x4_t index = vsriq_n_u32(vdupq_n_u32(0xFFFFFF00u), b, 27);
    const uint32x4_t byte = vreinterpretq_u32_u8(vqtbl2q_u8(table, vreinterpretq_u8_u32(index)));
    const uint32x4_t bit = vshlq_u32(
        vdupq_n_u32(1), vreinterpretq_s32_u32(vandq_u32(vshrq_n_u32(b, 24), vdupq_n_u32(7))));
    return vtstq_u32(byte, bit);
  }
#else
  // ARMv7: the codes narrowed to bytes, the byte and the bit by table lookups, the test widened.
  static M subset_bit(const std::uint8_t* subset, I bits) {
    static constexpr std::uint8_t kBit[8] = {1, 2, 4, 8, 16, 32, 64, 128};
    const uint8x8x4_t table = {
        {vld1_u8(subset), vld1_u8(subset + 8), vld1_u8(subset + 16), vld1_u8(subset + 24)}};
    const uint16x4_t c16 = vshrn_n_u32(vreinterpretq_u32_s32(bits), 16);
    const uint8x8_t c8 = vshrn_n_u16(vcombine_u16(c16, c16), 8);
    const uint8x8_t bytes = vtbl4_u8(table, vshr_n_u8(c8, 3));
    const uint8x8_t bit = vtbl1_u8(vld1_u8(kBit), vand_u8(c8, vdup_n_u8(7)));
    const int8x8_t set = vreinterpret_s8_u8(vtst_u8(bytes, bit));  // 0 or -1
    return vreinterpretq_u32_s32(vmovl_s16(vget_low_s16(vmovl_s8(set))));
  }
#endif

  static Acc acc_zero() {
    return {vdupq_n_s32(0), vdupq_n_s32(0)};
  }
  // Adds the delta's parts to the low and high sums in the lanes of `mask`, whose lanes are -1
  // or 0: acc - mask * part (MLS by element).
  static void acc_add(Acc& acc, M mask, Params p) {
    const int32x4_t m = vreinterpretq_s32_u32(mask);
    const int32x2_t delta = vget_high_s32(p);
    acc.low = vmlsq_s32(acc.low, m, vdupq_lane_s32(delta, 0));
    acc.high = vmlsq_s32(acc.high, m, vdupq_lane_s32(delta, 1));
  }
  // high * 2^shift + low >= threshold, per lane, in 64 bits.
  static M acc_at_least(const Acc& acc, int shift, std::int64_t threshold) {
    const int64x2_t s = vdupq_n_s64(shift);
    const int64x2_t t = vdupq_n_s64(threshold);
    const auto sum = [&s](int32x2_t high, int32x2_t low) {
      return vaddw_s32(vshlq_s64(vmovl_s32(high), s), low);
    };
    const int64x2_t sum_low = sum(vget_low_s32(acc.high), vget_low_s32(acc.low));
    const int64x2_t sum_high = sum(vget_high_s32(acc.high), vget_high_s32(acc.low));
#if EPIPOLE_NEON_A64_FORMS
    // AArch64 (and SIMDe) compare 64-bit lanes.
    return vuzp1q_u32(vreinterpretq_u32_u64(vcgeq_s64(sum_low, t)),
                      vreinterpretq_u32_u64(vcgeq_s64(sum_high, t)));
#else
    // ARMv7: from the sign of the difference.
    const int64x2_t below_low = vshrq_n_s64(vsubq_s64(sum_low, t), 63);
    const int64x2_t below_high = vshrq_n_s64(vsubq_s64(sum_high, t), 63);
    const int32x4_t below_all = vcombine_s32(vmovn_s64(below_low), vmovn_s64(below_high));
    return vmvnq_u32(vreinterpretq_u32_s32(below_all));
#endif
  }
};

}  // namespace epipole::vision::simd

#pragma once

// 4 windows per vector with NEON (native on ARM, SIMDe elsewhere), in the vocabulary of the
// cascade window kernel (cascade_simd.hpp): 32-bit integral sums, float feature values, masks,
// and int64 stage sums in two halves. Only intrinsics common to AArch64 and ARMv7 are used
// (no float64 or 64-bit compare vectors: ARMv7 has neither).
#include <cmath>
#include <cstdint>

#include "epipole/core/neon.hpp"

namespace epipole::vision::simd {

struct NeonCascade {
  static constexpr int kLanes = 4;
  using I = int32x4_t;
  using F = float32x4_t;
  using M = uint32x4_t;
  struct Acc {
    int64x2_t low;
    int64x2_t high;
  };

  // Consecutive entries of an integral row.
  static I load(const std::uint32_t* p) { return vreinterpretq_s32_u32(vld1q_u32(p)); }
  static I add(I a, I b) { return vaddq_s32(a, b); }
  static I sub(I a, I b) { return vsubq_s32(a, b); }
  static F to_float(I a) { return vcvtq_f32_s32(a); }
  static F splat(float v) { return vdupq_n_f32(v); }
  static F mul(F a, F b) { return vmulq_f32(a, b); }
  static F add(F a, F b) { return vaddq_f32(a, b); }
  static M less(F a, F b) { return vcltq_f32(a, b); }
  static M greater_equal(I a, I b) { return vcgeq_s32(a, b); }
  static I mask_to(M m, int value) {
    return vreinterpretq_s32_u32(vandq_u32(m, vdupq_n_u32(static_cast<std::uint32_t>(value))));
  }
  static M bit_and(M a, M b) { return vandq_u32(a, b); }
  // Lanes 0..3 as bits 0..3.
  static unsigned bits(M m) {
    static constexpr std::uint32_t kBits[4] = {1, 2, 4, 8};
    const uint32x4_t b = vandq_u32(m, vld1q_u32(kBits));
    const uint32x2_t pair = vadd_u32(vget_low_u32(b), vget_high_u32(b));
    return vget_lane_u32(vpadd_u32(pair, pair), 0);
  }
  static M from_bits(unsigned bits) {
    static constexpr std::uint32_t kBits[4] = {1, 2, 4, 8};
    return vtstq_u32(vdupq_n_u32(bits), vld1q_u32(kBits));
  }

  // The variance normalisation of 4 windows (see variance_factor): nf exactly in int64 lanes,
  // then, per lane, OpenCV's double square root and division.
  static void variance(I sum, I squares, double area, F& factor, M& ok) {
    const auto area32 = static_cast<std::uint32_t>(area);
    const uint32x4_t sq = vreinterpretq_u32_s32(squares);
    const int64x2_t nf_low = vsubq_s64(vreinterpretq_s64_u64(vmull_n_u32(vget_low_u32(sq), area32)),
                                       vmull_s32(vget_low_s32(sum), vget_low_s32(sum)));
    const int64x2_t nf_high =
        vsubq_s64(vreinterpretq_s64_u64(vmull_n_u32(vget_high_u32(sq), area32)),
                  vmull_s32(vget_high_s32(sum), vget_high_s32(sum)));
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
  }

  // Bit `code` of a 256-bit subset (32 bytes) for 4 codes in 0..255: byte code >> 3 by table
  // lookup, tested against the bit code & 7 (from a second table).
  static M subset_bit(const std::uint8_t* subset, I code) {
    static constexpr std::uint8_t kBit[8] = {1, 2, 4, 8, 16, 32, 64, 128};
    const uint8x8x4_t table = {
        {vld1_u8(subset), vld1_u8(subset + 8), vld1_u8(subset + 16), vld1_u8(subset + 24)}};
    const uint16x4_t c16 = vmovn_u32(vreinterpretq_u32_s32(code));
    const uint8x8_t c8 = vmovn_u16(vcombine_u16(c16, c16));
    const uint8x8_t bytes = vtbl4_u8(table, vshr_n_u8(c8, 3));
    const uint8x8_t bit = vtbl1_u8(vld1_u8(kBit), vand_u8(c8, vdup_n_u8(7)));
    const int8x8_t set = vreinterpret_s8_u8(vtst_u8(bytes, bit));  // 0 or -1
    return vreinterpretq_u32_s32(vmovl_s16(vget_low_s16(vmovl_s8(set))));
  }

  static Acc acc_zero() { return {vdupq_n_s64(0), vdupq_n_s64(0)}; }
  static void acc_add(Acc& acc, M mask, std::int64_t delta) {
    const int32x4_t m = vreinterpretq_s32_u32(mask);
    const int64x2_t d = vdupq_n_s64(delta);
    acc.low = vaddq_s64(acc.low, vandq_s64(vmovl_s32(vget_low_s32(m)), d));
    acc.high = vaddq_s64(acc.high, vandq_s64(vmovl_s32(vget_high_s32(m)), d));
  }
  // acc >= threshold, per lane (from the sign of acc - threshold).
  static M acc_at_least(const Acc& acc, std::int64_t threshold) {
    const int64x2_t t = vdupq_n_s64(threshold);
    const int64x2_t below_low = vshrq_n_s64(vsubq_s64(acc.low, t), 63);
    const int64x2_t below_high = vshrq_n_s64(vsubq_s64(acc.high, t), 63);
    const int32x4_t below = vcombine_s32(vmovn_s64(below_low), vmovn_s64(below_high));
    return vmvnq_u32(vreinterpretq_u32_s32(below));
  }
};

}  // namespace epipole::vision::simd

#pragma once

// 16 unsigned bytes per vector with NEON (native on ARM, SIMDe elsewhere), in the small
// vocabulary the generic kernels (*_simd.hpp) are written in. Only intrinsics that exist on both
// AArch64 and ARMv7 are used.
#include <cstdint>

#include "epipole/core/neon.hpp"

namespace epipole::vision::simd {

struct NeonU8 {
  using Vec = uint8x16_t;
  static constexpr int kLanes = 16;

  static Vec load(const std::uint8_t* p) { return vld1q_u8(p); }
  static void store(std::uint8_t* p, Vec v) { vst1q_u8(p, v); }
  static Vec splat(std::uint8_t v) { return vdupq_n_u8(v); }
  static Vec adds(Vec a, Vec b) { return vqaddq_u8(a, b); }  // saturating
  static Vec subs(Vec a, Vec b) { return vqsubq_u8(a, b); }  // saturating
  static Vec sub(Vec a, Vec b) { return vsubq_u8(a, b); }    // wrapping
  static Vec gt(Vec a, Vec b) { return vcgtq_u8(a, b); }
  static Vec lt(Vec a, Vec b) { return vcltq_u8(a, b); }
  static Vec bit_and(Vec a, Vec b) { return vandq_u8(a, b); }
  static Vec bit_or(Vec a, Vec b) { return vorrq_u8(a, b); }
  static Vec min(Vec a, Vec b) { return vminq_u8(a, b); }
  static Vec max(Vec a, Vec b) { return vmaxq_u8(a, b); }

  static bool any(Vec mask) {
    const uint64x2_t halves = vreinterpretq_u64_u8(mask);
    return (vgetq_lane_u64(halves, 0) | vgetq_lane_u64(halves, 1)) != 0;
  }

  // One bit per lane of a comparison mask (lane i -> bit i).
  static std::uint32_t lane_bits(Vec mask) {
    static constexpr std::uint8_t kWeights[16] = {1, 2, 4, 8, 16, 32, 64, 128,
                                                  1, 2, 4, 8, 16, 32, 64, 128};
    const uint8x16_t bits = vandq_u8(mask, vld1q_u8(kWeights));
    uint8x8_t sum = vpadd_u8(vget_low_u8(bits), vget_high_u8(bits));
    sum = vpadd_u8(sum, sum);
    sum = vpadd_u8(sum, sum);
    return vget_lane_u16(vreinterpret_u16_u8(sum), 0);
  }
};

}  // namespace epipole::vision::simd

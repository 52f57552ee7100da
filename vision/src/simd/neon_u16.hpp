#pragma once

// 8 unsigned 16-bit lanes per vector with NEON (native on ARM, SIMDe elsewhere), in the
// vocabulary of the stereo kernels (stereo_simd.hpp). Only intrinsics that exist on both AArch64
// and ARMv7 are used.
#include <cstdint>

#include "epipole/core/neon.hpp"

namespace epipole::vision::simd {

struct NeonU16 {
  using Vec = uint16x8_t;
  static constexpr int kLanes = 8;

  static Vec load(const std::uint16_t* p) { return vld1q_u16(p); }
  static void store(std::uint16_t* p, Vec v) { vst1q_u16(p, v); }
  // kLanes bytes, widened.
  static Vec load_u8(const std::uint8_t* p) { return vmovl_u8(vld1_u8(p)); }
  static Vec splat(std::uint16_t v) { return vdupq_n_u16(v); }
  static Vec zero() { return vdupq_n_u16(0); }
  static Vec add(Vec a, Vec b) { return vaddq_u16(a, b); }
  static Vec sub(Vec a, Vec b) { return vsubq_u16(a, b); }
  static Vec min(Vec a, Vec b) { return vminq_u16(a, b); }
  static Vec bit_and(Vec a, Vec b) { return vandq_u16(a, b); }
  static Vec bit_or(Vec a, Vec b) { return vorrq_u16(a, b); }
  static Vec bit_xor(Vec a, Vec b) { return veorq_u16(a, b); }
  static Vec gt(Vec a, Vec b) { return vcgtq_u16(a, b); }
  // a > b for values below 0x8000 (pixels).
  static Vec gt_small(Vec a, Vec b) { return vcgtq_u16(a, b); }
  static Vec eq(Vec a, Vec b) { return vceqq_u16(a, b); }
  static Vec select(Vec mask, Vec a, Vec b) { return vbslq_u16(mask, a, b); }
  static Vec iota() {
    static constexpr std::uint16_t kIota[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    return vld1q_u16(kIota);
  }
  // popcount(a) + popcount(b) per lane.
  static Vec popcount2(Vec a, Vec b) {
    const uint8x16_t bytes =
        vaddq_u8(vcntq_u8(vreinterpretq_u8_u16(a)), vcntq_u8(vreinterpretq_u8_u16(b)));
    return vpaddlq_u8(bytes);
  }
  static std::uint16_t hmin(Vec v) {
    uint16x4_t m = vmin_u16(vget_low_u16(v), vget_high_u16(v));
    m = vpmin_u16(m, m);
    m = vpmin_u16(m, m);
    return vget_lane_u16(m, 0);
  }
  static bool any(Vec mask) {
    const uint64x2_t halves = vreinterpretq_u64_u16(mask);
    return (vgetq_lane_u64(halves, 0) | vgetq_lane_u64(halves, 1)) != 0;
  }
};

}  // namespace epipole::vision::simd

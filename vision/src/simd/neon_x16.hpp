#pragma once

// 16 lanes with NEON (native on ARM, SIMDe elsewhere), in the vocabulary of the stereo kernels
// (stereo_simd.hpp): B holds 16 unsigned bytes (costs, census bytes, 8-bit path values), H the
// same 16 lanes as unsigned 16-bit values (sums), in two registers. Only intrinsics that exist
// on both AArch64 and ARMv7 are used.
#include <cstdint>

#include "epipole/core/neon.hpp"

namespace epipole::vision::simd {

struct NeonX16 {
  using B = uint8x16_t;
  using H = uint16x8x2_t;

  // Bytes.
  static B loadb(const std::uint8_t* p) { return vld1q_u8(p); }
  static void storeb(std::uint8_t* p, B v) { vst1q_u8(p, v); }
  static B splatb(std::uint8_t v) { return vdupq_n_u8(v); }
  static B zerob() { return vdupq_n_u8(0); }
  static B minb(B a, B b) { return vminq_u8(a, b); }
  static B addb(B a, B b) { return vaddq_u8(a, b); }    // wrapping
  static B subb(B a, B b) { return vsubq_u8(a, b); }    // wrapping
  static B addsb(B a, B b) { return vqaddq_u8(a, b); }  // saturating
  static B xorb(B a, B b) { return veorq_u8(a, b); }
  static B andb(B a, B b) { return vandq_u8(a, b); }
  static B maxb(B a, B b) { return vmaxq_u8(a, b); }
  static B gtb(B a, B b) { return vcgtq_u8(a, b); }
  static B iotab() {
    static constexpr std::uint8_t kIota[16] = {0, 1, 2,  3,  4,  5,  6,  7,
                                               8, 9, 10, 11, 12, 13, 14, 15};
    return vld1q_u8(kIota);
  }
  // acc with `bit` set in the lanes where a > c.
  static B set_if_greater(B acc, B a, B c, B bit) {
    return vorrq_u8(acc, vandq_u8(vcgtq_u8(a, c), bit));
  }
  // Per lane: popcount(a) + popcount(b) + popcount(c) + popcount(d).
  static B popcount4(B a, B b, B c, B d) {
    return vaddq_u8(vaddq_u8(vcntq_u8(a), vcntq_u8(b)), vaddq_u8(vcntq_u8(c), vcntq_u8(d)));
  }
  static std::uint8_t hminb(B v) {
    uint8x8_t m = vmin_u8(vget_low_u8(v), vget_high_u8(v));
    m = vpmin_u8(m, m);
    m = vpmin_u8(m, m);
    m = vpmin_u8(m, m);
    return vget_lane_u8(m, 0);
  }

  // 16-bit values.
  static H loadh(const std::uint16_t* p) { return {{vld1q_u16(p), vld1q_u16(p + 8)}}; }
  static void storeh(std::uint16_t* p, H v) {
    vst1q_u16(p, v.val[0]);
    vst1q_u16(p + 8, v.val[1]);
  }
  static H splath(std::uint16_t v) { return {{vdupq_n_u16(v), vdupq_n_u16(v)}}; }
  static H widen(B v) { return {{vmovl_u8(vget_low_u8(v)), vmovl_u8(vget_high_u8(v))}}; }
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
  static H iotah() {
    static constexpr std::uint16_t kIota[16] = {0, 1, 2,  3,  4,  5,  6,  7,
                                                8, 9, 10, 11, 12, 13, 14, 15};
    return loadh(kIota);
  }
  // Lane 15 of prev, then lanes 0..14 of cur: a window moved up by one lane.
  static H shift_in(H prev, H cur) {
    return {{vextq_u16(prev.val[1], cur.val[0], 7), vextq_u16(cur.val[0], cur.val[1], 7)}};
  }
  static std::uint16_t last(H v) { return vgetq_lane_u16(v.val[1], 7); }
  static std::uint16_t hminh(H v) {
    const uint16x8_t q = vminq_u16(v.val[0], v.val[1]);
    uint16x4_t m = vmin_u16(vget_low_u16(q), vget_high_u16(q));
    m = vpmin_u16(m, m);
    m = vpmin_u16(m, m);
    return vget_lane_u16(m, 0);
  }
  static std::uint32_t hsumh(H v) {
    const uint64x2_t q = vpaddlq_u32(vpaddlq_u16(vaddq_u16(v.val[0], v.val[1])));
    return static_cast<std::uint32_t>(vgetq_lane_u64(q, 0) + vgetq_lane_u64(q, 1));
  }
  static bool anyh(H mask) {
    const uint64x2_t halves = vreinterpretq_u64_u16(vorrq_u16(mask.val[0], mask.val[1]));
    return (vgetq_lane_u64(halves, 0) | vgetq_lane_u64(halves, 1)) != 0;
  }
};

}  // namespace epipole::vision::simd

// Hamming distances of 256-bit descriptors with NEON: two 16-byte halves, vcnt and pairwise
// widening adds (ARMv7-safe intrinsics).
#include "epipole/core/neon.hpp"
#include "sparse_stereo_kernels.hpp"

namespace epipole::vision::kernels {

void hamming_neon(const std::uint8_t* query, const std::uint8_t* candidates, int n,
                  std::uint16_t* distances) {
  const uint8x16_t q0 = vld1q_u8(query);
  const uint8x16_t q1 = vld1q_u8(query + 16);
  int i = 0;
  // Four candidates at a time: their byte counts summed pairwise into one vector of 4 sums.
  for (; i + 4 <= n; i += 4) {
    uint16x8_t s[4];
    for (int k = 0; k < 4; ++k) {
      const std::uint8_t* c = candidates + (i + k) * 32;
      const uint8x16_t bytes =
          vaddq_u8(vcntq_u8(veorq_u8(q0, vld1q_u8(c))), vcntq_u8(veorq_u8(q1, vld1q_u8(c + 16))));
      s[k] = vpaddlq_u8(bytes);
    }
    // Each s[k] holds 8 partial sums; pairwise adds reduce them to one per candidate.
    const uint16x4_t a = vpadd_u16(vget_low_u16(s[0]), vget_high_u16(s[0]));
    const uint16x4_t b = vpadd_u16(vget_low_u16(s[1]), vget_high_u16(s[1]));
    const uint16x4_t c = vpadd_u16(vget_low_u16(s[2]), vget_high_u16(s[2]));
    const uint16x4_t d = vpadd_u16(vget_low_u16(s[3]), vget_high_u16(s[3]));
    const uint16x4_t ab = vpadd_u16(a, b);  // two partial sums per candidate
    const uint16x4_t cd = vpadd_u16(c, d);
    vst1_u16(distances + i, vpadd_u16(ab, cd));
  }
  for (; i < n; ++i) {
    const std::uint8_t* c = candidates + i * 32;
    const uint8x16_t bytes =
        vaddq_u8(vcntq_u8(veorq_u8(q0, vld1q_u8(c))), vcntq_u8(veorq_u8(q1, vld1q_u8(c + 16))));
    const uint64x2_t sum = vpaddlq_u32(vpaddlq_u16(vpaddlq_u8(bytes)));
    distances[i] = static_cast<std::uint16_t>(vgetq_lane_u64(sum, 0) + vgetq_lane_u64(sum, 1));
  }
}

}  // namespace epipole::vision::kernels

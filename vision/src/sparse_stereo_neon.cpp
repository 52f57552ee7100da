// The sparse stereo kernels with NEON (ARMv7-safe intrinsics): Hamming distances of 256-bit
// descriptors (two 16-byte halves, vcnt and pairwise widening adds) and the descriptors' 5x5
// box sums.
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

namespace {

// Columns k .. k + 7 of the 16 vertical sums lo (columns 0..7), hi (8..15), 0 <= k <= 8.
template <int k>
uint16x8_t columns_from(uint16x8_t lo, uint16x8_t hi) {
  if constexpr (k == 0) {
    return lo;
  } else if constexpr (k == 8) {
    return hi;
  } else {
    return vextq_u16(lo, hi, k);
  }
}

// The box sums of the 8 pixels whose 12 columns start `skip` columns into the 16 from
// rows[r] + at: the 5 rows' vertical sums, then 5 neighbouring columns of those.
template <int skip>
[[gnu::always_inline]] inline uint16x8_t box5_block(const std::uint8_t* const* rows, int at) {
  uint8x16_t r[5];
#pragma GCC unroll 5
  for (int i = 0; i < 5; ++i) r[i] = vld1q_u8(rows[i] + at);
  const uint16x8_t lo = vaddw_u8(vaddq_u16(vaddl_u8(vget_low_u8(r[0]), vget_low_u8(r[1])),
                                           vaddl_u8(vget_low_u8(r[2]), vget_low_u8(r[3]))),
                                 vget_low_u8(r[4]));
  const uint16x8_t hi = vaddw_u8(vaddq_u16(vaddl_u8(vget_high_u8(r[0]), vget_high_u8(r[1])),
                                           vaddl_u8(vget_high_u8(r[2]), vget_high_u8(r[3]))),
                                 vget_high_u8(r[4]));
  return vaddq_u16(
      vaddq_u16(vaddq_u16(columns_from<skip>(lo, hi), columns_from<skip + 1>(lo, hi)),
                vaddq_u16(columns_from<skip + 2>(lo, hi), columns_from<skip + 3>(lo, hi))),
      columns_from<skip + 4>(lo, hi));
}

}  // namespace

void box5_row_neon(const std::uint8_t* const* rows, int width, std::uint16_t* out) {
  if (width < 16) {
    box5_row_ref(rows, width, out);
    return;
  }
  // Pixels x .. x + 7 read columns x - 2 .. x + 9, the last 12 of the 16 loaded from x - 6
  // (the first 12 for x = 2); the last 8 pixels (overlapping the ones before) from the last 16.
  // The row pointers in locals, so that the stores to out do not make the compiler load them
  // again.
  const std::uint8_t* const r[5] = {rows[0], rows[1], rows[2], rows[3], rows[4]};
  vst1q_u16(out + 2, box5_block<0>(r, 0));
  int x = 10;
  for (; x + 9 < width; x += 8) vst1q_u16(out + x, box5_block<4>(r, x - 6));
  if (x < width - 2) vst1q_u16(out + width - 10, box5_block<4>(r, width - 16));
}

}  // namespace epipole::vision::kernels

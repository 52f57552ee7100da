// The speckle filter's row masks in NEON, 16 pixels a word: the three comparisons eight lanes at
// a time, narrowed to bytes and then to nibbles by one shift-narrow (a pair of mask bytes
// 0xFF/0x00 read as 16 bits and shifted by 4 keeps a nibble of each).
#include "epipole/core/neon.hpp"
#include "epipole/vision/speckle_filter.hpp"
#include "speckle_filter_kernels.hpp"

namespace epipole::vision::kernels {

namespace {

std::uint64_t nibbles(uint16x8_t low, uint16x8_t high) {
  const uint8x16_t bytes = vcombine_u8(vmovn_u16(low), vmovn_u16(high));
  return vget_lane_u64(vreinterpret_u64_u8(vshrn_n_u16(vreinterpretq_u16_u8(bytes), 4)), 0);
}

uint16x8_t non_negative(int16x8_t a) {
  return vcgeq_s16(a, vdupq_n_s16(0));
}

// Both valid and at most `range` apart.
uint16x8_t connected(int16x8_t a, int16x8_t b, uint16x8_t a_valid, int16x8_t range) {
  return vandq_u16(vandq_u16(a_valid, non_negative(b)), vcleq_s16(vabdq_s16(a, b), range));
}

}  // namespace

void speckle_masks_row_neon(const std::int16_t* row, const std::int16_t* above, int width,
                            int range_x16, std::uint64_t* valid, std::uint64_t* left,
                            std::uint64_t* up) {
  const int16x8_t range = vdupq_n_s16(static_cast<std::int16_t>(range_x16));
  int16x8_t carry = vdupq_n_s16(-1);  // lane 7: the pixel before the block, invalid at x = 0
  std::int16_t tail_row[16];
  std::int16_t tail_above[16];
  for (int x = 0, w = 0; x < width; x += 16, ++w) {
    const std::int16_t* r = row + x;
    const std::int16_t* u = above != nullptr ? above + x : nullptr;
    if (width - x < 16) {  // the last pixels, padded with invalid ones
      for (int i = 0; i < 16; ++i) {
        tail_row[i] = x + i < width ? r[i] : std::int16_t{-1};
        if (u != nullptr) tail_above[i] = x + i < width ? u[i] : std::int16_t{-1};
      }
      r = tail_row;
      if (u != nullptr) u = tail_above;
    }
    const int16x8_t a = vld1q_s16(r);
    const int16x8_t b = vld1q_s16(r + 8);
    const uint16x8_t a_valid = non_negative(a);
    const uint16x8_t b_valid = non_negative(b);
    valid[w] = nibbles(a_valid, b_valid);
    left[w] = nibbles(connected(a, vextq_s16(carry, a, 7), a_valid, range),
                      connected(b, vextq_s16(a, b, 7), b_valid, range));
    carry = b;
    up[w] = u == nullptr ? 0
                         : nibbles(connected(a, vld1q_s16(u), a_valid, range),
                                   connected(b, vld1q_s16(u + 8), b_valid, range));
  }
}

}  // namespace epipole::vision::kernels

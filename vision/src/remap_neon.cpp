// Bilinear remap, 8 destination pixels at a time with NEON. NEON has no gather: each
// destination pixel's two 2-pixel pairs are fetched with scalar 16-bit loads (their offsets
// y * stride + x computed 8 at a time in vectors) and packed four to a register (neon_pairs.hpp),
// and the weighting (the same integer arithmetic as remap_row_ref) runs in vectors, so results
// equal the reference bit for bit. Blocks whose 8 neighbourhoods all lie inside the source skip the
// border checks; blocks wholly outside are the border value; the others go through a small
// buffer pixel by pixel. The last block of a row is moved left to end at the last pixel instead
// of falling back to scalar code. Only intrinsics that exist on both AArch64 and ARMv7 are used.
#include <algorithm>
#include <cstdint>
#include <cstring>

#include "epipole/core/neon.hpp"
#include "neon_pairs.hpp"
#include "remap_kernels.hpp"

namespace epipole::vision::kernels {

namespace {

inline bool all_set(uint16x8_t mask) {
  return vget_lane_u64(vreinterpret_u64_u8(vmovn_u16(mask)), 0) == ~std::uint64_t{0};
}

inline std::uint8_t pixel_or_border(GrayView source, int x, int y, std::uint8_t border) {
  return static_cast<unsigned>(x) < static_cast<unsigned>(source.width()) &&
                 static_cast<unsigned>(y) < static_cast<unsigned>(source.height())
             ? source(x, y)
             : border;
}

// The weighting of 8 pixels from their four neighbours (s00 s01 / s10 s11).
inline uint8x8_t blend8(uint8x8_t s00, uint8x8_t s01, uint8x8_t s10, uint8x8_t s11,
                        const std::uint16_t* fractions) {
  const uint16x8_t f = vld1q_u16(fractions);
  const uint16x8_t five_bits = vdupq_n_u16(31);
  const uint8x8_t fx = vmovn_u16(vandq_u16(f, five_bits));
  const uint16x8_t fy = vandq_u16(vshrq_n_u16(f, 5), five_bits);
  const uint8x8_t fx_rest = vsub_u8(vdup_n_u8(32), fx);
  const uint16x8_t fy_rest = vsubq_u16(vdupq_n_u16(32), fy);
  // Horizontal pass in 16 bits (at most 255 * 32), vertical pass in 32 bits.
  const uint16x8_t upper = vmlal_u8(vmull_u8(s00, fx_rest), s01, fx);
  const uint16x8_t lower = vmlal_u8(vmull_u8(s10, fx_rest), s11, fx);
  const uint32x4_t sum_low = vmlal_u16(vmull_u16(vget_low_u16(upper), vget_low_u16(fy_rest)),
                                       vget_low_u16(lower), vget_low_u16(fy));
  const uint32x4_t sum_high = vmlal_u16(vmull_u16(vget_high_u16(upper), vget_high_u16(fy_rest)),
                                        vget_high_u16(lower), vget_high_u16(fy));
  // (sum + 512) >> 10; the result is at most 255.
  return vmovn_u16(vcombine_u16(vrshrn_n_u32(sum_low, 10), vrshrn_n_u32(sum_high, 10)));
}

// The same with the pairs as 16-bit lanes (first pixel in the low byte, as memory holds them).
inline uint8x8_t blend8(uint16x8_t top, uint16x8_t bottom, const std::uint16_t* fractions) {
  return blend8(vmovn_u16(top), vshrn_n_u16(top, 8), vmovn_u16(bottom), vshrn_n_u16(bottom, 8),
                fractions);
}

// The pairs of 4 neighbourhoods, from their offsets in `row`.
inline uint16x4_t pairs_at(const std::uint8_t* row, int32x4_t offsets) {
  return pairs4(row, vgetq_lane_s32(offsets, 0), vgetq_lane_s32(offsets, 1),
                vgetq_lane_s32(offsets, 2), vgetq_lane_s32(offsets, 3));
}

}  // namespace

void remap_row_neon(GrayView source, const std::int16_t* xy, const std::uint16_t* fractions,
                    int width, std::uint8_t border, std::uint8_t* destination) {
  const int source_width = source.width();
  const int source_height = source.height();
  if (source_width == 0 || source_height == 0) {
    std::memset(destination, border, static_cast<std::size_t>(std::max(width, 0)));
    return;
  }
  if (width < 8) {
    remap_row_ref(source, xy, fractions, width, border, destination);
    return;
  }
  const std::ptrdiff_t stride = source.stride();
  const std::uint8_t* pixels = source.data();
  // Sizes are at most 32767, so as unsigned 16-bit lanes every negative coordinate compares
  // above them. Inside: x < width - 1 and y < height - 1. Wholly outside: x + 1 > width or
  // y + 1 > height (x + 1 wraps from 32767 to 32768, still above).
  const uint16x8_t inner_width = vdupq_n_u16(static_cast<std::uint16_t>(source_width - 1));
  const uint16x8_t inner_height = vdupq_n_u16(static_cast<std::uint16_t>(source_height - 1));
  const uint16x8_t outer_width = vdupq_n_u16(static_cast<std::uint16_t>(source_width));
  const uint16x8_t outer_height = vdupq_n_u16(static_cast<std::uint16_t>(source_height));
  const uint16x8_t one = vdupq_n_u16(1);
  const uint8x8_t border_vector = vdup_n_u8(border);
  // Inside offsets are below height * stride; computed in 32-bit lanes when that fits (always
  // but for a source of more than 2 GiB: such a one takes the buffered path).
  const bool offsets_fit = static_cast<std::int64_t>(source_height) * stride <= INT32_MAX;
  const auto row_step = static_cast<std::int32_t>(offsets_fit ? stride : 0);
  // Destination pixels [first, first + 8). The last block moves left to end at the last pixel
  // (recomputing a few: the same values).
  for (int i = 0; i < width; i += 8) {
    const int first = std::min(i, width - 8);
    const int16x8x2_t c = vld2q_s16(xy + 2 * first);
    const uint16x8_t x = vreinterpretq_u16_s16(c.val[0]);
    const uint16x8_t y = vreinterpretq_u16_s16(c.val[1]);
    if (offsets_fit && all_set(vandq_u16(vcltq_u16(x, inner_width), vcltq_u16(y, inner_height)))) {
      // Inside: 0 <= x, y, so the offsets y * stride + x are those of the signed lanes.
      const int32x4_t offsets_low = vmlaq_n_s32(vmovl_s16(vget_low_s16(c.val[0])),
                                                vmovl_s16(vget_low_s16(c.val[1])), row_step);
      const int32x4_t offsets_high = vmlaq_n_s32(vmovl_s16(vget_high_s16(c.val[0])),
                                                 vmovl_s16(vget_high_s16(c.val[1])), row_step);
      const std::uint8_t* below = pixels + stride;
      const uint16x8_t top =
          vcombine_u16(pairs_at(pixels, offsets_low), pairs_at(pixels, offsets_high));
      const uint16x8_t bottom =
          vcombine_u16(pairs_at(below, offsets_low), pairs_at(below, offsets_high));
      vst1_u8(destination + first, blend8(top, bottom, fractions + first));
      continue;
    }
    if (all_set(vorrq_u16(vcgtq_u16(vaddq_u16(x, one), outer_width),
                          vcgtq_u16(vaddq_u16(y, one), outer_height)))) {
      vst1_u8(destination + first, border_vector);
      continue;
    }
    const std::int16_t* entry = xy + 2 * first;
    std::uint8_t top[16];
    std::uint8_t bottom[16];
    for (int k = 0; k < 8; ++k) {
      const int sx = entry[2 * k];
      const int sy = entry[2 * k + 1];
      top[2 * k] = pixel_or_border(source, sx, sy, border);
      top[2 * k + 1] = pixel_or_border(source, sx + 1, sy, border);
      bottom[2 * k] = pixel_or_border(source, sx, sy + 1, border);
      bottom[2 * k + 1] = pixel_or_border(source, sx + 1, sy + 1, border);
    }
    const uint8x8x2_t t = vld2_u8(top);
    const uint8x8x2_t b = vld2_u8(bottom);
    vst1_u8(destination + first, blend8(t.val[0], t.val[1], b.val[0], b.val[1], fractions + first));
  }
}

}  // namespace epipole::vision::kernels

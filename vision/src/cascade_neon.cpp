// The cascade detector's NEON kernels: integral images 8 pixels at a time (in-vector prefix
// sums), the tilted integral 4 at a time, the pyramid resize 8 at a time (NEON has no gather:
// pixel pairs are fetched with scalar 16-bit loads, the weighting runs in vectors), and the
// window kernel with 4 windows per vector (cascade_simd.hpp over simd/neon.hpp, which has
// AArch64 forms of a few steps beside portable ones). Every result equals the reference's bit
// for bit.
#include <cstring>

#include "cascade_kernels.hpp"
#include "cascade_program.hpp"
#include "cascade_simd.hpp"
#include "epipole/core/neon.hpp"
#include "neon_pairs.hpp"
#include "simd/neon.hpp"

namespace epipole::vision::kernels {

void integral_row_neon(const std::uint8_t* row, int width, const std::uint32_t* sum_above,
                       const std::uint32_t* square_above, std::uint32_t* sum, std::uint32_t* square,
                       std::uint32_t* prefix) {
  integral_first_entries(sum_above, square_above, sum, square, prefix);
  std::uint32_t running = 0;
  std::uint32_t running_squares = 0;
  const uint16x8_t zero16 = vdupq_n_u16(0);
  const uint32x4_t zero32 = vdupq_n_u32(0);
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const uint8x8_t pixels = vld1_u8(row + x);
    // Prefix sums of 8 pixels (at most 2040) in 16 bits: shifts by 1, 2 and 4 lanes.
    uint16x8_t p = vmovl_u8(pixels);
    p = vaddq_u16(p, vextq_u16(zero16, p, 7));
    p = vaddq_u16(p, vextq_u16(zero16, p, 6));
    p = vaddq_u16(p, vextq_u16(zero16, p, 4));
    const uint32x4_t carry = vdupq_n_u32(running);
    const uint32x4_t low = vaddq_u32(vmovl_u16(vget_low_u16(p)), carry);
    const uint32x4_t high = vaddq_u32(vmovl_u16(vget_high_u16(p)), carry);
    running = vgetq_lane_u32(high, 3);
    vst1q_u32(sum + x + 1, vaddq_u32(low, vld1q_u32(sum_above + x + 1)));
    vst1q_u32(sum + x + 5, vaddq_u32(high, vld1q_u32(sum_above + x + 5)));
    if (prefix != nullptr) {
      vst1q_u32(prefix + x + 2, low);
      vst1q_u32(prefix + x + 6, high);
    }
    if (square == nullptr) continue;
    // Squares (at most 65025) in 32 bits, 4 lanes at a time.
    const uint16x8_t squares = vmull_u8(pixels, pixels);
    uint32x4_t q0 = vmovl_u16(vget_low_u16(squares));
    uint32x4_t q1 = vmovl_u16(vget_high_u16(squares));
    q0 = vaddq_u32(q0, vextq_u32(zero32, q0, 3));
    q0 = vaddq_u32(q0, vextq_u32(zero32, q0, 2));
    q1 = vaddq_u32(q1, vextq_u32(zero32, q1, 3));
    q1 = vaddq_u32(q1, vextq_u32(zero32, q1, 2));
    q0 = vaddq_u32(q0, vdupq_n_u32(running_squares));
    q1 = vaddq_u32(q1, vdupq_n_u32(vgetq_lane_u32(q0, 3)));
    running_squares = vgetq_lane_u32(q1, 3);
    vst1q_u32(square + x + 1, vaddq_u32(q0, vld1q_u32(square_above + x + 1)));
    vst1q_u32(square + x + 5, vaddq_u32(q1, vld1q_u32(square_above + x + 5)));
  }
  integral_columns(row, x, width, sum_above, square_above, sum, square, prefix, running,
                   running_squares);
}

void tilted_row_neon(const std::uint32_t* prefix, int width, const std::uint32_t* left_above,
                     const std::uint32_t* right_above, std::uint32_t* left, std::uint32_t* right,
                     std::uint32_t* tilted) {
  right[0] = 0;
  int x = 0;
  for (; x + 3 <= width; x += 4) {
    const uint32x4_t l = vaddq_u32(vld1q_u32(left_above + x + 1), vld1q_u32(prefix + x + 1));
    const uint32x4_t r = vaddq_u32(vld1q_u32(right_above + x), vld1q_u32(prefix + x));
    vst1q_u32(left + x, l);
    vst1q_u32(right + x + 1, r);
    vst1q_u32(tilted + x, vsubq_u32(l, r));
  }
  tilted_columns(prefix, x, width, left_above, right_above, left, right, tilted);
}

void resize_columns_neon(const std::uint8_t* row, int source_width, const std::int32_t* offsets,
                         const std::uint16_t* weights, int width, std::uint16_t* out) {
  int x = 0;
  // Blocks whose 8 pixel pairs lie inside the row (offsets never decrease).
  for (; x + 8 <= width && offsets[x + 7] + 1 < source_width; x += 8) {
    const std::int32_t* o = offsets + x;
    const uint16x8_t pairs =
        vcombine_u16(pairs4(row, o[0], o[1], o[2], o[3]), pairs4(row, o[4], o[5], o[6], o[7]));
    const uint16x8x2_t w = vld2q_u16(weights + 2 * x);
    // At most 255 * 256: 16 bits suffice.
    const uint16x8_t first = vandq_u16(pairs, vdupq_n_u16(0xFF));
    const uint16x8_t second = vshrq_n_u16(pairs, 8);
    vst1q_u16(out + x, vmlaq_u16(vmulq_u16(first, w.val[0]), second, w.val[1]));
  }
  resize_columns_ref(row, source_width, offsets + x, weights + 2 * x, width - x, out + x);
}

void resize_rows_neon(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
                      std::uint16_t w1, int width, std::uint8_t* out) {
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const uint16x8_t t = vld1q_u16(top + x);
    const uint16x8_t b = vld1q_u16(bottom + x);
    const uint32x4_t low = vmlal_n_u16(vmull_n_u16(vget_low_u16(t), w0), vget_low_u16(b), w1);
    const uint32x4_t high = vmlal_n_u16(vmull_n_u16(vget_high_u16(t), w0), vget_high_u16(b), w1);
    // (v + 32768) >> 16 is a rounding shift; the result is at most 255.
    vst1_u8(out + x, vmovn_u16(vcombine_u16(vrshrn_n_u32(low, 16), vrshrn_n_u32(high, 16))));
  }
  resize_rows_ref(top + x, bottom + x, w0, w1, width - x, out + x);
}

void split_row_neon(const std::uint32_t* row, int count, std::uint32_t* even, std::uint32_t* odd) {
  int x = 0;
  for (; x + 8 <= count; x += 8) {
    const uint32x4x2_t pairs = vld2q_u32(row + x);
    vst1q_u32(even + x / 2, pairs.val[0]);
    vst1q_u32(odd + x / 2, pairs.val[1]);
  }
  split_row_ref(row + x, count - x, even + x / 2, odd + x / 2);
}

int cascade_row_neon(const CascadeProgram& program, const std::uint32_t* row, int positions,
                     std::int32_t* hits) {
  if (!program.fixed_point_exact) return cascade_row_ref(program, row, positions, hits);
  return cascade_row_simd<simd::Neon>(program, row, positions, hits);
}

}  // namespace epipole::vision::kernels

// The Harris response with NEON: Sobel products 8 pixels at a time (int16 gradients, int32
// products), window sums 4 at a time (int32) and the float step 4 at a time. The integer parts
// are exact; the float step is harris_score's operations in its order, and this file is
// compiled with -ffp-contract=off (vision/CMakeLists.txt) so that no multiply is fused into a
// following add or subtract: results equal harris_response_ref bit for bit. Only intrinsics
// that exist on both AArch64 and ARMv7 are used. ARMv7 NEON flushes denormals to zero where
// the scalar VFP code does not; none can occur here: every non-zero a, b, c is at least
// scale2 >= 1e-9, a non-zero a c - b b at least an ulp of a number >= 1e-18, and k is 0 or
// >= 1e-6 (the detector checks it), so k trace trace is 0 or >= 1e-24.
#include <algorithm>
#include <limits>

#include "epipole/core/neon.hpp"
#include "harris_kernels.hpp"
#include "harris_rows.hpp"

namespace epipole::vision::kernels {

namespace {

void products_row_neon(const std::uint8_t* above, const std::uint8_t* row,
                       const std::uint8_t* below, int width, std::int32_t* xx, std::int32_t* xy,
                       std::int32_t* yy) {
  harris_products_columns_ref(above, row, below, width, 0, 1, xx, xy, yy);
  int x = 1;
  // A vector reads columns x-1 .. x+8, which must all lie inside the row.
  for (; x + 9 <= width; x += 8) {
    const uint8x8_t a0 = vld1_u8(above + x - 1), a1 = vld1_u8(above + x);
    const uint8x8_t a2 = vld1_u8(above + x + 1);
    const uint8x8_t r0 = vld1_u8(row + x - 1), r2 = vld1_u8(row + x + 1);
    const uint8x8_t b0 = vld1_u8(below + x - 1), b1 = vld1_u8(below + x);
    const uint8x8_t b2 = vld1_u8(below + x + 1);
    // Differences of two bytes wrap in uint16 and read back exactly as int16.
    const int16x8_t da = vreinterpretq_s16_u16(vsubl_u8(a2, a0));
    const int16x8_t dr = vreinterpretq_s16_u16(vsubl_u8(r2, r0));
    const int16x8_t db = vreinterpretq_s16_u16(vsubl_u8(b2, b0));
    const int16x8_t dx = vaddq_s16(vaddq_s16(da, db), vshlq_n_s16(dr, 1));
    const uint16x8_t top = vaddq_u16(vaddl_u8(a0, a2), vshll_n_u8(a1, 1));
    const uint16x8_t bottom = vaddq_u16(vaddl_u8(b0, b2), vshll_n_u8(b1, 1));
    const int16x8_t dy = vreinterpretq_s16_u16(vsubq_u16(bottom, top));

    const int16x4_t dx_lo = vget_low_s16(dx), dx_hi = vget_high_s16(dx);
    const int16x4_t dy_lo = vget_low_s16(dy), dy_hi = vget_high_s16(dy);
    vst1q_s32(xx + x, vmull_s16(dx_lo, dx_lo));
    vst1q_s32(xx + x + 4, vmull_s16(dx_hi, dx_hi));
    vst1q_s32(xy + x, vmull_s16(dx_lo, dy_lo));
    vst1q_s32(xy + x + 4, vmull_s16(dx_hi, dy_hi));
    vst1q_s32(yy + x, vmull_s16(dy_lo, dy_lo));
    vst1q_s32(yy + x + 4, vmull_s16(dy_hi, dy_hi));
  }
  // The last columns (and the reflected last one): the reference code.
  harris_products_columns_ref(above, row, below, width, x, width, xx, xy, yy);
}

// kCount > 0: that many rows, known when compiled (the window of 3, the default, unrolled);
// 0: `count` of them.
template <int kCount>
void column_sums_rows(const std::int32_t* const* rows, int count, int width, std::int32_t* sums) {
  if constexpr (kCount > 0) count = kCount;
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    int32x4_t lo = vld1q_s32(rows[0] + x);
    int32x4_t hi = vld1q_s32(rows[0] + x + 4);
#pragma GCC unroll 8
    for (int i = 1; i < count; ++i) {
      lo = vaddq_s32(lo, vld1q_s32(rows[i] + x));
      hi = vaddq_s32(hi, vld1q_s32(rows[i] + x + 4));
    }
    vst1q_s32(sums + x, lo);
    vst1q_s32(sums + x + 4, hi);
  }
  for (; x < width; ++x) {
    std::int32_t sum = 0;
    for (int i = 0; i < count; ++i) sum += rows[i][x];
    sums[x] = sum;
  }
}

void column_sums_neon(const std::int32_t* const* rows, int count, int width, std::int32_t* sums) {
  if (count == 3) {
    column_sums_rows<3>(rows, count, width, sums);
  } else {
    column_sums_rows<0>(rows, count, width, sums);
  }
}

// kBlock > 0: the window's width, known when compiled (3, the default, unrolled); 0:
// `block_size`.
template <int kBlock>
void box_response(const std::int32_t* sxx, const std::int32_t* sxy, const std::int32_t* syy,
                  int width, int block_size, float scale2, float k, float* out) {
  if constexpr (kBlock > 0) block_size = kBlock;
  const int radius = block_size / 2;
  const float32x4_t vscale = vdupq_n_f32(scale2);
  const float32x4_t vk = vdupq_n_f32(k);
  int x = 0;
  // The sums have `radius` reflected columns on either side, so every load is inside them.
  for (; x + 4 <= width; x += 4) {
    const int first = x - radius;
    int32x4_t sa = vld1q_s32(sxx + first);
    int32x4_t sb = vld1q_s32(sxy + first);
    int32x4_t sc = vld1q_s32(syy + first);
#pragma GCC unroll 8
    for (int i = 1; i < block_size; ++i) {
      sa = vaddq_s32(sa, vld1q_s32(sxx + first + i));
      sb = vaddq_s32(sb, vld1q_s32(sxy + first + i));
      sc = vaddq_s32(sc, vld1q_s32(syy + first + i));
    }
    // harris_score: a, b, c; det = a c - b b; trace = a + c; det - (k trace) trace.
    const float32x4_t a = vmulq_f32(vcvtq_f32_s32(sa), vscale);
    const float32x4_t b = vmulq_f32(vcvtq_f32_s32(sb), vscale);
    const float32x4_t c = vmulq_f32(vcvtq_f32_s32(sc), vscale);
    const float32x4_t det = vsubq_f32(vmulq_f32(a, c), vmulq_f32(b, b));
    const float32x4_t trace = vaddq_f32(a, c);
    vst1q_f32(out + x, vsubq_f32(det, vmulq_f32(vmulq_f32(vk, trace), trace)));
  }
  harris_box_response_columns_ref(sxx, sxy, syy, x, width, block_size, scale2, k, out);
}

void box_response_row_neon(const std::int32_t* sxx, const std::int32_t* sxy,
                           const std::int32_t* syy, int width, int block_size, float scale2,
                           float k, float* out) {
  if (block_size == 3) {
    box_response<3>(sxx, sxy, syy, width, block_size, scale2, k, out);
  } else {
    box_response<0>(sxx, sxy, syy, width, block_size, scale2, k, out);
  }
}

}  // namespace

// Four lanes of running maxima with std::max's rule (the new value only when strictly greater,
// so NaNs are passed over), then the lanes and the columns left over the same way.
float harris_max_response_neon(ImageView<const float> response) {
  const float none = -std::numeric_limits<float>::infinity();
  float32x4_t lanes = vdupq_n_f32(none);
  float max_r = none;
  for (int y = 0; y < response.height(); ++y) {
    const float* row = response.row(y);
    int x = 0;
    for (; x + 4 <= response.width(); x += 4) {
      const float32x4_t v = vld1q_f32(row + x);
      lanes = vbslq_f32(vcltq_f32(lanes, v), v, lanes);
    }
    for (; x < response.width(); ++x) max_r = std::max(max_r, row[x]);
  }
  max_r = std::max(max_r, vgetq_lane_f32(lanes, 0));
  max_r = std::max(max_r, vgetq_lane_f32(lanes, 1));
  max_r = std::max(max_r, vgetq_lane_f32(lanes, 2));
  max_r = std::max(max_r, vgetq_lane_f32(lanes, 3));
  return max_r == 0.0f ? 0.0f : max_r;
}

// Eight responses at a time: most are not above the threshold (1 % of the largest, by default),
// and a block of eight with none above it is passed over; the others are tested one by one.
std::size_t harris_candidates_row_neon(const float* above, const float* row, const float* below,
                                       int width, float threshold, std::uint32_t row_offset,
                                       std::uint32_t* out) {
  const float32x4_t t = vdupq_n_f32(threshold);
  std::size_t n = 0;
  const auto test = [&](int x) {
    if (harris_is_candidate(above, row, below, x, threshold)) {
      out[n++] = row_offset + static_cast<std::uint32_t>(x);
    }
  };
  int x = 1;
  for (; x + 8 <= width - 1; x += 8) {
    const uint32x4_t low = vcgtq_f32(vld1q_f32(row + x), t);
    const uint32x4_t high = vcgtq_f32(vld1q_f32(row + x + 4), t);
    const uint16x4_t any = vmovn_u32(vorrq_u32(low, high));
    if (vget_lane_u64(vreinterpret_u64_u16(any), 0) == 0) continue;
    for (int i = 0; i < 8; ++i) test(x + i);
  }
  for (; x < width - 1; ++x) test(x);
  return n;
}

void harris_response_neon(GrayView image, int block_size, float k, std::int32_t* workspace,
                          ImageView<float> response) {
  static constexpr HarrisRowKernels kRows{products_row_neon, column_sums_neon,
                                          box_response_row_neon};
  harris_response_rows(image, block_size, k, workspace, response, kRows);
}

}  // namespace epipole::vision::kernels

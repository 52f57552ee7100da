// The post-filters of disparity_filters.hpp in NEON. Hole filling, eight pixels at a time: valid
// stretches are skipped and long holes measured with one compare per eight, holes filled with
// eight-wide stores; the decision for each hole is the reference's.
#include <algorithm>

#include "disparity_filters_kernels.hpp"
#include "epipole/core/neon.hpp"
#include "epipole/vision/disparity_filters.hpp"

namespace epipole::vision::kernels {

namespace {

// Each lane all ones where the disparity is invalid (negative).
inline uint64x2_t invalid_lanes(const std::int16_t* p) {
  return vreinterpretq_u64_s16(vshrq_n_s16(vld1q_s16(p), 15));
}
inline bool any_invalid(const std::int16_t* p) {
  const uint64x2_t m = invalid_lanes(p);
  return (vgetq_lane_u64(m, 0) | vgetq_lane_u64(m, 1)) != 0;
}
inline bool all_invalid(const std::int16_t* p) {
  const uint64x2_t m = invalid_lanes(p);
  return (vgetq_lane_u64(m, 0) & vgetq_lane_u64(m, 1)) == ~std::uint64_t{0};
}

}  // namespace

void fill_holes_row_neon(std::int16_t* row, int width, int max_hole) {
  int x = 0;
  for (;;) {
    while (x + 8 <= width && !any_invalid(row + x)) x += 8;
    while (x < width && row[x] >= 0) ++x;
    if (x >= width) return;
    const int begin = x;
    while (x + 8 <= width && all_invalid(row + x)) x += 8;
    while (x < width && row[x] < 0) ++x;
    if (begin == 0 || x == width || x - begin > max_hole) continue;
    const std::int16_t farther = std::min(row[begin - 1], row[x]);
    const int16x8_t fill = vdupq_n_s16(farther);
    int i = begin;
    for (; i + 8 <= x; i += 8) vst1q_s16(row + i, fill);
    for (; i < x; ++i) row[i] = farther;
  }
}

namespace {

// The blend of both filters, eight pixels: each moved towards `before` where both are valid and
// close, the step rounded half away from zero. |pixel - before| * weight is formed in 16 bits:
// exact where it is used (steps of at most 7 px x16 = 112, weights up to 256), wrapping
// harmlessly where the lane is not taken.
class Blend {
 public:
  Blend(int weight, int max_step_x16)
      : weight_(vdupq_n_s16(static_cast<std::int16_t>(weight))),
        step_(vdupq_n_s16(static_cast<std::int16_t>(max_step_x16))) {}

  int16x8_t operator()(int16x8_t pixel, int16x8_t before) const {
    const int16x8_t zero = vdupq_n_s16(0);
    const int16x8_t difference = vsubq_s16(pixel, before);
    const int16x8_t size = vabsq_s16(difference);
    const uint16x8_t close = vandq_u16(vandq_u16(vcgeq_s16(pixel, zero), vcgeq_s16(before, zero)),
                                       vcleq_s16(size, step_));
    const int16x8_t moved = vshrq_n_s16(vaddq_s16(vmulq_s16(size, weight_), vdupq_n_s16(128)), 8);
    // The step's sign back on: (moved ^ s) - s is -moved where s is all ones.
    const int16x8_t sign = vshrq_n_s16(difference, 15);
    return vbslq_s16(close, vaddq_s16(before, vsubq_s16(veorq_s16(moved, sign), sign)), pixel);
  }

 private:
  int16x8_t weight_, step_;
};

// An 8x8 block of 16-bit values, rows to columns.
inline void transpose8x8(const std::int16_t* source, std::ptrdiff_t source_stride,
                         std::int16_t* target, std::ptrdiff_t target_stride) {
  int16x8_t r[8];
  for (int i = 0; i < 8; ++i) r[i] = vld1q_s16(source + i * source_stride);
  // Pairs of rows interleaved by 16, then by 32 bits: each 64-bit half is then four values of
  // one column, and the halves are put together.
  const int16x8x2_t t01 = vtrnq_s16(r[0], r[1]), t23 = vtrnq_s16(r[2], r[3]);
  const int16x8x2_t t45 = vtrnq_s16(r[4], r[5]), t67 = vtrnq_s16(r[6], r[7]);
  const auto trn32 = [](int16x8_t a, int16x8_t b) {
    return vtrnq_s32(vreinterpretq_s32_s16(a), vreinterpretq_s32_s16(b));
  };
  const int32x4x2_t u02 = trn32(t01.val[0], t23.val[0]), u13 = trn32(t01.val[1], t23.val[1]);
  const int32x4x2_t u46 = trn32(t45.val[0], t67.val[0]), u57 = trn32(t45.val[1], t67.val[1]);
  const auto low = [](int32x4_t a, int32x4_t b) {
    return vreinterpretq_s16_s32(vcombine_s32(vget_low_s32(a), vget_low_s32(b)));
  };
  const auto high = [](int32x4_t a, int32x4_t b) {
    return vreinterpretq_s16_s32(vcombine_s32(vget_high_s32(a), vget_high_s32(b)));
  };
  const int16x8_t columns[8] = {low(u02.val[0], u46.val[0]),  low(u13.val[0], u57.val[0]),
                                low(u02.val[1], u46.val[1]),  low(u13.val[1], u57.val[1]),
                                high(u02.val[0], u46.val[0]), high(u13.val[0], u57.val[0]),
                                high(u02.val[1], u46.val[1]), high(u13.val[1], u57.val[1])};
  for (int i = 0; i < 8; ++i) vst1q_s16(target + i * target_stride, columns[i]);
}

}  // namespace

// The temporal filter of disparity_filters.hpp, eight pixels at a time.
void temporal_row_neon(std::int16_t* now, std::int16_t* last, int width, int weight,
                       int max_step_x16) {
  const Blend blend(weight, max_step_x16);
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const int16x8_t out = blend(vld1q_s16(now + x), vld1q_s16(last + x));
    vst1q_s16(now + x, out);
    vst1q_s16(last + x, out);
  }
  temporal_row_ref(now + x, last + x, width - x, weight, max_step_x16);
}

// The spatial filter of disparity_filters.hpp. Along the rows, eight rows at a time: the band's
// columns are turned into vectors of eight (scratch), filtered one after the other both ways,
// and turned back; the last band, of fewer rows, has invalid lanes below them, which blend with
// nothing. Along the columns, row after row: each row blended with the one filtered before it,
// as the temporal filter blends a pair with its memory.
void spatial_pass_neon(std::int16_t* image, std::ptrdiff_t stride, int width, int height,
                       int weight, int max_step_x16, std::int16_t* scratch) {
  const Blend blend(weight, max_step_x16);
  std::int16_t* const band = scratch;  // column x of the band at band + 8 * x
  std::int16_t* const before = scratch + 8 * static_cast<std::ptrdiff_t>(width);
  const auto row = [&](int y) { return image + y * stride; };
  for (int y = 0; y < height; y += 8) {
    std::int16_t* const rows = row(y);
    const int n = std::min(8, height - y);
    int x = 0;
    if (n == 8) {
      for (; x + 8 <= width; x += 8) transpose8x8(rows + x, stride, band + 8 * x, 8);
    }
    for (; x < width; ++x) {
      for (int i = 0; i < 8; ++i) band[8 * x + i] = i < n ? rows[i * stride + x] : -1;
    }
    int16x8_t last = vld1q_s16(band);
    for (x = 1; x < width; ++x) {
      last = blend(vld1q_s16(band + 8 * x), last);
      vst1q_s16(band + 8 * x, last);
    }
    for (x = width - 2; x >= 0; --x) {
      last = blend(vld1q_s16(band + 8 * x), last);
      vst1q_s16(band + 8 * x, last);
    }
    x = 0;
    if (n == 8) {
      for (; x + 8 <= width; x += 8) transpose8x8(band + 8 * x, 8, rows + x, stride);
    }
    for (; x < width; ++x) {
      for (int i = 0; i < n; ++i) rows[i * stride + x] = band[8 * x + i];
    }
  }
  std::copy_n(row(0), width, before);
  for (int y = 1; y < height; ++y) temporal_row_neon(row(y), before, width, weight, max_step_x16);
  for (int y = height - 2; y >= 0; --y) {
    temporal_row_neon(row(y), before, width, weight, max_step_x16);
  }
}

}  // namespace epipole::vision::kernels

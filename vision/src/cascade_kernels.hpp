#pragma once

// The cascade stage's kernel interfaces: the scalar *_ref that defines each result and its SIMD
// variants. Internal to vision: its sources and the tests and benchmarks that check every path
// against the reference (target epipole_vision_kernels) include it.
#include <cstdint>

#include "epipole/vision/cascade.hpp"

namespace epipole::vision::kernels {

// One row of the integral images of an 8-bit row of `width` pixels: with P(X) the sum of
// row[0..X-1], sum[X] = sum_above[X] + P(X) and square[X] = square_above[X] + (sum of squares)
// for X in [0, width], modulo 2^32 (as OpenCV's CV_32S sums wrap). When `prefix` is not null it
// receives width + 2 entries: 0, P(0), P(1), ..., P(width) (the tilted kernel's input). With
// `square` null no squares are summed (LBP cascades need none).
void integral_row_ref(const std::uint8_t* row, int width, const std::uint32_t* sum_above,
                      const std::uint32_t* square_above, std::uint32_t* sum, std::uint32_t* square,
                      std::uint32_t* prefix);
void integral_row_neon(const std::uint8_t* row, int width, const std::uint32_t* sum_above,
                       const std::uint32_t* square_above, std::uint32_t* sum, std::uint32_t* square,
                       std::uint32_t* prefix);
void integral_row_avx2(const std::uint8_t* row, int width, const std::uint32_t* sum_above,
                       const std::uint32_t* square_above, std::uint32_t* sum, std::uint32_t* square,
                       std::uint32_t* prefix);
using IntegralRowKernel = void(const std::uint8_t*, int, const std::uint32_t*, const std::uint32_t*,
                               std::uint32_t*, std::uint32_t*, std::uint32_t*);
IntegralRowKernel* integral_row_kernel(SimdPath path);

// One row of the tilted (45 degree) integral image, OpenCV's: T(X, Y) is the sum of the pixels
// (x, y) with y < Y and |x - (X - 1)| <= Y - 1 - y. It is computed as L(X) - R(X + 1) from two
// running rows of width + 2 entries (all zero before the first image row):
//   L'(X) = L(X + 1) + prefix(X + 1) for X <= width, L'(width + 1) = L(width + 1) + P(width);
//   R'(0) = 0, R'(X + 1) = R(X) + prefix(X) for X <= width;
// `prefix` as integral_row writes it. `tilted` receives width + 1 entries.
void tilted_row_ref(const std::uint32_t* prefix, int width, const std::uint32_t* left_above,
                    const std::uint32_t* right_above, std::uint32_t* left, std::uint32_t* right,
                    std::uint32_t* tilted);
void tilted_row_neon(const std::uint32_t* prefix, int width, const std::uint32_t* left_above,
                     const std::uint32_t* right_above, std::uint32_t* left, std::uint32_t* right,
                     std::uint32_t* tilted);
using TiltedRowKernel = void(const std::uint32_t*, int, const std::uint32_t*, const std::uint32_t*,
                             std::uint32_t*, std::uint32_t*, std::uint32_t*);
TiltedRowKernel* tilted_row_kernel(SimdPath path);

// The pyramid levels are cv::resize(INTER_LINEAR_EXACT), as OpenCV 4.6's cascade builds them:
// 8-bit fractions (256 = 1), computed in double. Horizontal pass of one source row:
// out[x] = row[offsets[x]] * weights[2x] + row[offsets[x] + 1] * weights[2x + 1], the second
// term left out where offsets[x] is the last pixel (source_width - 1; its weight is 0 there).
// Offsets never decrease.
void resize_columns_ref(const std::uint8_t* row, int source_width, const std::int32_t* offsets,
                        const std::uint16_t* weights, int width, std::uint16_t* out);
void resize_columns_neon(const std::uint8_t* row, int source_width, const std::int32_t* offsets,
                         const std::uint16_t* weights, int width, std::uint16_t* out);
void resize_columns_avx2(const std::uint8_t* row, int source_width, const std::int32_t* offsets,
                         const std::uint16_t* weights, int width, std::uint16_t* out);
using ResizeColumnsKernel = void(const std::uint8_t*, int, const std::int32_t*,
                                 const std::uint16_t*, int, std::uint16_t*);
ResizeColumnsKernel* resize_columns_kernel(SimdPath path);

// Vertical pass: out[x] = (top[x] * w0 + bottom[x] * w1 + 32768) >> 16 (w0 + w1 = 256).
void resize_rows_ref(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
                     std::uint16_t w1, int width, std::uint8_t* out);
void resize_rows_neon(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
                      std::uint16_t w1, int width, std::uint8_t* out);
void resize_rows_avx2(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
                      std::uint16_t w1, int width, std::uint8_t* out);
using ResizeRowsKernel = void(const std::uint16_t*, const std::uint16_t*, std::uint16_t,
                              std::uint16_t, int, std::uint8_t*);
ResizeRowsKernel* resize_rows_kernel(SimdPath path);

// The offsets and weights of INTER_LINEAR_EXACT from `source` to `size` pixels (the same rule
// for columns and rows): with f = (i + 0.5) * (1 / (size / source)) - 0.5 in double, pixel i
// blends source pixels floor(f) and floor(f) + 1 with weights 256 - w1 and w1 = round(256 *
// (f - floor(f))) (ties to even); where floor(f) < 0 it is pixel 0, where floor(f) >=
// source - 1 the last pixel (weights 256, 0). `size` offsets and 2 * size weights.
void resize_coefficients(int source, int size, std::int32_t* offsets, std::uint16_t* weights);

}  // namespace epipole::vision::kernels

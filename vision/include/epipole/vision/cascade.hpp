#pragma once

// The Viola-Jones detector: a boosted cascade (cascade_model.hpp) run over an image pyramid,
// with the same windows, decisions and grouping as cv::CascadeClassifier::detectMultiScale
// (OpenCV 4.6), so that it finds the same boxes. docs/vision.md, "Viola-Jones cascade".

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/vision/cascade_model.hpp"

namespace epipole::vision {

struct CascadeConfig {
  int max_width = 0;  // the largest image detect() accepts
  int max_height = 0;
  double scale_factor = 1.1;  // > 1: each pyramid level is this much smaller
  // Groups of raw hits with at most this many members are dropped (groupRectangles'
  // groupThreshold, eps 0.2); 0 returns the raw hits ungrouped, as OpenCV does.
  int min_neighbors = 3;
  int min_object_width = 0;  // smaller windows are not searched (0: none)
  int min_object_height = 0;
  int max_object_width = 0;  // larger windows are not searched (0: the image size)
  int max_object_height = 0;
  int max_raw_hits = 5'000;  // bounds: hits beyond them are dropped and truncated() says so
  int max_detections = 1'000;
};

struct Detection {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  int neighbors = 0;  // raw hits in the group (1 for ungrouped hits)
  friend bool operator==(const Detection&, const Detection&) = default;
};

namespace kernels {
struct CascadeProgram;
}

// Fixed memory: the constructor allocates the pyramid level, the integral images (upright, of
// squares, and tilted when the cascade has tilted features), the evaluation tables, the raw
// hit list and the grouping scratch; detect() never allocates.
class CascadeDetector {
 public:
  // Throws Error for a bad configuration (sizes, scale factor, bounds).
  CascadeDetector(const CascadeModel& model, const CascadeConfig& config,
                  SimdPath path = best_simd_path());
  ~CascadeDetector();
  CascadeDetector(CascadeDetector&&) noexcept;
  CascadeDetector& operator=(CascadeDetector&&) noexcept;

  // The grouped detections of an 8-bit gray image no larger than the configured size, clipped
  // to the image, in OpenCV's order. The span stays valid until the next call.
  std::span<const Detection> detect(GrayView image);

  // The last image's raw hits (windows that passed every stage), before grouping, in OpenCV's
  // order (level by level, row by row).
  std::span<const Detection> raw_hits() const;
  // True when the last image had more raw hits or detections than the bounds.
  bool truncated() const;
  // Pyramid levels the last image was searched at.
  int levels() const;

  const CascadeConfig& config() const;
  SimdPath simd_path() const;
  // False when the cascade is not stump-based (or its leaves cannot be summed exactly in fixed
  // point): every path then evaluates windows with the reference code.
  bool simd_windows() const;
  // Everything the constructor allocated: evaluation tables (two layouts), pyramid level,
  // integral planes, scratch rows, coefficients, hit lists and grouping scratch.
  std::size_t working_set_bytes() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

namespace kernels {

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
using ResizeColumnsKernel = void(const std::uint8_t*, int, const std::int32_t*,
                                 const std::uint16_t*, int, std::uint16_t*);
ResizeColumnsKernel* resize_columns_kernel(SimdPath path);

// Vertical pass: out[x] = (top[x] * w0 + bottom[x] * w1 + 32768) >> 16 (w0 + w1 = 256).
void resize_rows_ref(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
                     std::uint16_t w1, int width, std::uint8_t* out);
void resize_rows_neon(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
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

}  // namespace kernels
}  // namespace epipole::vision

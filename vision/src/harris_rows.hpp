#pragma once

// The row stages of the Harris response, shared by harris.cpp (reference) and harris_neon.cpp.
#include <cstddef>
#include <cstdint>

#include "epipole/core/image.hpp"

namespace epipole::vision::kernels {

// Sobel products of one image row for columns [x_begin, x_end): with dx, dy the 3x3 Sobel
// derivatives (columns reflected at 0 and width-1 as BORDER_REFLECT_101), xx = dx*dx,
// xy = dx*dy, yy = dy*dy. `above` and `below` are the (already reflected) neighbour rows.
void harris_products_columns_ref(const std::uint8_t* above, const std::uint8_t* row,
                                 const std::uint8_t* below, int width, int x_begin, int x_end,
                                 std::int32_t* xx, std::int32_t* xy, std::int32_t* yy);

// The window sums of columns [x_begin, x_end) and their response. `sxx`, `sxy`, `syy` hold the
// vertical window sums of one output row with block_size / 2 reflected columns readable on
// either side of [0, width).
void harris_box_response_columns_ref(const std::int32_t* sxx, const std::int32_t* sxy,
                                     const std::int32_t* syy, int x_begin, int x_end,
                                     int block_size, float scale2, float k, float* out);

// The per-pixel float step, which defines the response: every implementation performs these
// operations in this order (and without fused multiply-add).
inline float harris_score(std::int32_t sum_xx, std::int32_t sum_xy, std::int32_t sum_yy,
                          float scale2, float k) {
  const float a = static_cast<float>(sum_xx) * scale2;
  const float b = static_cast<float>(sum_xy) * scale2;
  const float c = static_cast<float>(sum_yy) * scale2;
  const float det = a * c - b * b;
  const float trace = a + c;
  return det - k * trace * trace;  // (k * trace) * trace
}

struct HarrisRowKernels {
  // Products of a whole row, [0, width).
  void (*products)(const std::uint8_t* above, const std::uint8_t* row, const std::uint8_t* below,
                   int width, std::int32_t* xx, std::int32_t* xy, std::int32_t* yy);
  // sums[x] = rows[0][x] + ... + rows[count-1][x] for x in [0, width).
  void (*column_sums)(const std::int32_t* const* rows, int count, int width, std::int32_t* sums);
  // Box sums and response of a whole row, [0, width).
  void (*box_response)(const std::int32_t* sxx, const std::int32_t* sxy, const std::int32_t* syy,
                       int width, int block_size, float scale2, float k, float* out);
};

// The whole-image driver: rows, reflection at the borders, the ring of product rows.
void harris_response_rows(GrayView image, int block_size, float k, std::int32_t* workspace,
                          ImageView<float> response, const HarrisRowKernels& rows);

}  // namespace epipole::vision::kernels

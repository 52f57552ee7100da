#pragma once

// The FAST stage's kernel interfaces: the scalar *_ref that defines each result and its SIMD
// variants. Internal to vision: its sources and the tests and benchmarks that check every path
// against the reference (target epipole_vision_kernels) include it.
#include <cstddef>
#include <cstdint>

#include "epipole/vision/fast.hpp"

namespace epipole::vision::kernels {

// One image row of FAST-9. `row` points at pixel (0, y) of an image with rows y-3..y+3
// readable. Writes scores[x] for every x in [0, width): the corner score, or 0 where x is no
// corner or within 3 of the border. Appends the x of each corner to `columns` in increasing
// order and returns how many.
int fast_row_ref(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                 std::uint8_t* scores, int* columns);
int fast_row_neon(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns);
// x86 builds only.
int fast_row_avx2(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns);

using FastRowKernel = int(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                          std::uint8_t* scores, int* columns);

// The row kernel a FastDetector on this path runs.
FastRowKernel* fast_row_kernel(SimdPath path);

// The FAST score of the pixel at `p` (cv::FAST's definition): the largest threshold for which
// it is still a corner. `circle` holds the 16 circle offsets repeated to 25 entries.
int fast_score(const std::uint8_t* p, const std::ptrdiff_t* circle, int threshold);

// The 25 offsets (16 circle pixels, the first 9 repeated) for a row stride.
void fast_circle_offsets(std::ptrdiff_t stride, std::ptrdiff_t offsets[25]);

}  // namespace epipole::vision::kernels

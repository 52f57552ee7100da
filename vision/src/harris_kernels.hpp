#pragma once

// The Harris stage's kernel interfaces: the scalar *_ref that defines each result and its SIMD
// variants. Internal to vision: its sources and the tests and benchmarks that check every path
// against the reference (target epipole_vision_kernels) include it.
#include <cstddef>
#include <cstdint>

#include "epipole/vision/harris.hpp"

namespace epipole::vision::kernels {

// The int32 elements of workspace harris_response_* need for an image `width` wide.
std::size_t harris_workspace_elements(int width, int block_size);

// The Harris response of a whole image into `response` (same size, any stride). Needs
// width, height >= max(3, block_size), block_size odd in [1, kHarrisMaxBlockSize] and
// harris_workspace_elements(width, block_size) elements of workspace; these are not checked.
// Both produce the same bits: the float step is the same operations in the same order, and
// the files are compiled with -ffp-contract=off (see vision/CMakeLists.txt).
void harris_response_ref(GrayView image, int block_size, float k, std::int32_t* workspace,
                         ImageView<float> response);
void harris_response_neon(GrayView image, int block_size, float k, std::int32_t* workspace,
                          ImageView<float> response);

using HarrisResponseKernel = void(GrayView image, int block_size, float k, std::int32_t* workspace,
                                  ImageView<float> response);

// The kernel a HarrisDetector on this path runs (there is no AVX2 kernel: that path runs the
// NEON one).
HarrisResponseKernel* harris_response_kernel(SimdPath path);

// The largest response of the image (goodFeaturesToTrack's max of R), NaNs passed over; -inf
// when there is none; +0 when it is a zero (the largest of +0 and -0 is either, so it is fixed:
// the SIMD variants compare in another order).
float harris_max_response_ref(ImageView<const float> response);
float harris_max_response_neon(ImageView<const float> response);
using HarrisMaxResponseKernel = float(ImageView<const float> response);
HarrisMaxResponseKernel* harris_max_response_kernel(SimdPath path);

// The corner candidates of one response row (goodFeaturesToTrack's): the x in [1, width - 1)
// whose response v is above `threshold`, not 0, and not below any of its 8 neighbours' responses
// kept by the threshold (those not above it count as 0). Appends row_offset + x for each, in
// increasing x, to `out` and returns how many. `above` and `below` are the rows around `row`.
std::size_t harris_candidates_row_ref(const float* above, const float* row, const float* below,
                                      int width, float threshold, std::uint32_t row_offset,
                                      std::uint32_t* out);
std::size_t harris_candidates_row_neon(const float* above, const float* row, const float* below,
                                       int width, float threshold, std::uint32_t row_offset,
                                       std::uint32_t* out);

using HarrisCandidatesRowKernel = std::size_t(const float* above, const float* row,
                                              const float* below, int width, float threshold,
                                              std::uint32_t row_offset, std::uint32_t* out);

HarrisCandidatesRowKernel* harris_candidates_row_kernel(SimdPath path);

// Whether x is a candidate (harris_candidates_row_ref's test), for the SIMD variants.
inline bool harris_is_candidate(const float* above, const float* row, const float* below, int x,
                                float threshold) {
  const float v = row[x];
  if (!(v > threshold) || v == 0.0f) return false;
  const auto kept = [threshold](float n) { return n > threshold ? n : 0.0f; };
  return !(v < kept(above[x - 1]) || v < kept(above[x]) || v < kept(above[x + 1]) ||
           v < kept(row[x - 1]) || v < kept(row[x + 1]) || v < kept(below[x - 1]) ||
           v < kept(below[x]) || v < kept(below[x + 1]));
}

}  // namespace epipole::vision::kernels

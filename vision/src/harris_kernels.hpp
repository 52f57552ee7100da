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

}  // namespace epipole::vision::kernels

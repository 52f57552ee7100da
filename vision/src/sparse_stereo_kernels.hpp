#pragma once

// The sparse stereo stage's kernel interfaces: the scalar *_ref that defines each result and its
// SIMD variants. Internal to vision: its sources and the tests and benchmarks that check every
// path against the reference (target epipole_vision_kernels) include it.
#include <cstdint>

#include "epipole/vision/sparse_stereo.hpp"

namespace epipole::vision::kernels {

// Hamming distances between one 32-byte descriptor and n consecutive ones.
using HammingKernel = void(const std::uint8_t* query, const std::uint8_t* candidates, int n,
                           std::uint16_t* distances);
void hamming_ref(const std::uint8_t* query, const std::uint8_t* candidates, int n,
                 std::uint16_t* distances);
void hamming_neon(const std::uint8_t* query, const std::uint8_t* candidates, int n,
                  std::uint16_t* distances);
HammingKernel* hamming_kernel(SimdPath path);

// The 5x5 box sums of one row, the descriptors' smoothing: out[x] = the sum of the pixels in
// columns x - 2 .. x + 2 of rows[0..4] (rows y - 2 .. y + 2), for 2 <= x < width - 2; the other
// entries of out are left as they are.
using Box5RowKernel = void(const std::uint8_t* const* rows, int width, std::uint16_t* out);
void box5_row_ref(const std::uint8_t* const* rows, int width, std::uint16_t* out);
void box5_row_neon(const std::uint8_t* const* rows, int width, std::uint16_t* out);
Box5RowKernel* box5_row_kernel(SimdPath path);

}  // namespace epipole::vision::kernels

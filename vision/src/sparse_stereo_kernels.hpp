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

}  // namespace epipole::vision::kernels

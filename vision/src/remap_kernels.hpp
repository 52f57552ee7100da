#pragma once

// The remap stage's kernel interfaces: the scalar *_ref that defines each result and its SIMD
// variants. Internal to vision: its sources and the tests and benchmarks that check every path
// against the reference (target epipole_vision_kernels) include it.
#include <cstdint>

#include "epipole/vision/remap.hpp"

namespace epipole::vision::kernels {

// One destination row of the bilinear remap: destination[i] for i in [0, width) from the map
// entries xy[2i], xy[2i + 1], fractions[i] (layout of RemapMap), source pixels outside
// `source` taking the value `border`. Defined for every map value and any source size
// (an empty source gives the border everywhere); source dimensions must be at most 32767.
void remap_row_ref(GrayView source, const std::int16_t* xy, const std::uint16_t* fractions,
                   int width, std::uint8_t border, std::uint8_t* destination);
void remap_row_neon(GrayView source, const std::int16_t* xy, const std::uint16_t* fractions,
                    int width, std::uint8_t border, std::uint8_t* destination);

// x86 builds only.
void remap_row_avx2(GrayView source, const std::int16_t* xy, const std::uint16_t* fractions,
                    int width, std::uint8_t border, std::uint8_t* destination);

using RemapRowKernel = void(GrayView source, const std::int16_t* xy, const std::uint16_t* fractions,
                            int width, std::uint8_t border, std::uint8_t* destination);

// The row kernel a Rectifier on this path runs.
RemapRowKernel* remap_row_kernel(SimdPath path);

}  // namespace epipole::vision::kernels

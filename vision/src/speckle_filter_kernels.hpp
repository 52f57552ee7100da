#pragma once

// The speckle filter's kernel interfaces: the scalar *_ref that defines each result and its SIMD
// variants. Internal to vision: its sources and the tests that check every path against the
// reference (target epipole_vision_kernels) include it.
#include <cstddef>
#include <cstdint>

namespace epipole::vision::kernels {

// The speckle filter's view of one row, 16 pixels a 64-bit word and 4 bits a pixel (all set or
// all clear): pixel x in bits 4 * (x % 16) .. 4 * (x % 16) + 3 of word x / 16; the nibbles past
// the width clear.
//   valid[x]: row[x] >= 0;
//   left[x]:  x > 0, row[x] and row[x - 1] valid and at most range_x16 apart (x continues the
//             run of x - 1);
//   up[x]:    row[x] and above[x] valid and at most range_x16 apart (all clear when above is
//             null).
using SpeckleMasksRow = void(const std::int16_t* row, const std::int16_t* above, int width,
                             int range_x16, std::uint64_t* valid, std::uint64_t* left,
                             std::uint64_t* up);
void speckle_masks_row_ref(const std::int16_t* row, const std::int16_t* above, int width,
                           int range_x16, std::uint64_t* valid, std::uint64_t* left,
                           std::uint64_t* up);
void speckle_masks_row_neon(const std::int16_t* row, const std::int16_t* above, int width,
                            int range_x16, std::uint64_t* valid, std::uint64_t* left,
                            std::uint64_t* up);

}  // namespace epipole::vision::kernels

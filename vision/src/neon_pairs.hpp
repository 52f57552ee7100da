#pragma once

// Pixel pairs for the NEON kernels, which have no gather instruction: each 2-pixel pair is
// fetched with a scalar 16-bit load and four are packed in a general register, then moved to a
// vector at once (inserting them into vector lanes one by one would chain each insert to the
// last).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "epipole/core/neon.hpp"

namespace epipole::vision::kernels {

// The 2-pixel pair at `p` (first pixel in the low byte, as memory holds it).
inline std::uint64_t pair_at(const std::uint8_t* p) {
  std::uint16_t pair;
  std::memcpy(&pair, p, 2);
  return pair;
}

// The pairs at four offsets of `row`, as four 16-bit lanes.
inline uint16x4_t pairs4(const std::uint8_t* row, std::ptrdiff_t o0, std::ptrdiff_t o1,
                         std::ptrdiff_t o2, std::ptrdiff_t o3) {
  return vcreate_u16(pair_at(row + o0) | pair_at(row + o1) << 16 | pair_at(row + o2) << 32 |
                     pair_at(row + o3) << 48);
}

}  // namespace epipole::vision::kernels

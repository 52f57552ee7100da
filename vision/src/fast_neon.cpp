// FAST-9 with NEON, 16 pixels at a time: the generic kernel of fast_simd.hpp.
#include "fast_simd.hpp"
#include "simd/neon.hpp"

namespace epipole::vision::kernels {

int fast_row_neon(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns) {
  return fast_row_simd<simd::Neon>(row, stride, width, threshold, scores, columns);
}

}  // namespace epipole::vision::kernels

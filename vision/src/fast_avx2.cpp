// FAST-9 with AVX2, 32 pixels at a time: the generic kernel of fast_simd.hpp (x86 hosts only).
#include "fast_simd.hpp"
#include "simd/avx2.hpp"

namespace epipole::vision::kernels {

int fast_row_avx2(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns) {
  return fast_row_simd<simd::Avx2>(row, stride, width, threshold, scores, columns);
}

}  // namespace epipole::vision::kernels

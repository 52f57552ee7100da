// The stereo kernels with AVX2, 16 disparities at a time (bytes in SSE registers, 16-bit sums
// in AVX registers): the generic kernels of stereo_simd.hpp (x86 hosts only).
#include "simd/avx2_x16.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

StereoKernels stereo_kernels_avx2() {
  return {census_row_simd<simd::Avx2X16>, cost_row_simd<simd::Avx2X16>, sgm_row_simd<simd::Avx2X16>,
          box_columns_simd<simd::Avx2X16>, box_wta_simd<simd::Avx2X16>};
}

}  // namespace epipole::vision::kernels

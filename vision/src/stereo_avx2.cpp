// The stereo kernels with AVX2, 16 disparities at a time: the generic kernels of stereo_simd.hpp
// (x86 hosts only).
#include "simd/avx2_u16.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

StereoKernels stereo_kernels_avx2() {
  return {census_row_simd<simd::Avx2U16>,  cost_row_simd<simd::Avx2U16>,
          sgm_row_simd<simd::Avx2U16>,     wta_row_simd<simd::Avx2U16>,
          box_columns_simd<simd::Avx2U16>, box_row_simd<simd::Avx2U16>};
}

}  // namespace epipole::vision::kernels

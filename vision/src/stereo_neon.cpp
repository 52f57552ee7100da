// The stereo kernels with NEON, 8 disparities at a time: the generic kernels of stereo_simd.hpp.
#include "simd/neon_u16.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

StereoKernels stereo_kernels_neon() {
  return {census_row_simd<simd::NeonU16>,  cost_row_simd<simd::NeonU16>,
          sgm_row_simd<simd::NeonU16>,     wta_row_simd<simd::NeonU16>,
          box_columns_simd<simd::NeonU16>, box_row_simd<simd::NeonU16>};
}

}  // namespace epipole::vision::kernels

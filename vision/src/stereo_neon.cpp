// The stereo kernels with NEON, 16 disparities at a time: the generic kernels of
// stereo_simd.hpp.
#include "simd/neon_x16.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

StereoKernels stereo_kernels_neon() {
  return {census_row_simd<simd::NeonX16>, cost_row_simd<simd::NeonX16>, sgm_row_simd<simd::NeonX16>,
          box_columns_simd<simd::NeonX16>, bm_row_simd<simd::NeonX16>};
}

}  // namespace epipole::vision::kernels

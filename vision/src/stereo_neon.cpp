// The stereo kernels with NEON, 16 disparities at a time: the generic kernels of
// stereo_simd.hpp.
#include "simd/neon.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

StereoKernels stereo_kernels_neon() {
  return {census_row_simd<simd::Neon>, cost_row_simd<simd::Neon>, sgm_row_simd<simd::Neon>,
          box_columns_simd<simd::Neon>, bm_row_simd<simd::Neon>};
}

}  // namespace epipole::vision::kernels

// The stereo kernels with NEON, 16 disparities at a time: the generic kernels of
// stereo_simd.hpp, with the census as a word a pixel on AArch64.
#include "simd/neon.hpp"
#include "stereo_simd.hpp"

namespace epipole::vision::kernels {

StereoKernels stereo_kernels_neon() {
  // Words where ADDP sums the counts of 16 words in three instructions (AArch64, and SIMDe on
  // hosts); ARMv7's pairwise adds take half a register, six of them, and there four planes
  // cost less (armhf SGM: 535.6 M instructions a pair with words, 531.5 M with planes).
  constexpr CensusLayout kLayout =
      EPIPOLE_NEON_A64_FORMS ? CensusLayout::words : CensusLayout::planes;
  return {kLayout,
          census_row_simd<simd::Neon, kLayout>,
          cost_row_simd<simd::Neon, kLayout>,
          sgm_row_simd<simd::Neon>,
          box_columns_simd<simd::Neon>,
          bm_row_simd<simd::Neon>};
}

}  // namespace epipole::vision::kernels

// The cascade window kernel with AVX2 (x86 hosts only), 8 windows per vector: the generic
// kernel of cascade_simd.hpp. The integral images and the resize run their NEON kernels.
#include "cascade_program.hpp"
#include "cascade_simd.hpp"
#include "simd/avx2.hpp"

namespace epipole::vision::kernels {

int cascade_row_avx2(const CascadeProgram& program, const std::uint32_t* row, int positions,
                     std::int32_t* hits) {
  if (!program.fixed_point_exact) return cascade_row_ref(program, row, positions, hits);
  return cascade_row_simd<simd::Avx2>(program, row, positions, hits);
}

}  // namespace epipole::vision::kernels

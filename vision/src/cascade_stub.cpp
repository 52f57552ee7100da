// Temporary: the NEON and AVX2 entry points run the reference until their kernels land.
#include "cascade_program.hpp"
#include "epipole/vision/cascade.hpp"
namespace epipole::vision::kernels {
void integral_row_neon(const std::uint8_t* a, int b, const std::uint32_t* c, const std::uint32_t* d,
                       std::uint32_t* e, std::uint32_t* f, std::uint32_t* g) {
  integral_row_ref(a, b, c, d, e, f, g);
}
void tilted_row_neon(const std::uint32_t* a, int b, const std::uint32_t* c, const std::uint32_t* d,
                     std::uint32_t* e, std::uint32_t* f, std::uint32_t* g) {
  tilted_row_ref(a, b, c, d, e, f, g);
}
void resize_columns_neon(const std::uint8_t* a, int b, const std::int32_t* c,
                         const std::uint16_t* d, int e, std::uint16_t* f) {
  resize_columns_ref(a, b, c, d, e, f);
}
void resize_rows_neon(const std::uint16_t* a, const std::uint16_t* b, std::uint16_t c,
                      std::uint16_t d, int e, std::uint8_t* f) {
  resize_rows_ref(a, b, c, d, e, f);
}
int cascade_row_neon(const CascadeProgram& p, const std::uint32_t* r, int n, int s,
                     std::int32_t* h) {
  return cascade_row_ref(p, r, n, s, h);
}
int cascade_row_avx2(const CascadeProgram& p, const std::uint32_t* r, int n, int s,
                     std::int32_t* h) {
  return cascade_row_ref(p, r, n, s, h);
}
}  // namespace epipole::vision::kernels

// The cascade detector's AVX2 kernels (x86 hosts only): the integral rows 8 pixels at a time
// (in-vector prefix sums, the running sums kept in every lane), the pyramid's resize 8 pixels
// at a time along rows (pixel pairs fetched by scalar loads) and 16 down columns, and the window
// kernel with 8 windows per vector (the generic kernel of cascade_simd.hpp). Every result equals
// the reference's bit for bit. The tilted integral and the split of integral rows run their
// NEON kernels.
#include <immintrin.h>

#include <cstring>

#include "cascade_kernels.hpp"
#include "cascade_program.hpp"
#include "cascade_simd.hpp"
#include "simd/avx2.hpp"

namespace epipole::vision::kernels {

namespace {

__m256i load8(const std::uint32_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}
void store8(std::uint32_t* p, __m256i v) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v);
}

// Prefix sums of 8 words, modulo 2^32: within each 128-bit half, then the low half's total
// added to the high half.
__m256i prefix8(__m256i v) {
  v = _mm256_add_epi32(v, _mm256_slli_si256(v, 4));
  v = _mm256_add_epi32(v, _mm256_slli_si256(v, 8));
  const __m256i low_total = _mm256_shuffle_epi32(v, 0xFF);  // each half's last word
  return _mm256_add_epi32(v, _mm256_permute2x128_si256(low_total, low_total, 0x08));
}

__m256i last_word(__m256i v) {
  return _mm256_permutevar8x32_epi32(v, _mm256_set1_epi32(7));
}

}  // namespace

void integral_row_avx2(const std::uint8_t* row, int width, const std::uint32_t* sum_above,
                       const std::uint32_t* square_above, std::uint32_t* sum, std::uint32_t* square,
                       std::uint32_t* prefix) {
  integral_first_entries(sum_above, square_above, sum, square, prefix);
  __m256i running = _mm256_setzero_si256();  // the row's sum so far, in every word
  __m256i running_squares = _mm256_setzero_si256();
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const __m256i pixels =
        _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(row + x)));
    const __m256i p = _mm256_add_epi32(prefix8(pixels), running);
    running = last_word(p);
    store8(sum + x + 1, _mm256_add_epi32(p, load8(sum_above + x + 1)));
    if (prefix != nullptr) store8(prefix + x + 2, p);
    if (square == nullptr) continue;
    // A square (at most 65025) is the low 16 bits of the 16-bit product; the high ones are 0.
    const __m256i q =
        _mm256_add_epi32(prefix8(_mm256_mullo_epi16(pixels, pixels)), running_squares);
    running_squares = last_word(q);
    store8(square + x + 1, _mm256_add_epi32(q, load8(square_above + x + 1)));
  }
  integral_columns(row, x, width, sum_above, square_above, sum, square, prefix,
                   static_cast<std::uint32_t>(_mm256_cvtsi256_si32(running)),
                   static_cast<std::uint32_t>(_mm256_cvtsi256_si32(running_squares)));
}

void resize_columns_avx2(const std::uint8_t* row, int source_width, const std::int32_t* offsets,
                         const std::uint16_t* weights, int width, std::uint16_t* out) {
  // Each offset's pixel and the next one as the low bytes of a word, widened to the 16-bit
  // pairs that _mm256_madd_epi16 weighs with the (w0, w1) pairs: at most 255 * 256.
  const __m256i pair_bytes =
      _mm256_setr_epi8(0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1, 0, -1, 1, -1, 4,
                       -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1);
  int x = 0;
  const auto pair_at = [row](std::int32_t offset) {
    std::uint16_t pair;
    std::memcpy(&pair, row + offset, sizeof pair);
    return static_cast<int>(pair);
  };
  // Blocks whose 8 pixel pairs lie inside the row (offsets never decrease). The pairs are
  // fetched by scalar loads: a gather is slower on some x86 cores.
  for (; x + 8 <= width && offsets[x + 7] + 1 < source_width; x += 8) {
    const std::int32_t* o = offsets + x;
    const __m256i words =
        _mm256_setr_epi32(pair_at(o[0]), pair_at(o[1]), pair_at(o[2]), pair_at(o[3]), pair_at(o[4]),
                          pair_at(o[5]), pair_at(o[6]), pair_at(o[7]));
    const __m256i pairs = _mm256_shuffle_epi8(words, pair_bytes);
    const __m256i w = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(weights + 2 * x));
    const __m256i v = _mm256_madd_epi16(pairs, w);
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi32(v, v), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm256_castsi256_si128(packed));
  }
  resize_columns_ref(row, source_width, offsets + x, weights + 2 * x, width - x, out + x);
}

void resize_rows_avx2(const std::uint16_t* top, const std::uint16_t* bottom, std::uint16_t w0,
                      std::uint16_t w1, int width, std::uint8_t* out) {
  // _mm256_madd_epi16 multiplies signed 16 bits: each value v (at most 65280) goes in as
  // v - 32768, and 32768 * (w0 + w1) = 2^23 is added back.
  const __m256i weights = _mm256_set1_epi32(static_cast<int>(w0 | (std::uint32_t{w1} << 16)));
  const __m256i bias = _mm256_set1_epi16(static_cast<short>(0x8000));
  const __m256i back = _mm256_set1_epi32((1 << 23) + 32768);  // and the rounding
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    const __m256i t =
        _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(top + x)), bias);
    const __m256i b =
        _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(bottom + x)), bias);
    // Pixels 0-3 and 8-11, then 4-7 and 12-15: the packs below put them back in order.
    const __m256i low = _mm256_srli_epi32(
        _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpacklo_epi16(t, b), weights), back), 16);
    const __m256i high = _mm256_srli_epi32(
        _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpackhi_epi16(t, b), weights), back), 16);
    const __m256i words = _mm256_packus_epi32(low, high);
    const __m256i bytes = _mm256_permute4x64_epi64(_mm256_packus_epi16(words, words), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm256_castsi256_si128(bytes));
  }
  resize_rows_ref(top + x, bottom + x, w0, w1, width - x, out + x);
}

int cascade_row_avx2(const CascadeProgram& program, const std::uint32_t* row, int positions,
                     std::int32_t* hits) {
  if (!program.fixed_point_exact) return cascade_row_ref(program, row, positions, hits);
  return cascade_row_simd<simd::Avx2>(program, row, positions, hits);
}

}  // namespace epipole::vision::kernels

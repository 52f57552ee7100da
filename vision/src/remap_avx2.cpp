// Bilinear remap with AVX2 (x86 hosts only), 8 destination pixels at a time. The offsets of
// the 8 source neighbourhoods come from one multiply-add of the (x, y) pairs; two gathers fetch
// the top and bottom pixel pairs; the weighting is the integer arithmetic of remap_row_ref done
// with multiply-adds, so results equal the reference bit for bit. Blocks with a neighbourhood
// near or beyond the border take the reference code.
#include <immintrin.h>

#include <algorithm>
#include <cstring>
#include <limits>

#include "remap_kernels.hpp"

namespace epipole::vision::kernels {

namespace {

// The weighting of 8 pixels whose top pairs (S00, S01) and bottom pairs (S10, S11) sit in the
// low two bytes of each 32-bit lane of `top` and `bottom`.
inline __m128i blend8(__m256i top, __m256i bottom, __m128i fractions) {
  // Bytes 0 and 1 of each lane to two int16: (S00, S01) and (S10, S11).
  const __m256i spread = _mm256_setr_epi8(0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1,
                                          0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1);
  const __m256i upper_pairs = _mm256_shuffle_epi8(top, spread);
  const __m256i lower_pairs = _mm256_shuffle_epi8(bottom, spread);
  const __m256i f = _mm256_cvtepu16_epi32(fractions);
  const __m256i five_bits = _mm256_set1_epi32(31);
  const __m256i thirty_two = _mm256_set1_epi32(32);
  const __m256i fx = _mm256_and_si256(f, five_bits);
  const __m256i fy = _mm256_and_si256(_mm256_srli_epi32(f, 5), five_bits);
  // (32 - f, f) as int16 pairs.
  const __m256i x_weights =
      _mm256_or_si256(_mm256_sub_epi32(thirty_two, fx), _mm256_slli_epi32(fx, 16));
  const __m256i y_weights =
      _mm256_or_si256(_mm256_sub_epi32(thirty_two, fy), _mm256_slli_epi32(fy, 16));
  const __m256i upper = _mm256_madd_epi16(upper_pairs, x_weights);  // at most 255 * 32
  const __m256i lower = _mm256_madd_epi16(lower_pairs, x_weights);
  const __m256i vertical = _mm256_or_si256(upper, _mm256_slli_epi32(lower, 16));
  const __m256i sum =
      _mm256_add_epi32(_mm256_madd_epi16(vertical, y_weights), _mm256_set1_epi32(512));
  const __m256i value = _mm256_srli_epi32(sum, 10);         // at most 255
  const __m256i words = _mm256_packus_epi32(value, value);  // per 128-bit half: 4 values twice
  const __m256i bytes = _mm256_packus_epi16(words, words);  // per half: 4 bytes, repeated
  // Half 0 holds pixels 0..3 in its first 4 bytes, half 1 pixels 4..7.
  return _mm_unpacklo_epi32(_mm256_castsi256_si128(bytes), _mm256_extracti128_si256(bytes, 1));
}

}  // namespace

void remap_row_avx2(GrayView source, const std::int16_t* xy, const std::uint16_t* fractions,
                    int width, std::uint8_t border, std::uint8_t* destination) {
  const std::ptrdiff_t stride = source.stride();
  // The offsets are y * stride + x in 32 bits from one int16 multiply-add; larger images (and
  // rows too short for a block) take the reference code.
  if (width < 8 || source.width() < 4 || source.height() < 2 ||
      stride > std::numeric_limits<std::int16_t>::max() ||
      static_cast<long long>(stride) * source.height() > std::numeric_limits<std::int32_t>::max()) {
    remap_row_ref(source, xy, fractions, width, border, destination);
    return;
  }
  const auto* pixels = reinterpret_cast<const int*>(source.data());
  // A gather reads 4 bytes from x, so the fast path needs x + 3 inside the row and y + 1 inside
  // the image: 0 <= x < width - 3 and 0 <= y < height - 1 (unsigned, via a signed bias).
  const __m256i row_step = _mm256_set1_epi32(static_cast<int>(stride) << 16 | 1);
  const __m256i low_words = _mm256_set1_epi32(0xFFFF);
  const __m256i x_limit = _mm256_set1_epi32(source.width() - 3);
  const __m256i y_limit = _mm256_set1_epi32(source.height() - 1);
  const __m256i minus_one = _mm256_set1_epi32(-1);
  for (int i = 0; i < width; i += 8) {
    const int first = std::min(i, width - 8);
    const __m256i pairs = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(xy + 2 * first));
    const __m256i x = _mm256_srai_epi32(_mm256_slli_epi32(pairs, 16), 16);
    const __m256i y = _mm256_srai_epi32(pairs, 16);
    const __m256i x_inside =
        _mm256_and_si256(_mm256_cmpgt_epi32(x, minus_one), _mm256_cmpgt_epi32(x_limit, x));
    const __m256i y_inside =
        _mm256_and_si256(_mm256_cmpgt_epi32(y, minus_one), _mm256_cmpgt_epi32(y_limit, y));
    if (_mm256_movemask_epi8(_mm256_and_si256(x_inside, y_inside)) != -1) {
      remap_row_ref(source, xy + 2 * first, fractions + first, 8, border, destination + first);
      continue;
    }
    // x * 1 + y * stride; x's sign bits were cleared above by the inside test (x >= 0).
    const __m256i offsets = _mm256_madd_epi16(
        _mm256_and_si256(pairs, _mm256_or_si256(low_words, _mm256_slli_epi32(low_words, 16))),
        row_step);
    const __m256i top = _mm256_i32gather_epi32(pixels, offsets, 1);
    const __m256i bottom = _mm256_i32gather_epi32(
        pixels, _mm256_add_epi32(offsets, _mm256_set1_epi32(static_cast<int>(stride))), 1);
    const __m128i f = _mm_loadu_si128(reinterpret_cast<const __m128i*>(fractions + first));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(destination + first), blend8(top, bottom, f));
  }
}

}  // namespace epipole::vision::kernels

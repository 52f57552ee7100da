// The v-disparity row in NEON: the bins of eight pixels at a time (a shift, two comparisons,
// the uncounted pixels sent to bin 0), counted into four partial histograms in turn, so that a
// row whose pixels share one disparity (the ground's rows do) does not wait on one counter's
// store before each increment.
#include <algorithm>

#include "epipole/core/neon.hpp"
#include "ground_plane_kernels.hpp"

namespace epipole::vision::kernels {

void v_disparity_row_neon(const std::int16_t* row, int width, int bins, std::uint16_t* counts,
                          std::uint16_t* scratch) {
  const auto lanes = static_cast<std::size_t>(kVDisparityLanes);
  const auto n = static_cast<std::size_t>(bins);
  std::fill_n(scratch, lanes * n, std::uint16_t{0});
  std::uint16_t* const h0 = scratch;
  std::uint16_t* const h1 = scratch + n;
  std::uint16_t* const h2 = scratch + 2 * n;
  std::uint16_t* const h3 = scratch + 3 * n;
  const int16x8_t one = vdupq_n_s16(1);
  const int16x8_t limit = vdupq_n_s16(static_cast<std::int16_t>(bins));
  std::uint16_t bin[8];
  int x = 0;
  for (; x + 8 <= width; x += 8) {
    const int16x8_t d = vshrq_n_s16(vld1q_s16(row + x), 4);
    const uint16x8_t counted = vandq_u16(vcgeq_s16(d, one), vcltq_s16(d, limit));
    vst1q_u16(bin, vandq_u16(vreinterpretq_u16_s16(d), counted));
    ++h0[bin[0]];
    ++h1[bin[1]];
    ++h2[bin[2]];
    ++h3[bin[3]];
    ++h0[bin[4]];
    ++h1[bin[5]];
    ++h2[bin[6]];
    ++h3[bin[7]];
  }
  for (; x < width; ++x) {
    const int d = row[x] >> 4;
    if (d >= 1 && d < bins) ++h0[d];
  }
  for (std::size_t d = 0; d < n; d += 8) {
    if (d + 8 <= n) {
      const uint16x8_t sum = vaddq_u16(vaddq_u16(vld1q_u16(h0 + d), vld1q_u16(h1 + d)),
                                       vaddq_u16(vld1q_u16(h2 + d), vld1q_u16(h3 + d)));
      vst1q_u16(counts + d, sum);
    } else {
      for (std::size_t i = d; i < n; ++i) {
        counts[i] = static_cast<std::uint16_t>(h0[i] + h1[i] + h2[i] + h3[i]);
      }
    }
  }
  counts[0] = 0;
}

}  // namespace epipole::vision::kernels

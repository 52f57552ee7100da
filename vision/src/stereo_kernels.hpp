#pragma once

// The stereo stage's kernel interfaces: the scalar *_ref that defines each result and its SIMD
// variants. Internal to vision: its sources and the tests and benchmarks that check every path
// against the reference (target epipole_vision_kernels) include it.
#include <cstddef>
#include <cstdint>

#include "epipole/vision/stereo.hpp"
#include "stereo_census.hpp"

namespace epipole::vision::kernels {

// A row's census of n pixels: 4n bytes in the layout of the kernel set that writes and reads
// it (StereoKernels::census_layout). The census is 9x7 centre-symmetric, bit
// b = I(x+dx_b, y+dy_b) > I(x-dx_b, y-dy_b) for the 31 offsets of the upper half window.
//   planes: four byte planes one after the other: bits 0..7 of pixel x at [x], 8..15 at
//           [n + x], 16..23 at [2n + x], 24..30 at [3n + x] (the reference, AVX2, ARMv7 NEON:
//           a plane's 16 pixels are one load);
//   words:  pixel x's four bytes together, byte p at [4x + p] (AArch64 NEON: a pixel's census
//           is one splat load of a word, and 16 pixels' are four loads that CNT and ADDP
//           count).
enum class CensusLayout : std::uint8_t { planes, words };
// A pixel's census: 31 bits in 4 bytes, in either layout.
inline constexpr int kCensusBytes = 4;
// Where byte p (bits 8p..8p+7) of pixel x's census is, in a row of n pixels.
inline std::ptrdiff_t census_byte(CensusLayout layout, int n, int x, int p) {
  return layout == CensusLayout::planes ? static_cast<std::ptrdiff_t>(p) * n + x
                                        : static_cast<std::ptrdiff_t>(x) * kCensusBytes + p;
}
inline std::uint32_t census_at(CensusLayout layout, const std::uint8_t* census, int n, int x) {
  std::uint32_t bits = 0;
  for (int p = 0; p < kCensusBytes; ++p) {
    bits |= static_cast<std::uint32_t>(census[census_byte(layout, n, x, p)]) << (8 * p);
  }
  return bits;
}
inline void set_census(CensusLayout layout, std::uint8_t* census, int n, int x,
                       std::uint32_t bits) {
  for (int p = 0; p < kCensusBytes; ++p) {
    census[census_byte(layout, n, x, p)] = static_cast<std::uint8_t>(bits >> (8 * p));
  }
}

// The census of a row of n pixels into `reversed`, which holds `padded` >= n pixels: its pixel
// k is pixel n - 1 - k of `census` (k < n); the ones from n on are left as they are.
void reverse_census(CensusLayout layout, const std::uint8_t* census, int n, int padded,
                    std::uint8_t* reversed);

// The census of a row into `census` (width pixels): its first `bits` bits, kCensusBits or
// kSparseCensusBits (stereo_census.hpp), the others 0. rows[0..6] are rows y-3..y+3 (clamped
// at the image border by the caller); columns are clamped too.
using CensusRowKernel = void(const std::uint8_t* const* rows, int width, int bits,
                             std::uint8_t* census);
// Matching cost of one row over the census's first `bits` bits (kCensusBits or
// kSparseCensusBits): cost[x * D + d] = Hamming distance (0..bits) between the left census at x
// and the right census at x - d, and `bits` (the most) where d > x (beyond the left border).
// left holds width pixels; right holds width + D, reversed: its pixel k is right pixel
// width - 1 - k, for k < width (the caller pads k >= width).
using CostRowKernel = void(const std::uint8_t* left, const std::uint8_t* right, int width,
                           int disparities, int bits, std::uint8_t* cost);

// How the winner take all finds the right image's best disparity at xr (WtaRow::right_best),
// for the left-right check:
//   exact:        the smallest S(xr + d, d) over 0 <= d < min(D, width - xr), the smallest d
//                 among equal costs (SGM);
//   left_winners: from the left pixels' winners alone: of the winners best[x] = d that land on
//                 xr = x - d, the one of the smallest S(x, d), the smallest d among equal; -1
//                 where none lands (block matching; StereoBM's rule, validateDisparity).
enum class RightWinners : std::uint8_t { exact, left_winners };

// Winner take all of one row of aggregated costs S(x, d) (each below kNoCost), as the last step
// of the SGM and BM row kernels. disparity[x]: d * 16 with parabolic sub-pixel, or
// kInvalidDisparity when not unique or when d > x; best[x]: that integer d or -1.
// right_best[xr]: the right image's best disparity at xr (RightWinners: SGM's exact, BM's
// left_winners). window: 2 * (width + D) values of scratch. confidence[x] (when not null):
// confidence_of() the winner's cost and the lowest cost outside best +-1, 0 where there is no
// winner. The SIMD kernels need width >= 16 (the matcher's: D < width).
constexpr std::uint16_t kNoCost = 0x7FFF;
struct WtaRow {
  int uniqueness;
  std::int16_t* disparity;
  std::int16_t* best;
  std::int16_t* right_best;
  std::uint16_t* window;
  std::uint8_t* confidence = nullptr;
};

// One row of semi-global aggregation and its winner take all. Path values are 8-bit: each path
// step is C + min(...) - min_prev, between 0 and max cost + P2 = 31 + P2, so P2 <= 224 keeps
// them exact. Path arrays hold, per x in -1..width, `stride` = D + 32 bytes with the
// disparities at offset 16; entries -1 and width are zero, and the values at d = -1 and d = D
// are kSgmPad. mins hold each x's minimum (index x + 1).
constexpr std::uint8_t kSgmPad = 0xFF;
constexpr int kMaxSgmP2 = 255 - kCensusBits;
struct SgmRow {
  const std::uint8_t* cost;  // [x * D + d], each 0..31
  int width;
  int disparities;
  int p1;
  int p2;
  const std::uint8_t* prev[3];  // top, top-left, top-right: the previous row
  std::uint8_t* cur[3];
  const std::uint8_t* prev_min[3];
  std::uint8_t* cur_min[3];
  std::uint8_t* scratch;  // 2 * stride bytes: the horizontal paths
  std::uint16_t* sums;    // width * D values of scratch: the sums over the paths
  WtaRow wta;
};
using SgmRowKernel = void(const SgmRow& row);

// Where pixel x's three downward paths read the previous row (values and minimum) and write
// the current one (values; its minimum goes to cur_min[k][x + 1]): every SGM kernel's layout.
struct SgmDownPaths {
  SgmDownPaths(const SgmRow& r, int x) {
    constexpr int kDx[3] = {0, -1, 1};
    const std::ptrdiff_t stride = r.disparities + 32;
    for (int k = 0; k < 3; ++k) {
      prev[k] = r.prev[k] + (x + kDx[k] + 1) * stride + 16;
      prev_min_at[k] = r.prev_min[k] + x + kDx[k] + 1;
      prev_min[k] = *prev_min_at[k];
      cur[k] = r.cur[k] + (x + 1) * stride + 16;
    }
  }
  const std::uint8_t* prev[3];
  const std::uint8_t* prev_min_at[3];  // where prev_min was read
  int prev_min[3];
  std::uint8_t* cur[3];
};

// The horizontal path's two rows in r.scratch (previous, current), with their pads and the
// previous row zero: where a horizontal pass starts.
inline void sgm_horizontal_rows(const SgmRow& r, std::uint8_t* (&rows)[2]) {
  const int D = r.disparities;
  rows[0] = r.scratch + 16;
  rows[1] = r.scratch + (D + 32) + 16;
  for (std::uint8_t* e : rows) {
    e[-1] = kSgmPad;
    e[D] = kSgmPad;
  }
  for (int d = 0; d < D; ++d) rows[0][d] = 0;
}

// Box filter step (fast mode): sums[i] += add[i] - sub[i] over n values (add or sub may be
// null).
using BoxColumnsKernel = void(std::uint16_t* sums, const std::uint8_t* add, const std::uint8_t* sub,
                              int n);

// One row of block matching in one pass (what box_columns + box_wta_ref do one after the
// other): the column sums are updated with the cost row entering the box and the one leaving
// it (either may be null), and the box and its winner are taken. With both rows, as between the
// image's first and last rows, the caller promises what cost_row gives and the matcher keeps:
// every column sums 2 * radius + 1 rows, and the costs of column c at d > c (beyond the left
// border), entering and leaving, are max_cost (with radius >= 1: blocks of 3 and more). The
// SIMD kernels then leave out what that decides (bm_row_sweep).
struct BmRow {
  const std::uint8_t* entering;
  const std::uint8_t* leaving;
  std::uint16_t* columns;  // width * D
  int width;
  int disparities;
  int radius;
  int max_cost;         // the cost row's most: its census's bits
  std::uint16_t* sums;  // width * D values of scratch (width >= 16, as WtaRow)
  WtaRow wta;
};
using BmRowKernel = void(const BmRow& row);

struct StereoKernels {
  CensusLayout census_layout;  // of what census writes and cost reads
  CensusRowKernel* census;
  CostRowKernel* cost;
  SgmRowKernel* sgm;
  BoxColumnsKernel* box_columns;
  BmRowKernel* bm;
};

StereoKernels stereo_kernels(SimdPath path);

// The reference's census and cost: the planes layout.
void census_row_ref(const std::uint8_t* const* rows, int width, int bits, std::uint8_t* census);
void cost_row_ref(const std::uint8_t* left, const std::uint8_t* right, int width, int disparities,
                  int bits, std::uint8_t* cost);
void sgm_row_ref(const SgmRow& row);
void box_columns_ref(std::uint16_t* sums, const std::uint8_t* add, const std::uint8_t* sub, int n);
void bm_row_ref(const BmRow& row);
// The horizontal box of radius r over a row of per-x columns of D values into sums
// [x * D + d], and its winner take all (block matching's: right winners from the left's).
void box_wta_ref(const std::uint16_t* columns, int width, int disparities, int radius,
                 std::uint16_t* sums, const WtaRow& wta);
// The definition of the winner take all over a whole row of sums [x * D + d].
void wta_row_ref(const std::uint16_t* sums, int width, int disparities, const WtaRow& wta,
                 RightWinners right);

// The first `bits` census bits of pixel x (clamped columns), shared by every path for the
// border columns.
std::uint32_t census_bits(const std::uint8_t* const* rows, int width, int x, int bits);

}  // namespace epipole::vision::kernels

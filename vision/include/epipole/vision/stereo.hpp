#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/core/thread_pool.hpp"

namespace epipole::vision {

// The value of a pixel without a disparity in StereoMatcher's output (disparity x16), as
// OpenCV's matchers write it for minDisparity 0: -16, i.e. -1 pixel.
constexpr std::int16_t kInvalidDisparity = -16;
constexpr int kDisparityScale = 16;  // output = disparity * 16 (4 fractional bits)

enum class StereoMethod {
  sgm,  // quality: census cost, semi-global aggregation over 5 paths
  bm,   // fast: census cost, box aggregation
};

struct StereoConfig {
  int width = 0;
  int height = 0;
  int max_disparity = 64;  // disparities 0..max_disparity-1; 16..256, a multiple of 16
  StereoMethod method = StereoMethod::sgm;
  int p1 = 11;             // SGM: penalty for a disparity change of 1 (census cost units)
  int p2 = 120;            // SGM: penalty for larger changes (>= p1)
  int block_size = 7;      // BM: box of block_size x block_size census costs (odd, 3..21)
  int uniqueness = 10;     // percent: another disparity (not +-1) must cost this much more
  int lr_max_diff = 1;     // left-right check tolerance in pixels; < 0 switches it off
  int speckle_size = 100;  // connected regions smaller than this are invalidated; 0: off
  int speckle_range = 1;   // in pixels: neighbours closer than this belong to one region
  int threads = 1;         // row stripes on a fixed pool created by the constructor
};

// Dense disparity of a rectified pair (left image is the reference; a left pixel x matches the
// right pixel x - d). Cost: 9x7 centre-symmetric census (31 bits) with Hamming distance.
// Quality mode: semi-global aggregation along 5 paths (left, right, top, top-left, top-right),
// all in one top-down pass, so no cost volume is stored. Fast mode: box aggregation. Both: winner
// take all, parabolic sub-pixel, uniqueness ratio, left-right check, speckle removal.
//
// Fixed memory: everything is allocated by the constructor; compute() never allocates. See
// working_set_bytes() and docs/vision.md for the formula.
class StereoMatcher {
 public:
  explicit StereoMatcher(const StereoConfig& config, SimdPath path = best_simd_path());
  ~StereoMatcher();
  StereoMatcher(const StereoMatcher&) = delete;
  StereoMatcher& operator=(const StereoMatcher&) = delete;

  // Disparity x16 of the left image (kInvalidDisparity where unknown). The view stays valid
  // until the next call. Throws Error if either image differs from the configured size.
  ImageView<const std::int16_t> compute(GrayView left, GrayView right);

  std::size_t working_set_bytes() const;
  const StereoConfig& config() const { return config_; }
  SimdPath simd_path() const { return path_; }

  struct Worker;  // per-thread row buffers (stereo.cpp)

 private:
  void run_stripe(int stripe, int worker, GrayView left, GrayView right);
  void remove_speckles();

  StereoConfig config_;
  SimdPath path_;
  ThreadPool pool_;
  std::vector<std::unique_ptr<Worker>> workers_;
  std::vector<std::int16_t> padded_;   // the output with a border of one invalid pixel
  ImageView<std::int16_t> disparity_;  // the output: padded_ without its border
  std::vector<std::uint8_t> visited_;  // speckle filter
  std::vector<std::uint32_t> region_;  // speckle filter: pixels of the region being grown
};

namespace kernels {

// Census of one row: 9x7 centre-symmetric census, bit b = I(x+dx_b, y+dy_b) > I(x-dx_b, y-dy_b)
// for the 31 offsets of the upper half window. rows[0..6] are rows y-3..y+3 (clamped at the
// image border by the caller); columns are clamped too. Bits 0..15 go to lo, 16..30 to hi.
using CensusRowKernel = void(const std::uint8_t* const* rows, int width, std::uint16_t* lo,
                             std::uint16_t* hi);
// Matching cost of one row: cost[x * D + d] = Hamming distance between the left census at x and
// the right census at x - d. The right census comes reversed: right_lo[k] is the census of right
// pixel width - 1 - k, for k < width + D (the caller pads k >= width).
using CostRowKernel = void(const std::uint16_t* left_lo, const std::uint16_t* left_hi,
                           const std::uint16_t* right_lo, const std::uint16_t* right_hi, int width,
                           int disparities, std::uint16_t* cost);

// One row of semi-global aggregation. Path arrays hold, per x in -1..width, `stride` values
// (= D + 16) with the disparities at offset 8; entries -1 and width are zero, and the values at
// d = -1 and d = D are kSgmPad. mins hold each x's minimum (index x + 1).
constexpr std::uint16_t kSgmPad = 0x3FFF;
struct SgmRow {
  const std::uint16_t* cost;  // [x * D + d]
  int width;
  int disparities;
  int p1;
  int p2;
  const std::uint16_t* prev[3];  // top, top-left, top-right: the previous row
  std::uint16_t* cur[3];
  const std::uint16_t* prev_min[3];
  std::uint16_t* cur_min[3];
  std::uint16_t* scratch;  // 2 * stride values: the horizontal paths
  std::uint16_t* sums;     // out: [x * D + d], the sum over the 5 paths
};
using SgmRowKernel = void(const SgmRow& row);

// Winner take all on one row of aggregated costs (sums, each below kNoCost; the kernel may
// overwrite them). disparity[x]: d * 16 with parabolic sub-pixel, or kInvalidDisparity when not
// unique or when d > x; best[x]: the integer d or -1. right_min/right_disp (width + D values,
// reversed like the right census, set to kNoCost and 0xFFFF by the caller) get the best cost and
// disparity (the smallest d among equal costs) of each right pixel.
constexpr std::uint16_t kNoCost = 0x7FFF;
using WtaRowKernel = void(std::uint16_t* sums, int width, int disparities, int uniqueness,
                          std::int16_t* disparity, std::int16_t* best, std::uint16_t* right_min,
                          std::uint16_t* right_disp);

// Box filter steps (fast mode): sums[i] += add[i] - sub[i] over n values (sub may be null), and
// the horizontal box of radius r over a row of per-x columns of D values.
using BoxColumnsKernel = void(std::uint16_t* sums, const std::uint16_t* add,
                              const std::uint16_t* sub, int n);
using BoxRowKernel = void(const std::uint16_t* columns, int width, int disparities, int radius,
                          std::uint16_t* sums);

struct StereoKernels {
  CensusRowKernel* census;
  CostRowKernel* cost;
  SgmRowKernel* sgm;
  WtaRowKernel* wta;
  BoxColumnsKernel* box_columns;
  BoxRowKernel* box_row;
};

StereoKernels stereo_kernels(SimdPath path);

void census_row_ref(const std::uint8_t* const* rows, int width, std::uint16_t* lo,
                    std::uint16_t* hi);
void cost_row_ref(const std::uint16_t* left_lo, const std::uint16_t* left_hi,
                  const std::uint16_t* right_lo, const std::uint16_t* right_hi, int width,
                  int disparities, std::uint16_t* cost);
void sgm_row_ref(const SgmRow& row);
void wta_row_ref(std::uint16_t* sums, int width, int disparities, int uniqueness,
                 std::int16_t* disparity, std::int16_t* best, std::uint16_t* right_min,
                 std::uint16_t* right_disp);
void box_columns_ref(std::uint16_t* sums, const std::uint16_t* add, const std::uint16_t* sub,
                     int n);
void box_row_ref(const std::uint16_t* columns, int width, int disparities, int radius,
                 std::uint16_t* sums);

// One pixel of the census (clamped columns), shared by every path for the border columns.
void census_pixel(const std::uint8_t* const* rows, int width, int x, std::uint16_t* lo,
                  std::uint16_t* hi);
// Uniqueness, shared by every path: a disparity (other than best +-1) whose cost is below
// uniqueness_limit(min_cost, uniqueness_ratio(u)) ~ min_cost * 100 / (100 - u) makes the pixel
// ambiguous. ratio = 2^16 * 100 / (100 - u), fixed point, so no division per pixel.
std::uint32_t uniqueness_ratio(int uniqueness);
int uniqueness_limit(int min_cost, std::uint32_t ratio);
// Parabolic sub-pixel position, shared by every path: d*16 + offset from the three costs.
int subpixel(int d, int disparities, int below, int at, int above);

}  // namespace kernels
}  // namespace epipole::vision

#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/vision/corner.hpp"
#include "epipole/vision/strongest_corners.hpp"

namespace epipole::vision {

struct FastConfig {
  int width = 0;
  int height = 0;
  int threshold = 20;        // clamped to [0, 255] as cv::FAST does
  bool nonmax = true;        // 3x3 non-maximum suppression on the score
  int max_corners = 10'000;  // the strongest are kept when there are more
  // Bucketing: with a grid of more than one cell, each cell keeps at most
  // max_corners / (grid_columns * grid_rows) corners, the strongest.
  int grid_columns = 1;
  int grid_rows = 1;
};

// FAST-9 on the 16-pixel Bresenham circle of radius 3, with the same corners, scores and
// suppression as cv::FAST(image, keypoints, threshold, nonmax, TYPE_9_16). Corners come out in
// raster order. Pixels within 3 of the border are never corners.
//
// Fixed memory: everything is allocated by the constructor; detect() never allocates.
// Working set: 3 * width bytes of scores + 3 * width * 4 bytes of corner columns
//              + max_corners * sizeof(Corner) (12) + 4 * cells bytes of output.
class FastDetector {
 public:
  explicit FastDetector(const FastConfig& config, SimdPath path = best_simd_path());

  // Detects the corners of an image of the configured size. The span stays valid until the
  // next call. Throws Error if the image size differs from the configuration.
  std::span<const Corner> detect(GrayView image);

  // True when the last image had more corners than were kept (the weakest were dropped).
  bool truncated() const { return strongest_.truncated(); }
  std::size_t working_set_bytes() const;
  const FastConfig& config() const { return config_; }
  SimdPath simd_path() const { return path_; }

 private:
  FastConfig config_;
  SimdPath path_;
  std::unique_ptr<std::uint8_t[]> score_rows_;  // 3 rows of per-pixel scores (0: no corner)
  std::unique_ptr<int[]> corner_columns_;       // 3 rows of corner x positions
  StrongestCorners strongest_;
};

namespace kernels {

// One image row of FAST-9. `row` points at pixel (0, y) of an image with rows y-3..y+3
// readable. Writes scores[x] for every x in [0, width): the corner score, or 0 where x is no
// corner or within 3 of the border. Appends the x of each corner to `columns` in increasing
// order and returns how many.
int fast_row_ref(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                 std::uint8_t* scores, int* columns);
int fast_row_neon(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns);
// x86 builds only.
int fast_row_avx2(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                  std::uint8_t* scores, int* columns);

using FastRowKernel = int(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                          std::uint8_t* scores, int* columns);

// The row kernel a FastDetector on this path runs.
FastRowKernel* fast_row_kernel(SimdPath path);

// The FAST score of the pixel at `p` (cv::FAST's definition): the largest threshold for which
// it is still a corner. `circle` holds the 16 circle offsets repeated to 25 entries.
int fast_score(const std::uint8_t* p, const std::ptrdiff_t* circle, int threshold);

// The 25 offsets (16 circle pixels, the first 9 repeated) for a row stride.
void fast_circle_offsets(std::ptrdiff_t stride, std::ptrdiff_t offsets[25]);

}  // namespace kernels
}  // namespace epipole::vision

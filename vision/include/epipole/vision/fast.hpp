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

}  // namespace epipole::vision

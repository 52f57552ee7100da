#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/vision/corner.hpp"

namespace epipole::vision {

struct HarrisConfig {
  int width = 0;
  int height = 0;
  int block_size = 3;           // odd, 1..kHarrisMaxBlockSize: the window of the structure tensor
  double k = 0.04;              // Harris free parameter: 0 or in [1e-6, 1]
  double quality_level = 0.01;  // corners keep R > quality_level * max(R); finite, > 0
  double min_distance = 10;     // Euclidean pixels between kept corners; finite, >= 0
  int max_corners = 1000;       // the strongest are kept when there are more
};

inline constexpr int kHarrisMaxBlockSize = 31;  // box sums of 31 x 31 squared gradients fit int32

// The Harris response as cv::cornerHarris(image, R, block_size, 3, k) defines it on 8-bit
// images, and corners as cv::goodFeaturesToTrack(image, corners, max_corners, quality_level,
// min_distance, noArray(), block_size, 3, true, k) picks them.
//
// Response: Sobel 3x3 gradients Ix, Iy of the image (border BORDER_REFLECT_101), scaled by
// s = 1 / (4 * block_size * 255); the sums a = sum(Ix^2), b = sum(Ix Iy), c = sum(Iy^2) over the
// block_size x block_size window (un-normalised, border BORDER_REFLECT_101 on the products);
// R = (a c - b^2) - k (a + c)^2. The gradients, products and sums are exact integers (int16,
// int32); only the last step, per pixel, is float.
//
// Corners: pixels (1 <= x < width-1, 1 <= y < height-1) with R > quality_level * max(R) that
// are the maximum of their 3x3 neighbourhood (ties all survive, as with cv::dilate), taken by
// decreasing R (ties: later in raster order first, as OpenCV's sort) and kept when no kept
// corner is closer than min_distance, until max_corners. Corners come out strongest first;
// their score is R.
//
// Fixed memory: everything is allocated by the constructor; detect() never allocates.
// Working set, in bytes, with W = width, H = height, B = block_size,
// S = W rounded up to a multiple of 16, c = round(min_distance) (no grid when min_distance < 1):
//     4 * S * H                          response image (float)
//   + 12 * (B * W + W + B - 1)           kernel workspace (int32 products of B rows, sums)
//   + 4 * (W - 2) * (H - 2)              corner candidates (offsets into the response)
//   + 4 * ceil(W / c) * ceil(H / c)      min_distance grid (one list head per cell)
//   + 4 * max_corners                    grid links (only with the grid)
//   + 12 * max_corners                   output corners
class HarrisDetector {
 public:
  explicit HarrisDetector(const HarrisConfig& config, SimdPath path = best_simd_path());

  // Computes the response and detects the corners of an image of the configured size. The
  // span stays valid until the next call. Throws Error if the image size differs from the
  // configuration.
  std::span<const Corner> detect(GrayView image);

  // Only the response map (what detect() starts with). The view stays valid until the next
  // call of detect() or compute_response().
  ImageView<const float> compute_response(GrayView image);

  // The response map of the last image.
  ImageView<const float> response() const { return response_.view(); }
  // The largest response of the last image and the corner threshold derived from it.
  float max_response() const { return max_response_; }
  float threshold() const { return threshold_; }
  // True when the last image stopped at max_corners with candidates left unexamined.
  bool truncated() const { return truncated_; }

  std::size_t working_set_bytes() const;
  const HarrisConfig& config() const { return config_; }
  SimdPath simd_path() const { return path_; }

 private:
  HarrisConfig config_;
  SimdPath path_;
  int cell_size_ = 0;  // min_distance grid cell, 0: no grid
  int grid_width_ = 0;
  int grid_height_ = 0;
  Image<float> response_;
  std::unique_ptr<std::int32_t[]> workspace_;
  std::unique_ptr<std::uint32_t[]> candidates_;  // offsets into the response
  std::unique_ptr<int[]> grid_heads_;
  std::unique_ptr<int[]> grid_links_;
  std::unique_ptr<Corner[]> corners_;
  int count_ = 0;
  float max_response_ = 0.0f;
  float threshold_ = 0.0f;
  bool truncated_ = false;
};

}  // namespace epipole::vision

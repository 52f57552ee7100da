#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "epipole/vision/corner.hpp"

namespace epipole::vision {

// Keeps the strongest corners offered, in fixed memory: overall, or per cell of a
// grid_columns x grid_rows grid over the image (bucketing, so that corners spread over the
// view instead of piling up on one textured patch). Each cell keeps at most
// max_corners / (grid_columns * grid_rows); "strongest" is the higher score, ties going to the
// corner earlier in raster order. Corners come out in raster order. Corners offered must lie in
// the image, which is at most 65535 pixels wide and high.
//
// Working set: max_corners * (sizeof(Corner) + 8) + (cells + width + height) * sizeof(int) bytes.
class StrongestCorners {
 public:
  StrongestCorners(int width, int height, int max_corners, int grid_columns = 1, int grid_rows = 1);

  // A frame is clear(), offer() for each candidate, finish().
  void clear();
  void offer(const Corner& corner);
  // Ends the frame: returns the kept corners in raster order (valid until the next offer())
  // and empties the cells.
  std::span<const Corner> finish();

  // True when some corner of the frame was dropped (readable until the next clear()).
  bool truncated() const { return truncated_; }
  int cell_capacity() const { return cell_capacity_; }
  std::size_t working_set_bytes() const;

 private:
  int width_;
  int height_;
  int grid_columns_;
  int grid_rows_;
  int cell_capacity_;
  // A kept corner is one 64-bit key whose order is "stronger": the score's bits made to order as
  // unsigned integers above the complement of its raster position (y * 65536 + x). So a heap
  // step is one integer comparison.
  std::unique_ptr<std::uint64_t[]> keys_;  // cell i owns [i * cell_capacity_, (i + 1) * ...)
  std::unique_ptr<int[]> counts_;
  std::unique_ptr<Corner[]> corners_;      // what finish() returns
  std::unique_ptr<int[]> cell_of_column_;  // x -> the grid column of x
  std::unique_ptr<int[]> cell_of_row_;     // y -> the first cell of y's grid row
  bool truncated_ = false;
};

}  // namespace epipole::vision

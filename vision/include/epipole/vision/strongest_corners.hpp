#pragma once

#include <bit>
#include <cassert>
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
// the image, which is at most 65535 pixels wide and high (checked only by assert: offer() is on
// the detectors' hot path). NaN scores are ordered too: a positive NaN above +inf, a negative
// one below -inf.
//
// Working set: about max_corners * (sizeof(Corner) + 16) + cells * 12 + (width + height) * 4
// bytes.
class StrongestCorners {
 public:
  StrongestCorners(int width, int height, int max_corners, int grid_columns = 1, int grid_rows = 1);

  // A frame is clear(), offer() for each candidate, finish().
  void clear();
  // Inline: a detector offers every corner that survives its non-maximum suppression.
  void offer(const Corner& corner) {
    assert(corner.x >= 0 && corner.x < width_ && corner.y >= 0 && corner.y < height_);
    const int cell = cell_of_row_[corner.y] + cell_of_column_[corner.x];
    const std::uint64_t key = key_of(corner);
    if (key > floors_[cell]) keep(cell, key);  // else weaker than all a full cell kept
  }
  // Ends the frame: returns the kept corners in raster order (valid until the next offer())
  // and empties the cells.
  std::span<const Corner> finish();

  // After finish(): true when some corner of the frame was dropped (readable until the next
  // clear()). Before it, true only once a cell has collected kCollected times its capacity.
  bool truncated() const { return truncated_; }
  int cell_capacity() const { return cell_capacity_; }
  std::size_t working_set_bytes() const;

 private:
  // The score's bits as an unsigned integer of the same order (-0 taken as +0): negative floats
  // order in reverse as integers, so theirs are complemented; the others get the sign bit.
  static std::uint32_t ordered_bits(float score) {
    if (score == 0.0f) score = 0.0f;
    const auto bits = std::bit_cast<std::uint32_t>(score);
    return (bits & 0x8000'0000u) != 0 ? ~bits : bits | 0x8000'0000u;
  }
  // Higher score, then earlier in raster order, is a larger key.
  static std::uint64_t key_of(const Corner& corner) {
    const auto position =
        static_cast<std::uint32_t>(corner.y) << 16 | static_cast<std::uint32_t>(corner.x);
    return static_cast<std::uint64_t>(ordered_bits(corner.score)) << 32 | ~position;
  }
  // A cell collects keys up to this many times its capacity before it keeps its strongest.
  static constexpr int kCollected = 2;
  std::uint64_t* cell_keys(int cell);
  // Adds a key above the cell's floor; a cell at kCollected times its capacity keeps its
  // strongest.
  void keep(int cell, std::uint64_t key);

  int width_;
  int height_;
  int grid_columns_;
  int grid_rows_;
  int cell_capacity_;
  // A corner is kept as one 64-bit key whose order is "stronger": the score's bits made to order
  // as unsigned integers above the complement of its raster position (y * 65536 + x). A cell
  // collects up to kCollected times its capacity, then keeps its strongest (std::nth_element) and
  // from then on takes only keys above the weakest it kept (its floor).
  std::unique_ptr<std::uint64_t[]>
      keys_;  // cell i owns kCollected * cell_capacity_ from cell_keys(i)
  std::unique_ptr<std::uint64_t[]> floors_;
  std::unique_ptr<int[]> counts_;
  std::unique_ptr<Corner[]> corners_;      // what finish() returns
  std::unique_ptr<int[]> cell_of_column_;  // x -> the grid column of x
  std::unique_ptr<int[]> cell_of_row_;     // y -> the first cell of y's grid row
  bool truncated_ = false;
};

}  // namespace epipole::vision

#include "epipole/vision/strongest_corners.hpp"

#include <algorithm>
#include <bit>
#include <functional>

#include "epipole/core/error.hpp"

namespace epipole::vision {

namespace {

// The score's bits as an unsigned integer of the same order (-0 taken as +0): negative floats
// order in reverse as integers, so theirs are complemented; the others get the sign bit.
std::uint32_t ordered_bits(float score) {
  if (score == 0.0f) score = 0.0f;
  const auto bits = std::bit_cast<std::uint32_t>(score);
  return (bits & 0x8000'0000u) != 0 ? ~bits : bits | 0x8000'0000u;
}

float score_of(std::uint32_t ordered) {
  return std::bit_cast<float>((ordered & 0x8000'0000u) != 0 ? ordered & 0x7fff'ffffu : ~ordered);
}

// Higher score, then earlier in raster order, is a larger key.
std::uint64_t key_of(const Corner& corner) {
  const auto position =
      static_cast<std::uint32_t>(corner.y) << 16 | static_cast<std::uint32_t>(corner.x);
  return static_cast<std::uint64_t>(ordered_bits(corner.score)) << 32 | ~position;
}

Corner corner_of(std::uint64_t key) {
  const auto position = ~static_cast<std::uint32_t>(key);
  return {static_cast<int>(position & 0xffffu), static_cast<int>(position >> 16),
          score_of(static_cast<std::uint32_t>(key >> 32))};
}

// A cell's keys once full: a heap whose front is the smallest key (the weakest corner).
// Replaces the front by the larger `key` and restores the heap in one pass down.
void replace_weakest(std::uint64_t* heap, int count, std::uint64_t key) {
  int hole = 0;
  for (;;) {
    int child = 2 * hole + 1;
    if (child >= count) break;
    if (child + 1 < count && heap[child + 1] < heap[child]) ++child;
    if (key <= heap[child]) break;
    heap[hole] = heap[child];
    hole = child;
  }
  heap[hole] = key;
}

}  // namespace

StrongestCorners::StrongestCorners(int width, int height, int max_corners, int grid_columns,
                                   int grid_rows)
    : width_(width), height_(height), grid_columns_(grid_columns), grid_rows_(grid_rows) {
  require(width > 0 && height > 0, "corner grid over an empty ", width, "x", height, " image");
  require(grid_columns >= 1 && grid_rows >= 1 && grid_columns <= width && grid_rows <= height,
          "corner grid ", grid_columns, "x", grid_rows, " does not fit a ", width, "x", height,
          " image");
  const int cells = grid_columns * grid_rows;
  require(max_corners >= cells, "max_corners ", max_corners, " is less than one per cell of the ",
          grid_columns, "x", grid_rows, " grid");
  require(width <= 0xffff && height <= 0xffff, "corner grid over a ", width, "x", height,
          " image: at most 65535 pixels wide and high");
  cell_capacity_ = max_corners / cells;
  const auto kept = static_cast<std::size_t>(cell_capacity_) * cells;
  keys_ = std::make_unique<std::uint64_t[]>(kept);
  counts_ = std::make_unique<int[]>(static_cast<std::size_t>(cells));
  corners_ = std::make_unique<Corner[]>(kept);
  cell_of_column_ = std::make_unique<int[]>(static_cast<std::size_t>(width));
  for (int x = 0; x < width; ++x)
    cell_of_column_[x] = static_cast<int>(static_cast<long>(x) * grid_columns / width);
  cell_of_row_ = std::make_unique<int[]>(static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y)
    cell_of_row_[y] = static_cast<int>(static_cast<long>(y) * grid_rows / height) * grid_columns;
  clear();
}

void StrongestCorners::clear() {
  std::fill_n(counts_.get(), grid_columns_ * grid_rows_, 0);
  truncated_ = false;
}

std::size_t StrongestCorners::working_set_bytes() const {
  const auto cells = static_cast<std::size_t>(grid_columns_) * grid_rows_;
  return static_cast<std::size_t>(cell_capacity_) * cells *
             (sizeof(Corner) + sizeof(std::uint64_t)) +
         cells * sizeof(int);
}

void StrongestCorners::offer(const Corner& corner) {
  const int cell = cell_of_row_[corner.y] + cell_of_column_[corner.x];
  std::uint64_t* begin = keys_.get() + static_cast<std::ptrdiff_t>(cell) * cell_capacity_;
  const std::uint64_t key = key_of(corner);
  int& count = counts_[cell];
  if (count < cell_capacity_) {
    begin[count++] = key;
    if (count == cell_capacity_) std::make_heap(begin, begin + count, std::greater<>{});
    return;
  }
  truncated_ = true;
  if (key > begin[0]) replace_weakest(begin, count, key);
}

std::span<const Corner> StrongestCorners::finish() {
  const int cells = grid_columns_ * grid_rows_;
  // Each kept key, its halves swapped: the raster position, complemented, above the score's
  // bits. Sorted in decreasing order, they are in raster order.
  std::uint64_t* out = keys_.get();
  for (int cell = 0; cell < cells; ++cell) {
    const std::uint64_t* begin = keys_.get() + static_cast<std::ptrdiff_t>(cell) * cell_capacity_;
    // Cells move towards the front in order, so a cell is never overwritten before it moves.
    out = std::transform(begin, begin + counts_[cell], out,
                         [](std::uint64_t key) { return key << 32 | key >> 32; });
    counts_[cell] = 0;
  }
  // One cell that never filled is still in the order the corners came: raster order.
  if (cells > 1 || truncated_) std::sort(keys_.get(), out, std::greater<>{});
  const Corner* end = std::transform(keys_.get(), out, corners_.get(), [](std::uint64_t swapped) {
    return corner_of(swapped << 32 | swapped >> 32);
  });
  return {corners_.get(), static_cast<std::size_t>(end - corners_.get())};
}

}  // namespace epipole::vision

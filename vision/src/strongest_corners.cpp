#include "epipole/vision/strongest_corners.hpp"

#include <algorithm>
#include <bit>
#include <functional>

#include "epipole/core/error.hpp"

namespace epipole::vision {

namespace {

float score_of(std::uint32_t ordered) {
  return std::bit_cast<float>((ordered & 0x8000'0000u) != 0 ? ordered & 0x7fff'ffffu : ~ordered);
}

Corner corner_of(std::uint64_t key) {
  const auto position = ~static_cast<std::uint32_t>(key);
  return {static_cast<int>(position & 0xffffu), static_cast<int>(position >> 16),
          score_of(static_cast<std::uint32_t>(key >> 32))};
}

// Keeps the `capacity` largest of a cell's `count` keys at its front, in any order; returns the
// smallest of them.
std::uint64_t keep_largest(std::uint64_t* keys, int count, int capacity) {
  std::nth_element(keys, keys + capacity - 1, keys + count, std::greater<>{});
  return keys[capacity - 1];
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
  keys_ = std::make_unique<std::uint64_t[]>(kCollected * kept);
  counts_ = std::make_unique<int[]>(static_cast<std::size_t>(cells));
  floors_ = std::make_unique<std::uint64_t[]>(static_cast<std::size_t>(cells));
  corners_ = std::make_unique<Corner[]>(kept);
  cell_of_column_ = std::make_unique<int[]>(static_cast<std::size_t>(width));
  for (int x = 0; x < width; ++x)
    cell_of_column_[x] = static_cast<int>(static_cast<std::int64_t>(x) * grid_columns / width);
  cell_of_row_ = std::make_unique<int[]>(static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y)
    cell_of_row_[y] =
        static_cast<int>(static_cast<std::int64_t>(y) * grid_rows / height) * grid_columns;
  clear();
}

void StrongestCorners::clear() {
  std::fill_n(counts_.get(), grid_columns_ * grid_rows_, 0);
  std::fill_n(floors_.get(), grid_columns_ * grid_rows_, 0);  // every key is above 0
  truncated_ = false;
}

std::size_t StrongestCorners::working_set_bytes() const {
  const auto cells = static_cast<std::size_t>(grid_columns_) * grid_rows_;
  const auto kept = static_cast<std::size_t>(cell_capacity_) * cells;
  return kept * (kCollected * sizeof(std::uint64_t) + sizeof(Corner)) +
         cells * (sizeof(int) + sizeof(std::uint64_t)) +
         (static_cast<std::size_t>(width_) + height_) * sizeof(int);
}

std::uint64_t* StrongestCorners::cell_keys(int cell) {
  return keys_.get() + kCollected * static_cast<std::ptrdiff_t>(cell) * cell_capacity_;
}

void StrongestCorners::keep(int cell, std::uint64_t key) {
  std::uint64_t* keys = cell_keys(cell);
  int& count = counts_[cell];
  keys[count++] = key;
  if (count == kCollected * cell_capacity_) {
    floors_[cell] = keep_largest(keys, count, cell_capacity_);
    count = cell_capacity_;
    truncated_ = true;
  }
}

std::span<const Corner> StrongestCorners::finish() {
  const int cells = grid_columns_ * grid_rows_;
  // Each kept key, its halves swapped: the raster position, complemented, above the score's
  // bits. Sorted in decreasing order, they are in raster order.
  std::uint64_t* out = keys_.get();
  for (int cell = 0; cell < cells; ++cell) {
    std::uint64_t* keys = cell_keys(cell);
    int count = counts_[cell];
    if (count > cell_capacity_) {
      keep_largest(keys, count, cell_capacity_);
      count = cell_capacity_;
      truncated_ = true;
    }
    // Cells move towards the front in order, so a cell is never overwritten before it moves.
    out = std::transform(keys, keys + count, out,
                         [](std::uint64_t key) { return std::rotl(key, 32); });
    counts_[cell] = 0;
    floors_[cell] = 0;
  }
  // One cell that never filled is still in the order the corners came: raster order.
  if (cells > 1 || truncated_) std::sort(keys_.get(), out, std::greater<>{});
  const Corner* end = std::transform(keys_.get(), out, corners_.get(), [](std::uint64_t swapped) {
    return corner_of(std::rotl(swapped, 32));
  });
  return {corners_.get(), static_cast<std::size_t>(end - corners_.get())};
}

}  // namespace epipole::vision

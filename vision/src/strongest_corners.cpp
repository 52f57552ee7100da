#include "epipole/vision/strongest_corners.hpp"

#include <algorithm>

#include "epipole/core/error.hpp"

namespace epipole::vision {

namespace {

// Strict weak order "a is a stronger corner than b": higher score, then earlier in raster order.
bool stronger(const Corner& a, const Corner& b) {
  if (a.score != b.score) return a.score > b.score;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

bool raster_order(const Corner& a, const Corner& b) {
  return a.y != b.y ? a.y < b.y : a.x < b.x;
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
  cell_capacity_ = max_corners / cells;
  corners_ = std::make_unique<Corner[]>(static_cast<std::size_t>(cell_capacity_) * cells);
  counts_ = std::make_unique<int[]>(static_cast<std::size_t>(cells));
  clear();
}

void StrongestCorners::clear() {
  std::fill_n(counts_.get(), grid_columns_ * grid_rows_, 0);
  truncated_ = false;
}

std::size_t StrongestCorners::working_set_bytes() const {
  const auto cells = static_cast<std::size_t>(grid_columns_) * grid_rows_;
  return static_cast<std::size_t>(cell_capacity_) * cells * sizeof(Corner) + cells * sizeof(int);
}

void StrongestCorners::offer(const Corner& corner) {
  const int column = static_cast<int>(static_cast<long>(corner.x) * grid_columns_ / width_);
  const int row = static_cast<int>(static_cast<long>(corner.y) * grid_rows_ / height_);
  const int cell =
      std::clamp(row, 0, grid_rows_ - 1) * grid_columns_ + std::clamp(column, 0, grid_columns_ - 1);
  Corner* begin = corners_.get() + static_cast<std::ptrdiff_t>(cell) * cell_capacity_;
  int& count = counts_[cell];
  if (count < cell_capacity_) {
    begin[count++] = corner;
    if (count == cell_capacity_) std::make_heap(begin, begin + count, stronger);
    return;
  }
  // A full cell is a heap whose front is its weakest corner.
  truncated_ = true;
  if (!stronger(corner, begin[0])) return;
  std::pop_heap(begin, begin + count, stronger);
  begin[count - 1] = corner;
  std::push_heap(begin, begin + count, stronger);
}

std::span<const Corner> StrongestCorners::finish() {
  const int cells = grid_columns_ * grid_rows_;
  Corner* out = corners_.get();
  std::size_t total = 0;
  for (int cell = 0; cell < cells; ++cell) {
    const Corner* begin = corners_.get() + static_cast<std::ptrdiff_t>(cell) * cell_capacity_;
    // Cells move towards the front in order, so a cell is never overwritten before it moves.
    out = std::copy(begin, begin + counts_[cell], out);
    total += static_cast<std::size_t>(counts_[cell]);
    counts_[cell] = 0;
  }
  // One cell that never filled is still in the order the corners came: raster order.
  if (cells > 1 || truncated_) std::sort(corners_.get(), corners_.get() + total, raster_order);
  return {corners_.get(), total};
}

}  // namespace epipole::vision

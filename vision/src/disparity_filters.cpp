#include "epipole/vision/disparity_filters.hpp"

#include <algorithm>

#include "epipole/core/error.hpp"
#include "kernel_set.hpp"

namespace epipole::vision {

namespace kernels {

void fill_holes_row_ref(std::int16_t* row, int width, int max_hole) {
  for (int x = 0; x < width;) {
    if (row[x] >= 0) {
      ++x;
      continue;
    }
    const int begin = x;
    while (x < width && row[x] < 0) ++x;
    if (begin > 0 && x < width && x - begin <= max_hole) {
      std::fill(row + begin, row + x, std::min(row[begin - 1], row[x]));
    }
  }
}

}  // namespace kernels

void fill_holes(ImageView<std::int16_t> disparity, int max_hole, SimdPath path) {
  require(max_hole >= 0, "hole filling: the longest hole must be 0 or more, not ", max_hole);
  if (max_hole == 0) return;
  static constexpr KernelSet<kernels::FillHolesRow> kFill{kernels::fill_holes_row_ref,
                                                          kernels::fill_holes_row_neon, nullptr};
  kernels::FillHolesRow* const fill = kFill.pick(path);
  for (int y = 0; y < disparity.height(); ++y) fill(disparity.row(y), disparity.width(), max_hole);
}

}  // namespace epipole::vision

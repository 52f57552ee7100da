#include "epipole/vision/disparity_filters.hpp"

#include <algorithm>
#include <cstdlib>

#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"
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

void temporal_row_ref(std::int16_t* now, std::int16_t* last, int width, int weight,
                      int max_step_x16) {
  for (int x = 0; x < width; ++x) {
    const int n = now[x], l = last[x];
    int out = n;
    if (n >= 0 && l >= 0 && std::abs(n - l) <= max_step_x16) {
      out = l + (((n - l) * weight + 128) >> 8);
    }
    now[x] = last[x] = static_cast<std::int16_t>(out);
  }
}

}  // namespace kernels

TemporalFilter::TemporalFilter(int width, int height, int new_percent, int max_step)
    : last_(width, height),
      weight_((new_percent * 256 + 50) / 100),
      max_step_(max_step * kDisparityScale) {
  require(width > 0 && height > 0, "temporal filter: empty size ", width, "x", height);
  require(new_percent >= 1 && new_percent <= 99, "temporal filter: the new pair's weight is ",
          new_percent, " %, expected 1..99");
  require(max_step >= 1 && max_step <= 7, "temporal filter: the largest step is ", max_step,
          " px, expected 1..7");
  reset();
}

void TemporalFilter::reset() {
  for (int y = 0; y < last_.height(); ++y) {
    std::fill_n(last_.view().row(y), last_.width(), kInvalidDisparity);
  }
}

void TemporalFilter::apply(ImageView<std::int16_t> disparity, SimdPath path) {
  require(same_size(disparity, last_.view()), "temporal filter for ", last_.width(), "x",
          last_.height(), " was given a ", disparity.width(), "x", disparity.height(),
          " disparity");
  static constexpr KernelSet<kernels::TemporalRow> kTemporal{kernels::temporal_row_ref,
                                                             kernels::temporal_row_neon, nullptr};
  kernels::TemporalRow* const filter = kTemporal.pick(path);
  for (int y = 0; y < disparity.height(); ++y) {
    filter(disparity.row(y), last_.view().row(y), disparity.width(), weight_, max_step_);
  }
}

void fill_holes(ImageView<std::int16_t> disparity, int max_hole, SimdPath path) {
  require(max_hole >= 0, "hole filling: the longest hole must be 0 or more, not ", max_hole);
  if (max_hole == 0) return;
  static constexpr KernelSet<kernels::FillHolesRow> kFill{kernels::fill_holes_row_ref,
                                                          kernels::fill_holes_row_neon, nullptr};
  kernels::FillHolesRow* const fill = kFill.pick(path);
  for (int y = 0; y < disparity.height(); ++y) fill(disparity.row(y), disparity.width(), max_hole);
}

}  // namespace epipole::vision

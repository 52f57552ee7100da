#include "epipole/vision/disparity_filters.hpp"

#include <algorithm>
#include <cstdlib>

#include "disparity_filters_kernels.hpp"
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

namespace {

// The blend of both filters: `pixel` moved towards `before` where both are valid and close. The
// step is rounded half away from zero: rounding half up would add half a unit at each blend,
// and the spatial filter's chains of blends would drift upwards by a fifth of a pixel.
inline std::int16_t blend(int pixel, int before, int weight, int max_step_x16) {
  const int step = pixel - before;
  if (pixel < 0 || before < 0 || std::abs(step) > max_step_x16) {
    return static_cast<std::int16_t>(pixel);
  }
  const int moved = (std::abs(step) * weight + 128) >> 8;
  return static_cast<std::int16_t>(before + (step < 0 ? -moved : moved));
}

}  // namespace

void temporal_row_ref(std::int16_t* now, std::int16_t* last, int width, int weight,
                      int max_step_x16) {
  for (int x = 0; x < width; ++x) now[x] = last[x] = blend(now[x], last[x], weight, max_step_x16);
}

void spatial_pass_ref(std::int16_t* image, std::ptrdiff_t stride, int width, int height, int weight,
                      int max_step_x16, std::int16_t* /*scratch*/) {
  for (int y = 0; y < height; ++y) {
    std::int16_t* row = image + y * stride;
    for (int x = 1; x < width; ++x) row[x] = blend(row[x], row[x - 1], weight, max_step_x16);
    for (int x = width - 2; x >= 0; --x) row[x] = blend(row[x], row[x + 1], weight, max_step_x16);
  }
  const auto at = [&](int x, int y) -> std::int16_t& { return image[y * stride + x]; };
  for (int x = 0; x < width; ++x) {
    for (int y = 1; y < height; ++y) at(x, y) = blend(at(x, y), at(x, y - 1), weight, max_step_x16);
    for (int y = height - 2; y >= 0; --y) {
      at(x, y) = blend(at(x, y), at(x, y + 1), weight, max_step_x16);
    }
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

SpatialFilter::SpatialFilter(int width, int height, int own_percent, int max_step, int passes)
    : width_(width),
      height_(height),
      weight_((own_percent * 256 + 50) / 100),
      max_step_(max_step * kDisparityScale),
      passes_(passes) {
  require(width > 0 && height > 0, "spatial filter: empty size ", width, "x", height);
  require(own_percent >= 1 && own_percent <= 99, "spatial filter: a pixel's own weight is ",
          own_percent, " %, expected 1..99");
  require(max_step >= 1 && max_step <= 7, "spatial filter: the largest step is ", max_step,
          " px, expected 1..7");
  require(passes >= 1 && passes <= 4, "spatial filter: ", passes, " passes, expected 1..4");
  scratch_.assign(static_cast<std::size_t>(width) * 9, 0);
}

void SpatialFilter::apply(ImageView<std::int16_t> disparity, SimdPath path) {
  require(disparity.width() == width_ && disparity.height() == height_, "spatial filter for ",
          width_, "x", height_, " was given a ", disparity.width(), "x", disparity.height(),
          " disparity");
  static constexpr KernelSet<kernels::SpatialPass> kSpatial{kernels::spatial_pass_ref,
                                                            kernels::spatial_pass_neon, nullptr};
  kernels::SpatialPass* const pass = kSpatial.pick(path);
  for (int i = 0; i < passes_; ++i) {
    pass(disparity.row(0), disparity.stride(), width_, height_, weight_, max_step_,
         scratch_.data());
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

#include "epipole/vision/remap.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <utility>

#include "epipole/core/error.hpp"
#include "epipole/core/fixed_point.hpp"
#include "kernel_set.hpp"
#include "remap_kernels.hpp"

namespace epipole::vision {

namespace kernels {

namespace {

// The source pixel (x, y), or the border value outside the image.
inline int pixel_or_border(GrayView source, int x, int y, int border) {
  return static_cast<unsigned>(x) < static_cast<unsigned>(source.width()) &&
                 static_cast<unsigned>(y) < static_cast<unsigned>(source.height())
             ? source(x, y)
             : border;
}

inline std::uint8_t blend(int s00, int s01, int s10, int s11, unsigned fraction) {
  const int fx = static_cast<int>(fraction & (RemapMap::kFractionSteps - 1));
  const int fy =
      static_cast<int>((fraction >> RemapMap::kFractionBits) & (RemapMap::kFractionSteps - 1));
  const int top = s00 * (32 - fx) + s01 * fx;
  const int bottom = s10 * (32 - fx) + s11 * fx;
  return static_cast<std::uint8_t>((top * (32 - fy) + bottom * fy + 512) >> 10);
}

}  // namespace

void remap_row_ref(GrayView source, const std::int16_t* xy, const std::uint16_t* fractions,
                   int width, std::uint8_t border, std::uint8_t* destination) {
  // (x, y) has its four neighbours inside when x < inner_width and y < inner_height (unsigned).
  const auto inner_width = static_cast<unsigned>(std::max(source.width() - 1, 0));
  const auto inner_height = static_cast<unsigned>(std::max(source.height() - 1, 0));
  const std::ptrdiff_t stride = source.stride();
  for (int i = 0; i < width; ++i) {
    const int x = xy[2 * i];
    const int y = xy[2 * i + 1];
    const unsigned fraction = fractions[i];
    if (static_cast<unsigned>(x) < inner_width && static_cast<unsigned>(y) < inner_height) {
      const std::uint8_t* p = source.row(y) + x;
      destination[i] = blend(p[0], p[1], p[stride], p[stride + 1], fraction);
    } else {
      destination[i] =
          blend(pixel_or_border(source, x, y, border), pixel_or_border(source, x + 1, y, border),
                pixel_or_border(source, x, y + 1, border),
                pixel_or_border(source, x + 1, y + 1, border), fraction);
    }
  }
}

RemapRowKernel* remap_row_kernel(SimdPath path) {
  static constexpr KernelSet<RemapRowKernel> kKernels{remap_row_ref, remap_row_neon,
                                                      EPIPOLE_AVX2_KERNEL(remap_row_avx2)};
  return kKernels.pick(path);
}

}  // namespace kernels

namespace {

void require_map_size(int width, int height) {
  require(width >= 0 && height >= 0 && width <= RemapMap::kMaxSize && height <= RemapMap::kMaxSize,
          "remap map size ", width, "x", height, " is outside [0, ", RemapMap::kMaxSize, "]");
}

}  // namespace

RemapMap::RemapMap(int width, int height) {
  require_map_size(width, height);
  xy_ = Image<std::int16_t>(2 * width, height);
  fractions_ = Image<std::uint16_t>(width, height);
  for (int y = 0; y < height; ++y) {
    std::int16_t* xy = xy_.view().row(y);
    for (int x = 0; x < width; ++x) {
      xy[2 * x] = static_cast<std::int16_t>(x);
      xy[2 * x + 1] = static_cast<std::int16_t>(y);
    }
    std::fill_n(fractions_.view().row(y), width, std::uint16_t{0});
  }
}

RemapMap::RemapMap(ImageView<const std::int16_t> xy, ImageView<const std::uint16_t> fractions) {
  require(xy.width() == 2 * fractions.width() && xy.height() == fractions.height(),
          "remap map planes disagree: xy is ", xy.width(), "x", xy.height(),
          " (2 int16 per pixel), fractions ", fractions.width(), "x", fractions.height());
  require_map_size(fractions.width(), fractions.height());
  xy_ = Image<std::int16_t>(xy.width(), xy.height());
  fractions_ = Image<std::uint16_t>(fractions.width(), fractions.height());
  for (int y = 0; y < xy.height(); ++y) {
    std::copy_n(xy.row(y), xy.width(), xy_.view().row(y));
    std::copy_n(fractions.row(y), fractions.width(), fractions_.view().row(y));
  }
}

RemapMap RemapMap::from_float(ImageView<const float> map_x, ImageView<const float> map_y) {
  require(same_size(map_x, map_y), "remap float maps differ in size: x is ", map_x.width(), "x",
          map_x.height(), ", y is ", map_y.width(), "x", map_y.height());
  RemapMap map(map_x.width(), map_x.height());
  map.assign_float(map_x, map_y);
  return map;
}

void RemapMap::assign_float(ImageView<const float> map_x, ImageView<const float> map_y) {
  require(map_x.width() == width() && map_x.height() == height() && same_size(map_x, map_y),
          "remap float maps of ", map_x.width(), "x", map_x.height(), " and ", map_y.width(), "x",
          map_y.height(), " do not fit a ", width(), "x", height(), " map");
  for (int v = 0; v < height(); ++v) {
    std::int16_t* xy = xy_.view().row(v);
    std::uint16_t* fractions = fractions_.view().row(v);
    const float* xs = map_x.row(v);
    const float* ys = map_y.row(v);
    for (int u = 0; u < width(); ++u) {
      const int fx = to_fixed_point(xs[u], &xy[2 * u]);
      const int fy = to_fixed_point(ys[u], &xy[2 * u + 1]);
      fractions[u] = static_cast<std::uint16_t>(fy * kFractionSteps + fx);
    }
  }
}

RemapMap RemapMap::clone() const {
  RemapMap copy;
  copy.xy_ = xy_.clone();
  copy.fractions_ = fractions_.clone();
  return copy;
}

Rectifier::Rectifier(const RectifierConfig& config, RemapMap map, SimdPath path)
    : config_(config), path_(path), map_(std::move(map)) {
  const auto in_range = [](int size) { return size >= 1 && size <= RemapMap::kMaxSize; };
  require(in_range(config.source_width) && in_range(config.source_height), "rectifier source size ",
          config.source_width, "x", config.source_height, " is outside [1, ", RemapMap::kMaxSize,
          "]");
  require(in_range(config.width) && in_range(config.height), "rectifier output size ", config.width,
          "x", config.height, " is outside [1, ", RemapMap::kMaxSize, "]");
  require(map_.width() == config.width && map_.height() == config.height, "rectifier map is ",
          map_.width(), "x", map_.height(), " but the output is ", config.width, "x",
          config.height);
  if (config.own_output) output_ = GrayImage(config.width, config.height);
}

void Rectifier::swap_map(RemapMap& other) {
  require(other.width() == map_.width() && other.height() == map_.height(), "a map of ",
          other.width(), "x", other.height(), " cannot replace the rectifier's ", map_.width(), "x",
          map_.height());
  std::swap(map_, other);
}

std::size_t Rectifier::working_set_bytes() const {
  return map_.size_bytes() + output_.size_bytes();
}

GrayView Rectifier::rectify(GrayView source) {
  check_own_output();
  rectify(source, output_.view());
  return output_.view();
}

void Rectifier::check_own_output() const {
  require(config_.own_output, "this rectifier has no image of its own: give it one to fill");
}

void Rectifier::check_source(GrayView source) const {
  require(source.width() == config_.source_width && source.height() == config_.source_height,
          "rectifier configured for ", config_.source_width, "x", config_.source_height,
          " sources was given a ", source.width(), "x", source.height(), " image");
}

void Rectifier::rectify(GrayView source, MutableGrayView destination) const {
  rectify_rows(source, destination, 0, config_.height);
}

GrayView Rectifier::rectify_rows(GrayView source, int first_row, int end_row) {
  check_own_output();
  rectify_rows(source, output_.view(), first_row, end_row);
  return output_.view();
}

void Rectifier::rectify_rows(GrayView source, MutableGrayView destination, int first_row,
                             int end_row) const {
  check_source(source);
  require(destination.width() == config_.width && destination.height() == config_.height,
          "rectifier output is ", config_.width, "x", config_.height, ", not ", destination.width(),
          "x", destination.height());
  require(0 <= first_row && first_row <= end_row && end_row <= config_.height, "rows ", first_row,
          "..", end_row, " are not within the rectified image's ", config_.height);
  // Byte ranges [first, last] of both images; std::less gives a total order on pointers.
  const std::uint8_t* source_end = source.row(source.height() - 1) + source.width();
  const std::uint8_t* destination_begin = destination.data();
  const std::uint8_t* destination_end =
      destination.row(destination.height() - 1) + destination.width();
  const std::less<const std::uint8_t*> before;
  require(!before(destination_begin, source_end) || !before(source.data(), destination_end),
          "rectifier output overlaps its source");
  remap_rows(source, destination, first_row, end_row);
}

void Rectifier::remap_rows(GrayView source, MutableGrayView destination, int first_row,
                           int end_row) const {
  kernels::RemapRowKernel* const row_kernel = kernels::remap_row_kernel(path_);
  const ImageView<const std::int16_t> xy = map_.xy();
  const ImageView<const std::uint16_t> fractions = map_.fractions();
  for (int y = first_row; y < end_row; ++y) {
    row_kernel(source, xy.row(y), fractions.row(y), config_.width, config_.border,
               destination.row(y));
  }
}

}  // namespace epipole::vision

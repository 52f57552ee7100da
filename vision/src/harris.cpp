// The Harris response (reference rows and the whole-image driver) and the corner detector.
//
// Floating point: this file and harris_neon.cpp are compiled with -ffp-contract=off (see
// vision/CMakeLists.txt), so that GCC fuses no a*b+c into an FMA here (it would on aarch64 and
// ARMv7-VFPv4 by default) and the reference and NEON float steps give the same bits.
#include "epipole/vision/harris.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "epipole/core/error.hpp"
#include "harris_kernels.hpp"
#include "harris_rows.hpp"
#include "kernel_set.hpp"

namespace epipole::vision {

namespace kernels {

namespace {

// BORDER_REFLECT_101 for -n < i < 2n - 1: ... 2 1 | 0 1 2 ... n-2 n-1 | n-2 n-3 ...
int reflect101(int i, int n) {
  if (i < 0) return -i;
  if (i >= n) return 2 * n - 2 - i;
  return i;
}

void products_row_ref(const std::uint8_t* above, const std::uint8_t* row, const std::uint8_t* below,
                      int width, std::int32_t* xx, std::int32_t* xy, std::int32_t* yy) {
  harris_products_columns_ref(above, row, below, width, 0, width, xx, xy, yy);
}

void column_sums_ref(const std::int32_t* const* rows, int count, int width, std::int32_t* sums) {
  for (int x = 0; x < width; ++x) {
    std::int32_t sum = 0;
    for (int i = 0; i < count; ++i) sum += rows[i][x];
    sums[x] = sum;
  }
}

void box_response_row_ref(const std::int32_t* sxx, const std::int32_t* sxy, const std::int32_t* syy,
                          int width, int block_size, float scale2, float k, float* out) {
  harris_box_response_columns_ref(sxx, sxy, syy, 0, width, block_size, scale2, k, out);
}

}  // namespace

void harris_products_columns_ref(const std::uint8_t* above, const std::uint8_t* row,
                                 const std::uint8_t* below, int width, int x_begin, int x_end,
                                 std::int32_t* xx, std::int32_t* xy, std::int32_t* yy) {
  for (int x = x_begin; x < x_end; ++x) {
    const int l = x == 0 ? 1 : x - 1;
    const int r = x == width - 1 ? width - 2 : x + 1;
    // Sobel: dx = [-1 0 1] horizontally smoothed by [1 2 1] vertically, dy the transpose.
    const int dx = (above[r] - above[l]) + 2 * (row[r] - row[l]) + (below[r] - below[l]);
    const int dy = (below[l] + 2 * below[x] + below[r]) - (above[l] + 2 * above[x] + above[r]);
    xx[x] = dx * dx;
    xy[x] = dx * dy;
    yy[x] = dy * dy;
  }
}

void harris_box_response_columns_ref(const std::int32_t* sxx, const std::int32_t* sxy,
                                     const std::int32_t* syy, int x_begin, int x_end,
                                     int block_size, float scale2, float k, float* out) {
  const int radius = block_size / 2;
  for (int x = x_begin; x < x_end; ++x) {
    std::int32_t a = 0, b = 0, c = 0;
    for (int i = x - radius; i <= x + radius; ++i) {
      a += sxx[i];
      b += sxy[i];
      c += syy[i];
    }
    out[x] = harris_score(a, b, c, scale2, k);
  }
}

std::size_t harris_workspace_elements(int width, int block_size) {
  const auto w = static_cast<std::size_t>(width);
  const auto b = static_cast<std::size_t>(block_size);
  return 3 * (b * w + w + b - 1);
}

void harris_response_rows(GrayView image, int block_size, float k, std::int32_t* workspace,
                          ImageView<float> response, const HarrisRowKernels& rows) {
  const int width = image.width();
  const int height = image.height();
  const int radius = block_size / 2;
  const auto w = static_cast<std::size_t>(width);
  const std::size_t padded = w + 2 * static_cast<std::size_t>(radius);
  // OpenCV's scale for 8-bit input and ksize 3, applied to each gradient: s = 1 / (4 B 255).
  const double scale = 1.0 / (4.0 * block_size * 255.0);
  const auto scale2 = static_cast<float>(scale * scale);

  // A ring of block_size rows of products; row y lives in slot y % block_size. Output row y
  // needs the rows max(0, y - r) .. min(height - 1, y + r) (reflection stays inside them), so
  // computing rows in order never overwrites one still needed.
  std::int32_t* products = workspace;
  std::int32_t* sums = workspace + 3 * static_cast<std::size_t>(block_size) * w;
  const auto product_row = [&](int y, int channel) {
    return products + (static_cast<std::size_t>(y % block_size) * 3 + channel) * w;
  };

  const std::int32_t* window[3][kHarrisMaxBlockSize];
  int next = 0;  // the first product row not computed yet
  for (int y = 0; y < height; ++y) {
    for (const int last = std::min(y + radius, height - 1); next <= last; ++next) {
      rows.products(image.row(reflect101(next - 1, height)), image.row(next),
                    image.row(reflect101(next + 1, height)), width, product_row(next, 0),
                    product_row(next, 1), product_row(next, 2));
    }
    for (int channel = 0; channel < 3; ++channel) {
      for (int i = 0; i < block_size; ++i) {
        window[channel][i] = product_row(reflect101(y - radius + i, height), channel);
      }
      std::int32_t* s = sums + channel * padded + radius;
      rows.column_sums(window[channel], block_size, width, s);
      for (int i = 1; i <= radius; ++i) {  // BORDER_REFLECT_101 on the columns
        s[-i] = s[i];
        s[width - 1 + i] = s[width - 1 - i];
      }
    }
    rows.box_response(sums + radius, sums + padded + radius, sums + 2 * padded + radius, width,
                      block_size, scale2, k, response.row(y));
  }
}

void harris_response_ref(GrayView image, int block_size, float k, std::int32_t* workspace,
                         ImageView<float> response) {
  static constexpr HarrisRowKernels kRows{products_row_ref, column_sums_ref, box_response_row_ref};
  harris_response_rows(image, block_size, k, workspace, response, kRows);
}

float harris_max_response_ref(ImageView<const float> response) {
  float max_r = -std::numeric_limits<float>::infinity();
  for (int y = 0; y < response.height(); ++y) {
    const float* row = response.row(y);
    for (int x = 0; x < response.width(); ++x) max_r = std::max(max_r, row[x]);
  }
  return max_r == 0.0f ? 0.0f : max_r;
}

HarrisMaxResponseKernel* harris_max_response_kernel(SimdPath path) {
  static constexpr KernelSet<HarrisMaxResponseKernel> kKernels{harris_max_response_ref,
                                                               harris_max_response_neon, nullptr};
  return kKernels.pick(path);
}

std::size_t harris_candidates_row_ref(const float* above, const float* row, const float* below,
                                      int width, float threshold, std::uint32_t row_offset,
                                      std::uint32_t* out) {
  std::size_t n = 0;
  for (int x = 1; x < width - 1; ++x) {
    if (harris_is_candidate(above, row, below, x, threshold)) {
      out[n++] = row_offset + static_cast<std::uint32_t>(x);
    }
  }
  return n;
}

HarrisCandidatesRowKernel* harris_candidates_row_kernel(SimdPath path) {
  static constexpr KernelSet<HarrisCandidatesRowKernel> kKernels{
      harris_candidates_row_ref, harris_candidates_row_neon, nullptr};
  return kKernels.pick(path);
}

HarrisResponseKernel* harris_response_kernel(SimdPath path) {
  static constexpr KernelSet<HarrisResponseKernel> kKernels{harris_response_ref,
                                                            harris_response_neon, nullptr};
  return kKernels.pick(path);
}

}  // namespace kernels

HarrisDetector::HarrisDetector(const HarrisConfig& config, SimdPath path)
    : config_(config), path_(path) {
  require(config.block_size >= 1 && config.block_size <= kHarrisMaxBlockSize &&
              config.block_size % 2 == 1,
          "Harris block_size must be odd and in [1, ", kHarrisMaxBlockSize, "], not ",
          config.block_size);
  const int min_size = std::max(3, config.block_size);
  require(config.width >= min_size && config.height >= min_size, "Harris with block_size ",
          config.block_size, " needs an image of at least ", min_size, "x", min_size, ", not ",
          config.width, "x", config.height);
  require(static_cast<long long>(config.width + 15) * config.height <=
              std::numeric_limits<std::int32_t>::max(),
          "Harris image ", config.width, "x", config.height, " is too large");
  // k outside [1e-6, 1] is meaningless (k > 0.25 makes every R <= 0); below 1e-6, k trace^2
  // could be a denormal, which ARMv7 NEON flushes to zero and the scalar code does not.
  require(config.k == 0.0 || (config.k >= 1e-6 && config.k <= 1.0),
          "Harris k must be 0 or in [1e-6, 1], not ", config.k);
  require(std::isfinite(config.quality_level) && config.quality_level > 0.0,
          "Harris quality_level must be finite and > 0, not ", config.quality_level);
  require(std::isfinite(config.min_distance) && config.min_distance >= 0.0,
          "Harris min_distance must be finite and >= 0, not ", config.min_distance);
  require(config.max_corners > 0, "Harris max_corners must be positive, not ", config.max_corners);

  const auto w = static_cast<std::size_t>(config.width);
  const auto h = static_cast<std::size_t>(config.height);
  if (config.min_distance >= 1.0) {
    // OpenCV's cell is cvRound(min_distance); any cell of at least that size finds every kept
    // corner closer than min_distance in the 3x3 cells around a pixel, so capping it at the
    // image size changes no result.
    const double capped = std::min(config.min_distance, static_cast<double>(std::max(w, h)));
    cell_size_ = std::max(1, static_cast<int>(std::lrint(capped)));
    grid_width_ = (config.width + cell_size_ - 1) / cell_size_;
    grid_height_ = (config.height + cell_size_ - 1) / cell_size_;
    grid_heads_ = std::make_unique<int[]>(static_cast<std::size_t>(grid_width_) * grid_height_);
    grid_links_ = std::make_unique<int[]>(static_cast<std::size_t>(config.max_corners));
  }
  response_ = Image<float>(config.width, config.height);
  workspace_ = std::make_unique<std::int32_t[]>(
      kernels::harris_workspace_elements(config.width, config.block_size));
  candidates_ = std::make_unique<std::uint32_t[]>((w - 2) * (h - 2));
  corners_ = std::make_unique<Corner[]>(static_cast<std::size_t>(config.max_corners));
}

std::size_t HarrisDetector::working_set_bytes() const {
  const auto w = static_cast<std::size_t>(config_.width);
  const auto h = static_cast<std::size_t>(config_.height);
  const auto max_corners = static_cast<std::size_t>(config_.max_corners);
  std::size_t bytes = response_.size_bytes();
  bytes +=
      kernels::harris_workspace_elements(config_.width, config_.block_size) * sizeof(std::int32_t);
  bytes += (w - 2) * (h - 2) * sizeof(std::uint32_t);
  if (cell_size_ > 0) {
    bytes += static_cast<std::size_t>(grid_width_) * grid_height_ * sizeof(int);
    bytes += max_corners * sizeof(int);
  }
  return bytes + max_corners * sizeof(Corner);
}

ImageView<const float> HarrisDetector::compute_response(GrayView image) {
  require(image.width() == config_.width && image.height() == config_.height,
          "Harris configured for ", config_.width, "x", config_.height, " was given a ",
          image.width(), "x", image.height(), " image");
  kernels::harris_response_kernel(path_)(image, config_.block_size, static_cast<float>(config_.k),
                                         workspace_.get(), response_.view());
  return response_.view();
}

std::span<const Corner> HarrisDetector::detect(GrayView image) {
  const ImageView<const float> r = compute_response(image);
  const int width = config_.width;
  const int height = config_.height;

  const float max_r = kernels::harris_max_response_kernel(path_)(r);
  max_response_ = max_r;
  // As cv::threshold(THRESH_TOZERO) with a float threshold: kept when R > threshold.
  threshold_ = static_cast<float>(static_cast<double>(max_r) * config_.quality_level);
  const float t = threshold_;

  // Candidates: kept, non-zero and the maximum of the kept values of their 3x3 neighbourhood.
  // They are kept as offsets y * stride + x into the response.
  kernels::HarrisCandidatesRowKernel* const candidates_row =
      kernels::harris_candidates_row_kernel(path_);
  std::size_t n = 0;
  std::uint32_t* candidates = candidates_.get();
  for (int y = 1; y < height - 1; ++y) {
    const float* row = r.row(y);
    n += candidates_row(r.row(y - 1), row, r.row(y + 1), width, t,
                        static_cast<std::uint32_t>(row - r.data()), candidates + n);
  }
  // OpenCV's order: larger response first, and among equal responses the later pixel first.
  const float* base = r.data();
  std::sort(candidates, candidates + n, [base](std::uint32_t a, std::uint32_t b) {
    return base[a] != base[b] ? base[a] > base[b] : a > b;
  });

  // Greedy minimum distance, strongest first; the grid holds the kept corners of each cell.
  count_ = 0;
  truncated_ = false;
  const double min_distance2 = config_.min_distance * config_.min_distance;
  if (cell_size_ > 0) {
    std::fill_n(grid_heads_.get(), static_cast<std::size_t>(grid_width_) * grid_height_, -1);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (count_ == config_.max_corners) {
      truncated_ = true;
      break;
    }
    const auto offset = static_cast<std::ptrdiff_t>(candidates[i]);
    const auto y = static_cast<int>(offset / r.stride());
    const auto x = static_cast<int>(offset % r.stride());
    if (cell_size_ > 0) {
      const int cx = x / cell_size_;
      const int cy = y / cell_size_;
      bool close = false;
      for (int gy = std::max(0, cy - 1); gy <= std::min(grid_height_ - 1, cy + 1) && !close; ++gy) {
        for (int gx = std::max(0, cx - 1); gx <= std::min(grid_width_ - 1, cx + 1) && !close;
             ++gx) {
          for (int j = grid_heads_[gy * grid_width_ + gx]; j >= 0 && !close; j = grid_links_[j]) {
            const int dx = x - corners_[j].x;
            const int dy = y - corners_[j].y;
            close = static_cast<double>(dx * dx + dy * dy) < min_distance2;
          }
        }
      }
      if (close) continue;
      const int cell = cy * grid_width_ + cx;
      grid_links_[count_] = grid_heads_[cell];
      grid_heads_[cell] = count_;
    }
    corners_[count_++] = Corner{x, y, base[offset]};
  }
  return {corners_.get(), static_cast<std::size_t>(count_)};
}

}  // namespace epipole::vision

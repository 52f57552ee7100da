#include "epipole/vision/fast.hpp"

#include <algorithm>
#include <cstring>

#include "epipole/core/error.hpp"
#include "fast_columns.hpp"
#include "fast_kernels.hpp"
#include "kernel_set.hpp"

namespace epipole::vision {

namespace kernels {

namespace {
// The circle, clockwise from the top: (dx, dy).
constexpr int kCircle[16][2] = {{0, -3}, {1, -3},  {2, -2},  {3, -1}, {3, 0},  {3, 1},
                                {2, 2},  {1, 3},   {0, 3},   {-1, 3}, {-2, 2}, {-3, 1},
                                {-3, 0}, {-3, -1}, {-2, -2}, {-1, -3}};
constexpr int kArc = 9;  // contiguous circle pixels that make a corner
}  // namespace

void fast_circle_offsets(std::ptrdiff_t stride, std::ptrdiff_t offsets[25]) {
  // Unrolled: the row kernels call this once a row.
#pragma GCC unroll 25
  for (int k = 0; k < 25; ++k) offsets[k] = kCircle[k & 15][0] + kCircle[k & 15][1] * stride;
}

int fast_score(const std::uint8_t* p, const std::ptrdiff_t* circle, int threshold) {
  const int v = p[0];
  int d[25];
  for (int k = 0; k < 25; ++k) d[k] = v - p[circle[k]];

  // Brighter-than-centre arcs: the largest a0 such that some 9-arc has every d > a0... taken
  // over arcs starting at even positions and extended by one on either side, as OpenCV does.
  int a0 = threshold;
  for (int k = 0; k < 16; k += 2) {
    int a = std::min({d[k + 1], d[k + 2], d[k + 3]});
    if (a <= a0) continue;
    a = std::min({a, d[k + 4], d[k + 5], d[k + 6], d[k + 7], d[k + 8]});
    a0 = std::max(a0, std::min(a, d[k]));
    a0 = std::max(a0, std::min(a, d[k + 9]));
  }
  int b0 = -a0;
  for (int k = 0; k < 16; k += 2) {
    int b = std::max({d[k + 1], d[k + 2], d[k + 3], d[k + 4], d[k + 5]});
    if (b >= b0) continue;
    b = std::max({b, d[k + 6], d[k + 7], d[k + 8]});
    b0 = std::min(b0, std::max(b, d[k]));
    b0 = std::min(b0, std::max(b, d[k + 9]));
  }
  return -b0 - 1;
}

int fast_columns_ref(const std::uint8_t* row, const std::ptrdiff_t* circle, int x_begin, int x_end,
                     int threshold, std::uint8_t* scores, int* columns) {
  int count = 0;
  for (int x = x_begin; x < x_end; ++x) {
    const std::uint8_t* p = row + x;
    const int v = p[0];
    const int darker_than = v - threshold;
    const int brighter_than = v + threshold;
    int dark_run = 0;
    int bright_run = 0;
    bool corner = false;
    for (int k = 0; k < 25 && !corner; ++k) {
      const int c = p[circle[k]];
      dark_run = c < darker_than ? dark_run + 1 : 0;
      bright_run = c > brighter_than ? bright_run + 1 : 0;
      corner = dark_run >= kArc || bright_run >= kArc;
    }
    if (corner) {
      scores[x] = static_cast<std::uint8_t>(fast_score(p, circle, threshold));
      columns[count++] = x;
    }
  }
  return count;
}

int fast_row_ref(const std::uint8_t* row, std::ptrdiff_t stride, int width, int threshold,
                 std::uint8_t* scores, int* columns) {
  std::ptrdiff_t circle[25];
  fast_circle_offsets(stride, circle);
  std::memset(scores, 0, static_cast<std::size_t>(width));
  return fast_columns_ref(row, circle, 3, width - 3, threshold, scores, columns);
}

FastRowKernel* fast_row_kernel(SimdPath path) {
  static constexpr KernelSet<FastRowKernel> kKernels{fast_row_ref, fast_row_neon,
                                                     EPIPOLE_AVX2_KERNEL(fast_row_avx2)};
  return kKernels.pick(path);
}

}  // namespace kernels

namespace {
FastConfig checked(const FastConfig& config) {
  require(config.width >= 7 && config.height >= 7, "FAST needs an image of at least 7x7, not ",
          config.width, "x", config.height);
  require(config.max_corners > 0, "FAST max_corners must be positive, not ", config.max_corners);
  FastConfig clamped = config;
  clamped.threshold = std::clamp(config.threshold, 0, 255);
  return clamped;
}
}  // namespace

FastDetector::FastDetector(const FastConfig& config, SimdPath path)
    : config_(checked(config)),
      path_(path),
      score_rows_(std::make_unique<std::uint8_t[]>(3 * static_cast<std::size_t>(config.width))),
      corner_columns_(std::make_unique<int[]>(3 * static_cast<std::size_t>(config.width))),
      strongest_(config.width, config.height, config.max_corners, config.grid_columns,
                 config.grid_rows) {}

std::size_t FastDetector::working_set_bytes() const {
  const auto w = static_cast<std::size_t>(config_.width);
  return 3 * w + 3 * w * sizeof(int) + strongest_.working_set_bytes();
}

std::span<const Corner> FastDetector::detect(GrayView image) {
  require(image.width() == config_.width && image.height() == config_.height,
          "FAST configured for ", config_.width, "x", config_.height, " was given a ",
          image.width(), "x", image.height(), " image");
  kernels::FastRowKernel* const row_kernel = kernels::fast_row_kernel(path_);
  const int width = config_.width;
  const int height = config_.height;
  const auto w = static_cast<std::size_t>(width);
  std::memset(score_rows_.get(), 0, 3 * w);
  int row_counts[3] = {0, 0, 0};
  strongest_.clear();

  // Rows are scored one ahead: row y-1's corners are kept once row y's scores are known.
  for (int y = 3; y < height - 2; ++y) {
    const int slot = (y - 3) % 3;
    std::uint8_t* current = score_rows_.get() + slot * w;
    int* columns = corner_columns_.get() + slot * w;
    if (y < height - 3) {
      row_counts[slot] =
          row_kernel(image.row(y), image.stride(), width, config_.threshold, current, columns);
    } else {
      std::memset(current, 0, w);
      row_counts[slot] = 0;
    }
    if (y == 3) continue;

    const int prev_slot = (y - 4) % 3;
    const std::uint8_t* prev = score_rows_.get() + prev_slot * w;
    const std::uint8_t* pprev = score_rows_.get() + ((y - 5 + 3) % 3) * w;
    const int* prev_columns = corner_columns_.get() + prev_slot * w;
    for (int i = 0; i < row_counts[prev_slot]; ++i) {
      const int x = prev_columns[i];
      const int s = prev[x];
      if (!config_.nonmax ||
          (s > prev[x - 1] && s > prev[x + 1] && s > pprev[x - 1] && s > pprev[x] &&
           s > pprev[x + 1] && s > current[x - 1] && s > current[x] && s > current[x + 1])) {
        strongest_.offer({x, y - 1, static_cast<float>(s)});
      }
    }
  }

  return strongest_.finish();
}

}  // namespace epipole::vision

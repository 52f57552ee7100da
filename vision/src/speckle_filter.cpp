// The speckle filter on runs: each row is cut into runs of valid pixels that continue one
// another (kernels::SpeckleMasksRow's `left`), a run joins the runs above it that it touches at
// a pixel connected upwards (`up`), by union-find over all runs with each region's size at its
// root; then the same runs, found again, are invalidated where their region is small. The
// masks come from a NEON kernel; runs and overlaps are found 16 pixels a word.
#include "epipole/vision/speckle_filter.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <utility>

#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"
#include "kernel_set.hpp"
#include "speckle_filter_kernels.hpp"

namespace epipole::vision {

namespace kernels {

void speckle_masks_row_ref(const std::int16_t* row, const std::int16_t* above, int width,
                           int range_x16, std::uint64_t* valid, std::uint64_t* left,
                           std::uint64_t* up) {
  const int words = (width + 15) / 16;
  std::fill_n(valid, words, std::uint64_t{0});
  std::fill_n(left, words, std::uint64_t{0});
  std::fill_n(up, words, std::uint64_t{0});
  const auto near = [range_x16](int a, int b) { return std::abs(a - b) <= range_x16; };
  for (int x = 0; x < width; ++x) {
    if (row[x] < 0) continue;
    const std::uint64_t nibble = std::uint64_t{0xF} << (4 * (x % 16));
    valid[x / 16] |= nibble;
    if (x > 0 && row[x - 1] >= 0 && near(row[x], row[x - 1])) left[x / 16] |= nibble;
    if (above != nullptr && above[x] >= 0 && near(row[x], above[x])) up[x / 16] |= nibble;
  }
}

}  // namespace kernels

namespace {

constexpr int kPixelsPerWord = 16;

// The nibble of pixel b (0..15) and those above it.
std::uint64_t from_pixel(int b) {
  return ~std::uint64_t{0} << (4 * b);
}

// The first pixel from `from` on whose nibble is set in (mask(w)), or `limit` when none is.
template <typename Mask>
int first_set(Mask&& mask, int from, int words, int limit) {
  if (from >= limit) return limit;
  int w = from / kPixelsPerWord;
  std::uint64_t bits = mask(w) & from_pixel(from % kPixelsPerWord);
  while (bits == 0) {
    if (++w == words) return limit;
    bits = mask(w);
  }
  return std::min(limit, w * kPixelsPerWord + std::countr_zero(bits) / 4);
}

// Whether any nibble of pixels [begin, end) is set in `mask`.
bool any_set(const std::uint64_t* mask, int begin, int end) {
  const int first = begin / kPixelsPerWord;
  const int last = (end - 1) / kPixelsPerWord;
  const std::uint64_t head = from_pixel(begin % kPixelsPerWord);
  const int tail_pixels = end - last * kPixelsPerWord;  // 1..16
  const std::uint64_t tail =
      tail_pixels == kPixelsPerWord ? ~std::uint64_t{0} : ~from_pixel(tail_pixels);
  if (first == last) return (mask[first] & head & tail) != 0;
  if ((mask[first] & head) != 0 || (mask[last] & tail) != 0) return true;
  for (int w = first + 1; w < last; ++w) {
    if (mask[w] != 0) return true;
  }
  return false;
}

}  // namespace

SpeckleFilter::SpeckleFilter(int width, int height, int min_size, int range)
    : width_(width),
      height_(height),
      min_size_(min_size),
      words_((width + kPixelsPerWord - 1) / kPixelsPerWord) {
  require(width > 0 && height > 0, "speckle filter: the size must not be empty, not ", width, "x",
          height);
  require(min_size >= 1, "speckle filter: the smallest region kept must be 1 pixel or more, not ",
          min_size);
  require(range >= 0 && range <= 255, "speckle filter: the range must be 0..255 px, not ", range);
  range_x16_ = range * kDisparityScale;
  const auto w = static_cast<std::size_t>(width);
  nodes_.assign(w * static_cast<std::size_t>(height), 0);  // at most one run per pixel
  const auto words = static_cast<std::size_t>(words_);
  valid_.assign(words, 0);
  left_.assign(words, 0);
  up_.assign(words, 0);
  for (Runs& r : runs_) {
    r.begin.assign(w, 0);
    r.end.assign(w, 0);
  }
}

std::size_t SpeckleFilter::working_set_bytes() const {
  std::size_t n = (nodes_.size() + 4 * static_cast<std::size_t>(width_)) * sizeof(std::int32_t);
  return n + 3 * valid_.size() * sizeof(std::uint64_t);
}

// A run starts at a valid pixel that does not continue the one before it and ends at the first
// pixel after it that does not continue it.
void SpeckleFilter::find_runs(Runs& runs) const {
  const std::uint64_t* const valid = valid_.data();
  const std::uint64_t* const left = left_.data();
  const auto starts = [&](int w) { return valid[w] & ~left[w]; };
  const auto breaks = [&](int w) { return ~left[w]; };
  int count = 0;
  for (int x = first_set(starts, 0, words_, width_); x < width_;) {
    const int end = first_set(breaks, x + 1, words_, width_);
    runs.begin[static_cast<std::size_t>(count)] = x;
    runs.end[static_cast<std::size_t>(count)] = end;
    ++count;
    x = first_set(starts, end, words_, width_);
  }
  runs.count = count;
}

void SpeckleFilter::apply(ImageView<std::int16_t> disparity, SimdPath path) {
  require(disparity.width() == width_ && disparity.height() == height_, "speckle filter: made for ",
          width_, "x", height_, ", given ", disparity.width(), "x", disparity.height());
  if (min_size_ <= 1) return;
  static constexpr KernelSet<kernels::SpeckleMasksRow> kMasks{
      kernels::speckle_masks_row_ref, kernels::speckle_masks_row_neon, nullptr};
  kernels::SpeckleMasksRow* const masks = kMasks.pick(path);
  std::int32_t* const node = nodes_.data();
  const auto find = [node](std::int32_t i) {
    while (node[i] >= 0) {
      if (node[node[i]] >= 0) node[i] = node[node[i]];
      i = node[i];
    }
    return i;
  };
  const auto join = [&](std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    const auto [big, small] = node[a] <= node[b] ? std::pair{a, b} : std::pair{b, a};
    node[big] += node[small];
    node[small] = big;
  };
  Runs* cur = &runs_[0];
  Runs* above = &runs_[1];
  std::int32_t count = 0;        // runs so far
  std::int32_t above_first = 0;  // the id of the row above's first run
  for (int y = 0; y < height_; ++y) {
    masks(disparity.row(y), y > 0 ? disparity.row(y - 1) : nullptr, width_, range_x16_,
          valid_.data(), left_.data(), up_.data());
    find_runs(*cur);
    const std::int32_t first = count;
    for (int i = 0; i < cur->count; ++i) node[count++] = cur->begin[i] - cur->end[i];
    // Each pair of runs that overlap, in order along the row: joined when a pixel they share
    // is connected upwards.
    for (int i = 0, j = 0; y > 0 && i < cur->count && j < above->count;) {
      const int begin = std::max(cur->begin[i], above->begin[j]);
      const int end = std::min(cur->end[i], above->end[j]);
      if (begin < end && any_set(up_.data(), begin, end)) join(first + i, above_first + j);
      if (cur->end[i] <= above->end[j]) {
        ++i;
      } else {
        ++j;
      }
    }
    above_first = first;
    std::swap(cur, above);
  }
  std::int32_t id = 0;
  for (int y = 0; y < height_; ++y) {
    std::int16_t* d = disparity.row(y);
    masks(d, nullptr, width_, range_x16_, valid_.data(), left_.data(), up_.data());
    find_runs(*cur);
    for (int i = 0; i < cur->count; ++i, ++id) {
      if (-node[find(id)] < min_size_) {
        std::fill(d + cur->begin[i], d + cur->end[i], kInvalidDisparity);
      }
    }
  }
}

}  // namespace epipole::vision

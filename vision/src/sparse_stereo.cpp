#include "epipole/vision/sparse_stereo.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>

#include "descriptor_search.hpp"
#include "epipole/core/error.hpp"
#include "kernel_set.hpp"
#include "sparse_stereo_kernels.hpp"

namespace epipole::vision {

namespace kernels {

void hamming_ref(const std::uint8_t* query, const std::uint8_t* candidates, int n,
                 std::uint16_t* distances) {
  constexpr int kBytes = SparseStereoMatcher::kDescriptorBytes;
  for (int i = 0; i < n; ++i) {
    int bits = 0;
    for (int b = 0; b < kBytes; ++b) {
      bits += std::popcount(static_cast<unsigned>(query[b] ^ candidates[i * kBytes + b]));
    }
    distances[i] = static_cast<std::uint16_t>(bits);
  }
}

HammingKernel* hamming_kernel(SimdPath path) {
  return KernelSet<HammingKernel>{hamming_ref, hamming_neon, nullptr}.pick(path);
}

void box5_row_ref(const std::uint8_t* const* rows, int width, std::uint16_t* out) {
  for (int x = 2; x < width - 2; ++x) {
    int sum = 0;
    for (int r = 0; r < 5; ++r) {
      for (int dx = -2; dx <= 2; ++dx) sum += rows[r][x + dx];
    }
    out[x] = static_cast<std::uint16_t>(sum);
  }
}

Box5RowKernel* box5_row_kernel(SimdPath path) {
  return KernelSet<Box5RowKernel>{box5_row_ref, box5_row_neon, nullptr}.pick(path);
}

}  // namespace kernels

namespace {

constexpr int kBits = SparseStereoMatcher::kDescriptorBytes * 8;
constexpr int kBoxRadius = 2;
constexpr int kSadRadius = 3;
constexpr int kSadSearch = 2;       // sub-pixel: SAD at d - 2 .. d + 2
constexpr int kNoSad = 0x7FFFFFFF;  // a window outside the image

template <typename T>
std::size_t bytes_of(const std::vector<T>& v) {
  return v.size() * sizeof(T);
}

}  // namespace

SparseStereoMatcher::SparseStereoMatcher(const SparseStereoConfig& config, SimdPath path)
    : config_(config), path_(path) {
  const int W = config.width;
  const int H = config.height;
  require(W > 2 * kBorder && H > 2 * kBorder && W <= 32767 && H <= 32767, "image size ", W, "x", H,
          " is outside ", 2 * kBorder + 1, "x", 2 * kBorder + 1, "..32767x32767 for sparse stereo");
  require(config.max_disparity >= 1 && config.max_disparity < W, "disparity range ",
          config.max_disparity, " must be in 1..", W - 1, " (smaller than the image width)");
  require(config.row_tolerance >= 0 && config.row_tolerance <= 16, "row tolerance ",
          config.row_tolerance, " must be in 0..16 rows");
  require(config.ratio >= 1 && config.ratio <= 100, "ratio ", config.ratio,
          " must be in 1..100 percent");
  require(config.max_distance >= 0 && config.max_distance <= kBits, "maximum distance ",
          config.max_distance, " must be in 0..", kBits);
  require(config.max_corners >= 1 && config.max_corners <= 1'000'000, "maximum corners ",
          config.max_corners, " must be in 1..1000000");
  require(config.max_matches >= 1 && config.max_matches <= 1'000'000, "maximum matches ",
          config.max_matches, " must be in 1..1000000");
  require(
      config.band_rows == 0 || (config.band_rows >= config.row_tolerance && config.band_rows <= 64),
      "band rows ", config.band_rows, " must be 0 or in ", config.row_tolerance, "..64");
  require(simd_path_available(path), "kernel path ", to_string(path),
          " is not available on this CPU");

  // The test pattern: points (x, y) with x and y in -12..12, each the sum of two uniform draws
  // in -6..6 from a fixed linear congruential generator, so every build has the same
  // descriptor; kept as offsets in the box sums, y * W + x.
  pattern_.resize(2 * kBits);
  std::uint32_t state = 0x2545F491u;
  const auto draw = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<int>((state >> 16) % 13u) - 6;
  };
  for (std::int32_t& offset : pattern_) {
    const int x = draw() + draw();
    const int y = draw() + draw();
    offset = y * W + x;
  }

  const auto pixels = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  const auto corners = static_cast<std::size_t>(config.max_corners);
  distances_.assign(corners, 0);
  for (Side* side : {&left_, &right_}) {
    side->box.assign(pixels, 0);
    side->descriptors.assign(corners * kDescriptorBytes, 0);
    side->x.assign(corners, 0);
    side->y.assign(corners, 0);
    side->row_start.assign(static_cast<std::size_t>(H) + 1, 0);
    side->order.assign(corners, 0);
    side->partner.assign(corners, -2);
  }
  matches_.resize(static_cast<std::size_t>(config.max_matches));
  if (config.band_rows > 0) band_matches_.resize(matches_.size());
}

std::size_t SparseStereoMatcher::working_set_bytes() const {
  std::size_t n =
      bytes_of(pattern_) + bytes_of(distances_) + bytes_of(matches_) + bytes_of(band_matches_);
  for (const Side* side : {&left_, &right_}) {
    n += bytes_of(side->box) + bytes_of(side->descriptors) + bytes_of(side->x) + bytes_of(side->y) +
         bytes_of(side->row_start) + bytes_of(side->order) + bytes_of(side->partner);
  }
  return n;
}

// The 5x5 box sums of the image (interior pixels only), the corners sorted by (y, x) with
// their descriptors, and the first corner of each row.
void SparseStereoMatcher::prepare(Side& side, GrayView image, std::span<const Corner> corners) {
  const int W = config_.width;
  const int H = config_.height;
  kernels::Box5RowKernel* const box5_row = kernels::box5_row_kernel(path_);
  for (int y = kBoxRadius; y < H - kBoxRadius; ++y) {
    const std::uint8_t* rows[2 * kBoxRadius + 1];
    for (int i = 0; i <= 2 * kBoxRadius; ++i) rows[i] = image.row(y - kBoxRadius + i);
    box5_row(rows, W, side.box.data() + static_cast<std::ptrdiff_t>(y) * W);
  }

  // Corners with a descriptor, at most max_corners, sorted by (y, x).
  int n = 0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Corner& c = corners[i];
    require(c.x >= 0 && c.y >= 0 && c.x < W && c.y < H, "corner (", c.x, ", ", c.y,
            ") is outside the ", W, "x", H, " image");
    if (c.x < kBorder || c.y < kBorder || c.x >= W - kBorder || c.y >= H - kBorder) continue;
    if (n == config_.max_corners) {
      truncated_ = true;
      continue;
    }
    side.order[static_cast<std::size_t>(n++)] = static_cast<std::uint32_t>(i);
  }
  std::sort(side.order.begin(), side.order.begin() + n, [&](std::uint32_t a, std::uint32_t b) {
    return corners[a].y != corners[b].y
               ? corners[a].y < corners[b].y
               : (corners[a].x != corners[b].x ? corners[a].x < corners[b].x : a < b);
  });
  side.count = n;
  std::fill(side.row_start.begin(), side.row_start.end(), 0u);
  for (int k = 0; k < n; ++k) {
    const Corner& c = corners[side.order[static_cast<std::size_t>(k)]];
    side.x[static_cast<std::size_t>(k)] = static_cast<std::int16_t>(c.x);
    side.y[static_cast<std::size_t>(k)] = static_cast<std::int16_t>(c.y);
    ++side.row_start[static_cast<std::size_t>(c.y) + 1];
    std::uint8_t* d = side.descriptors.data() + static_cast<std::ptrdiff_t>(k) * kDescriptorBytes;
    const std::uint16_t* centre = side.box.data() + static_cast<std::ptrdiff_t>(c.y) * W + c.x;
    const std::int32_t* o = pattern_.data();
    for (int byte = 0; byte < kDescriptorBytes; ++byte) {
      unsigned bits = 0;
      for (int b = 0; b < 8; ++b, o += 2) bits |= (centre[o[0]] < centre[o[1]] ? 1u : 0u) << b;
      d[byte] = static_cast<std::uint8_t>(bits);
    }
    side.partner[static_cast<std::size_t>(k)] = -2;
  }
  for (int y = 0; y < H; ++y) {
    side.row_start[static_cast<std::size_t>(y) + 1] += side.row_start[static_cast<std::size_t>(y)];
  }
}

// The best corner of `to` for corner i of `from`: on rows y +- row_tolerance, at x - d for the
// left image's corners (direction +1) or x + d for the right image's (-1).
SparseStereoMatcher::Best SparseStereoMatcher::best_match(const Side& from, int i, const Side& to,
                                                          int direction) {
  const auto ui = static_cast<std::size_t>(i);
  const int x = from.x[ui];
  const int y = from.y[ui];
  const int lo = direction > 0 ? x - config_.max_disparity + 1 : x;
  const int hi = direction > 0 ? x : x + config_.max_disparity - 1;
  const std::uint8_t* query = from.descriptors.data() + ui * kDescriptorBytes;
  const NearestDescriptor nearest =
      nearest_descriptor(query, to.x, to.row_start, to.descriptors.data(), y - tolerance_,
                         y + tolerance_, lo, hi, kernels::hamming_kernel(path_), distances_.data());
  Best result;
  result.index = nearest.index;
  result.distance = nearest.distance;
  result.ok = nearest.passes(config_.max_distance, config_.ratio);
  return result;
}

// The best corner of `to` for corner i of `from`, when it passes both tests; -1 otherwise.
int SparseStereoMatcher::partner_of(Side& from, int i, const Side& to, int direction) {
  std::int32_t& p = from.partner[static_cast<std::size_t>(i)];
  if (p == -2) {
    const Best b = best_match(from, i, to, direction);
    p = b.ok ? b.index : -1;
  }
  return p;
}

// Sub-pixel disparity from the SAD of 7x7 windows around the corners' difference.
float SparseStereoMatcher::refine(GrayView left, GrayView right, int xl, int yl, int xr,
                                  int yr) const {
  const int d = xl - xr;
  int sad[2 * kSadSearch + 1];
  for (int k = -kSadSearch; k <= kSadSearch; ++k) {
    const int x = xl - (d + k);  // the right window's centre
    if (x - kSadRadius < 0 || x + kSadRadius >= config_.width || d + k < 0) {
      sad[k + kSadSearch] = kNoSad;
      continue;
    }
    int s = 0;
    for (int j = -kSadRadius; j <= kSadRadius; ++j) {
      const std::uint8_t* a = left.row(yl + j) + xl;
      const std::uint8_t* b = right.row(yr + j) + x;
      for (int i = -kSadRadius; i <= kSadRadius; ++i) s += std::abs(a[i] - b[i]);
    }
    sad[k + kSadSearch] = s;
  }
  int m = 0;
  for (int k = 1; k <= 2 * kSadSearch; ++k) {
    if (sad[k] < sad[m]) m = k;
  }
  // No parabola at either end of the search or next to a window outside the image: the
  // corners' own difference.
  if (m == 0 || m == 2 * kSadSearch || sad[m - 1] == kNoSad || sad[m + 1] == kNoSad) {
    return static_cast<float>(d);
  }
  const int below = sad[m - 1];
  const int at = sad[m];
  const int above = sad[m + 1];
  const int denom = below + above - 2 * at;
  const float offset =
      denom > 0 ? static_cast<float>(below - above) / static_cast<float>(2 * denom) : 0.0f;
  return static_cast<float>(d + m - kSadSearch) + offset;
}

std::span<const SparseMatch> SparseStereoMatcher::match(GrayView left,
                                                        std::span<const Corner> left_corners,
                                                        GrayView right,
                                                        std::span<const Corner> right_corners) {
  require(same_size(left, right), "left image ", left.width(), "x", left.height(),
          " and right image ", right.width(), "x", right.height(), " differ in size");
  require(left.width() == config_.width && left.height() == config_.height, "images are ",
          left.width(), "x", left.height(), " but the sparse matcher is configured for ",
          config_.width, "x", config_.height);
  truncated_ = false;
  prepare(left_, left, left_corners);
  prepare(right_, right, right_corners);
  match_count_ = collect(left, right, config_.row_tolerance, matches_, /*refine_disparity=*/true);
  return {matches_.data(), static_cast<std::size_t>(match_count_)};
}

std::span<const SparseMatch> SparseStereoMatcher::match_band(GrayView left, GrayView right) {
  require(config_.band_rows > 0, "the sparse matcher has no band (band_rows 0)");
  require(
      same_size(left, right) && left.width() == config_.width && left.height() == config_.height,
      "images are not the sparse matcher's ", config_.width, "x", config_.height);
  for (Side* side : {&left_, &right_}) {
    std::fill_n(side->partner.begin(), side->count, -2);
  }
  const int n = collect(left, right, config_.band_rows, band_matches_, /*refine_disparity=*/false);
  return {band_matches_.data(), static_cast<std::size_t>(n)};
}

int SparseStereoMatcher::collect(GrayView left, GrayView right, int tolerance,
                                 std::vector<SparseMatch>& out, bool refine_disparity) {
  tolerance_ = tolerance;
  int count = 0;
  for (int i = 0; i < left_.count; ++i) {
    const int j = partner_of(left_, i, right_, 1);
    if (j < 0 || partner_of(right_, j, left_, -1) != i) continue;
    if (count == config_.max_matches) {
      truncated_ = true;
      break;
    }
    const auto ui = static_cast<std::size_t>(i);
    const auto uj = static_cast<std::size_t>(j);
    const int xl = left_.x[ui];
    const int yl = left_.y[ui];
    const int xr = right_.x[uj];
    const int yr = right_.y[uj];
    SparseMatch& m = out[static_cast<std::size_t>(count++)];
    m.xl = static_cast<float>(xl);
    m.yl = static_cast<float>(yl);
    m.disparity =
        refine_disparity ? refine(left, right, xl, yl, xr, yr) : static_cast<float>(xl - xr);
    m.xr = m.xl - m.disparity;
    m.yr = static_cast<float>(yr);
    kernels::hamming_ref(left_.descriptors.data() + ui * kDescriptorBytes,
                         right_.descriptors.data() + uj * kDescriptorBytes, 1, distances_.data());
    m.distance = distances_[0];
    m.left_feature = i;
  }
  return count;
}

DescribedCorners SparseStereoMatcher::left_features() const {
  const auto n = static_cast<std::size_t>(left_.count);
  return {std::span(left_.x).first(n), std::span(left_.y).first(n), std::span(left_.row_start),
          std::span(left_.descriptors).first(n * kDescriptorBytes)};
}

}  // namespace epipole::vision

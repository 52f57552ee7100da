#include "epipole/vision/window_matcher.hpp"

#include <algorithm>
#include <cmath>

#include "descriptor_search.hpp"
#include "epipole/core/error.hpp"
#include "sparse_stereo_kernels.hpp"

namespace epipole::vision {

namespace {

constexpr int kDescriptorBits = SparseStereoMatcher::kDescriptorBytes * 8;

}  // namespace

WindowMatcher::WindowMatcher(const WindowMatchConfig& config, SimdPath path)
    : config_(config), path_(path) {
  require(config.width > 0 && config.height > 0, "window matcher: the image's size must be set");
  require(config.max_queries >= 1 && config.max_queries <= 100000,
          "window matcher: max_queries must be 1..100000");
  require(config.max_corners >= 1 && config.max_corners <= 100000,
          "window matcher: max_corners must be 1..100000");
  require(config.radius >= 1 && config.radius <= 256, "window matcher: radius must be 1..256");
  require(config.max_distance >= 0 && config.max_distance <= kDescriptorBits,
          "window matcher: max_distance must be 0..256");
  require(config.ratio >= 1 && config.ratio <= 100, "window matcher: ratio must be 1..100");
  distances_.resize(static_cast<std::size_t>(config.max_corners));
  holder_.resize(static_cast<std::size_t>(config.max_corners));
  chosen_.resize(static_cast<std::size_t>(config.max_queries));
  distance_.resize(static_cast<std::size_t>(config.max_queries));
  matches_.resize(static_cast<std::size_t>(config.max_queries));
}

std::size_t WindowMatcher::working_set_bytes() const {
  return sizeof(*this) + distances_.capacity() * 2 + holder_.capacity() * 4 +
         chosen_.capacity() * 4 + distance_.capacity() * 4 +
         matches_.capacity() * sizeof(WindowMatch);
}

std::span<const WindowMatch> WindowMatcher::match(std::span<const std::uint8_t> descriptors,
                                                  std::span<const float> x,
                                                  std::span<const float> y,
                                                  const DescribedCorners& corners) {
  constexpr std::size_t kBytes = SparseStereoMatcher::kDescriptorBytes;
  const std::size_t queries = x.size();
  require(y.size() == queries && descriptors.size() == queries * kBytes,
          "window matcher: ", queries, " places but ", y.size(), " rows and ",
          descriptors.size() / kBytes, " descriptors");
  require(queries <= chosen_.size(), "window matcher: ", queries,
          " queries, more than max_queries (", chosen_.size(), ")");
  const auto count = static_cast<std::size_t>(corners.count());
  require(count <= holder_.size(), "window matcher: ", count, " corners, more than max_corners (",
          holder_.size(), ")");
  require(corners.row_start.size() == static_cast<std::size_t>(config_.height) + 1 &&
              corners.descriptors.size() == count * kBytes && corners.y.size() == count,
          "window matcher: corners of another image size or without their descriptors");
  std::fill_n(holder_.begin(), count, -1);
  kernels::HammingKernel* const hamming = kernels::hamming_kernel(path_);
  const int r = config_.radius;
  for (std::size_t q = 0; q < queries; ++q) {
    chosen_[q] = -1;
    // Off the image (or not a number): nothing to find; checked before rounding.
    if (!(x[q] > -0.5f && x[q] < static_cast<float>(config_.width) - 0.5f && y[q] > -0.5f &&
          y[q] < static_cast<float>(config_.height) - 0.5f)) {
      continue;
    }
    const int cx = static_cast<int>(std::lround(x[q]));
    const int cy = static_cast<int>(std::lround(y[q]));
    const std::uint8_t* query = descriptors.data() + q * kBytes;
    const NearestDescriptor nearest =
        nearest_descriptor(query, corners.x, corners.row_start, corners.descriptors.data(), cy - r,
                           cy + r, cx - r, cx + r, hamming, distances_.data());
    if (!nearest.passes(config_.max_distance, config_.ratio)) continue;
    const int best = nearest.index, best_distance = nearest.distance;
    std::int32_t& holder = holder_[static_cast<std::size_t>(best)];
    if (holder >= 0) {
      if (distance_[static_cast<std::size_t>(holder)] <= best_distance) continue;
      chosen_[static_cast<std::size_t>(holder)] = -1;  // the nearer query takes it
    }
    holder = static_cast<std::int32_t>(q);
    chosen_[q] = best;
    distance_[q] = best_distance;
  }
  std::size_t n = 0;
  for (std::size_t q = 0; q < queries; ++q) {
    if (chosen_[q] < 0) continue;
    matches_[n++] = {static_cast<int>(q), chosen_[q], distance_[q]};
  }
  return std::span(matches_).first(n);
}

}  // namespace epipole::vision

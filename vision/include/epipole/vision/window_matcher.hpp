#pragma once

// Features of one image found again in a later one, as the odometry follows them from pair to
// pair: each query (a descriptor where the feature is expected to be) takes the corner of the
// later image, within a square window around that place, whose descriptor is nearest in Hamming
// distance; by the sparse stereo's tests (the nearest below max_distance, and below ratio % of
// the second nearest). A corner two queries take goes to the nearer (the first among equals:
// give the most distinctive first); the other finds nothing (its second candidate failed the
// ratio test already).
#include <cstdint>
#include <span>
#include <vector>

#include "epipole/core/simd.hpp"
#include "epipole/vision/sparse_stereo.hpp"

namespace epipole::vision {

struct WindowMatchConfig {
  int width = 0, height = 0;  // the later image's
  int max_queries = 2000;     // match() takes at most this many
  int max_corners = 4000;     // of the later image
  int radius = 32;            // the window: the expected place +- radius pixels, 1..256
  int max_distance = 64;      // Hamming distance of the 256-bit descriptors, 0..256
  int ratio = 80;             // percent, 1..100
};

struct WindowMatch {
  int query = 0;   // its index among the queries
  int corner = 0;  // the later image's corner's index (DescribedCorners order)
  int distance = 0;
};

// Fixed memory: the constructor allocates; match() never does.
class WindowMatcher {
 public:
  // Throws Error for a configuration out of range.
  explicit WindowMatcher(const WindowMatchConfig& config, SimdPath path = best_simd_path());

  // `descriptors`: SparseStereoMatcher::kDescriptorBytes per query; x, y: where each is expected
  // in the later image (a query outside it, or not finite, finds nothing). The matches in query
  // order; the span stays valid until the next call. Throws Error for more queries or corners
  // than configured, or spans of different lengths.
  std::span<const WindowMatch> match(std::span<const std::uint8_t> descriptors,
                                     std::span<const float> x, std::span<const float> y,
                                     const DescribedCorners& corners);

  const WindowMatchConfig& config() const { return config_; }
  SimdPath simd_path() const { return path_; }
  std::size_t working_set_bytes() const;

 private:
  WindowMatchConfig config_;
  SimdPath path_;
  std::vector<std::uint16_t> distances_;  // one row's candidates
  std::vector<std::int32_t> holder_;      // per corner: the query holding it, -1 none
  std::vector<std::int32_t> chosen_;      // per query: its corner, -1 none
  std::vector<std::int32_t> distance_;    // per query: the chosen corner's distance
  std::vector<WindowMatch> matches_;
};

}  // namespace epipole::vision

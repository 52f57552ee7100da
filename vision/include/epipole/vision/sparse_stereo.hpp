#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/vision/corner.hpp"

namespace epipole::vision {

struct SparseStereoConfig {
  int width = 0;
  int height = 0;
  int max_disparity = 64;  // disparities 0..max_disparity-1 (1..width-1)
  int row_tolerance = 1;   // candidates on rows y - t .. y + t of the other image (0..16)
  int ratio = 80;          // percent (1..100): best distance * 100 < ratio * second best
  int max_distance = 64;   // Hamming distance of the 256-bit descriptors (0..256)
  int max_corners = 4000;  // per image; corners beyond are ignored (truncated())
  int max_matches = 2000;  // the output's bound (truncated())
  int band_rows = 0;       // match_band()'s rows, 0 (none) or row_tolerance..64
};

// A match of a left corner with a right corner of a rectified pair. disparity = xl - xr, with
// sub-pixel refinement along the row; yr is the right corner's row.
struct SparseMatch {
  float xl = 0, yl = 0;
  float xr = 0, yr = 0;
  float disparity = 0;
  int distance = 0;       // Hamming distance of the descriptors
  int left_feature = -1;  // the left corner's index in SparseStereoMatcher::left_features()
};

// Corners with their descriptors, sorted by (y, x): row_start[y] is the first corner of row y
// (height + 1 entries); kDescriptorBytes bytes of descriptor each, in the same order.
struct DescribedCorners {
  std::span<const std::int16_t> x, y;
  std::span<const std::uint32_t> row_start;
  std::span<const std::uint8_t> descriptors;
  int count() const { return static_cast<int>(x.size()); }
};

// Sparse stereo: matches the corners of the left and right rectified images along the rows.
//
// - Descriptor: 256 bits, each the comparison of two points of a 25x25 patch around the corner
//   (a fixed pattern, sampled from a triangular distribution), on the image smoothed by a 5x5
//   box; corners closer than kBorder to the image border have none and are skipped.
// - Candidates: the right corners on rows y - row_tolerance .. y + row_tolerance with
//   disparity xl - xr in 0..max_disparity-1; the smallest Hamming distance wins (the first in
//   (row, column) order among equals). Ratio test: best * 100 < ratio * second best (a lone
//   candidate passes); best <= max_distance. Left-right check: the right corner's own best
//   left corner (the same search the other way, also passing both tests) must be this one.
// - Sub-pixel: the SAD of 7x7 windows (left at the corner, right on the right corner's row) at
//   disparities d - 2 .. d + 2 around the corners' difference d; a parabola through the
//   smallest SAD and its two neighbours (none when it is at either end).
//
// Fixed memory: everything is allocated by the constructor; match() never allocates. See
// working_set_bytes() and docs/vision.md for the formula.
class SparseStereoMatcher {
 public:
  static constexpr int kPatchRadius = 12;
  static constexpr int kBorder = kPatchRadius + 2;  // + the box's radius
  static constexpr int kDescriptorBytes = 32;

  explicit SparseStereoMatcher(const SparseStereoConfig& config, SimdPath path = best_simd_path());

  // The matches, in (row, column) order of their left corners. The span stays valid until
  // the next call. Throws Error if an image differs from the configured size or a corner lies
  // outside its image.
  std::span<const SparseMatch> match(GrayView left, std::span<const Corner> left_corners,
                                     GrayView right, std::span<const Corner> right_corners);

  // After match(): the same corners matched again, on rows y - band_rows .. y + band_rows (wider
  // than row_tolerance: a drifted rig's matches are rows apart), by the same tests; xr and yr are
  // the right corner's (whole pixels: their sub-pixel place is the caller's to measure,
  // vision::align_patch). The span stays valid until the next call; match()'s stays valid too.
  // Throws Error when band_rows is 0.
  std::span<const SparseMatch> match_band(GrayView left, GrayView right);

  // After match(): the left corners that have a descriptor (those kBorder or more inside the
  // image), as it prepared them; valid until the next match(). What the odometry follows from
  // pair to pair (vision::WindowMatcher).
  DescribedCorners left_features() const;

  // True when the last call ignored corners beyond max_corners or matches beyond max_matches.
  bool truncated() const { return truncated_; }
  std::size_t working_set_bytes() const;
  const SparseStereoConfig& config() const { return config_; }
  SimdPath simd_path() const { return path_; }

 private:
  struct Side {
    std::vector<std::uint16_t> box;         // the 5x5 box sums, W x H
    std::vector<std::uint8_t> descriptors;  // kDescriptorBytes per corner, in sorted order
    std::vector<std::int16_t> x, y;         // corner positions, sorted by (y, x)
    std::vector<std::uint32_t> row_start;   // first corner of each row (H + 1)
    std::vector<std::uint32_t> order;       // sorting scratch
    std::vector<std::int32_t> partner;      // best partner in the other image, -2 unknown
    int count = 0;
  };
  struct Best {
    int index = -1;
    int distance = 0;
    bool ok = false;  // ratio test and max_distance passed
  };

  void prepare(Side& side, GrayView image, std::span<const Corner> corners);
  Best best_match(const Side& from, int i, const Side& to, int direction);
  int partner_of(Side& from, int i, const Side& to, int direction);
  float refine(GrayView left, GrayView right, int xl, int yl, int xr, int yr) const;
  // The left corners' mutual best matches on rows +-tolerance, into `out`: their count.
  int collect(GrayView left, GrayView right, int tolerance, std::vector<SparseMatch>& out,
              bool refine_disparity);

  SparseStereoConfig config_;
  SimdPath path_;
  std::vector<std::int32_t> pattern_;  // per bit, 2 points as offsets in the box sums
  std::vector<std::uint16_t> distances_;
  Side left_, right_;
  std::vector<SparseMatch> matches_;
  std::vector<SparseMatch> band_matches_;
  int tolerance_ = 0;  // best_match()'s rows either side
  int match_count_ = 0;
  bool truncated_ = false;
};

}  // namespace epipole::vision

#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/vision/disparity_filters.hpp"
#include "epipole/vision/speckle_filter.hpp"

namespace epipole::vision {

// The value of a pixel without a disparity in StereoMatcher's output (disparity x16), as
// OpenCV's matchers write it for minDisparity 0: -16, i.e. -1 pixel.
constexpr std::int16_t kInvalidDisparity = -16;
constexpr int kDisparityScale = 16;  // output = disparity * 16 (4 fractional bits)

enum class StereoMethod {
  sgm,  // quality: census cost, semi-global aggregation over 5 paths
  bm,   // fast: sparse census cost (16 of the 31 comparisons), box aggregation
};

struct StereoConfig {
  int width = 0;
  int height = 0;
  int max_disparity = 64;  // disparities 0..max_disparity-1; 16..256, a multiple of 16
  StereoMethod method = StereoMethod::sgm;
  int p1 = 11;                   // SGM: penalty for a disparity change of 1 (census cost units)
  int p2 = 120;                  // SGM: penalty for larger changes (p1..224)
  int block_size = 7;            // BM: box of block_size x block_size census costs (odd, 3..21)
  int uniqueness = 10;           // percent: another disparity (not +-1) must cost this much more
  int lr_max_diff = 1;           // left-right check tolerance in pixels; < 0 switches it off
  int speckle_size = 100;        // connected regions smaller than this are invalidated; 0: off
  int speckle_range = 1;         // in pixels: neighbours closer than this belong to one region
  bool fill_occlusions = false;  // after the speckles: holes where the left-right check found
                                 // the right camera's view hidden take their background
  int spatial_percent = 0;    // after the speckles, along rows and columns (disparity_filters.hpp):
                              // a pixel's own weight, 1..99 (0: off)
  int spatial_max_step = 2;   // px: larger steps are edges, kept (1..7)
  int spatial_passes = 2;     // 1..4
  int hole_fill = 0;          // then holes up to this long filled (disparity_filters.hpp)
  int temporal_percent = 0;   // then over time: the new pair's weight, 1..99 (0: off)
  int temporal_max_step = 2;  // px: larger changes are taken at once (1..7)
  bool confidence = false;    // also a confidence per pixel (StereoMatcher::confidence())
  int threads = 1;            // row stripes, and the workers that may run them at once
};

// Dense disparity of a rectified pair (left image is the reference; a left pixel x matches the
// right pixel x - d). Cost: 9x7 centre-symmetric census (31 bits; block matching a checkerboard
// of 16 of them) with Hamming distance.
// Quality mode: semi-global aggregation along 5 paths (left, right, top, top-left, top-right),
// all in one top-down pass, so no cost volume is stored. Fast mode: box aggregation. Both: winner
// take all, parabolic sub-pixel, uniqueness ratio, left-right check (the fast mode's right
// winners from the left winners alone, as StereoBM's), speckle removal; on request a confidence
// per pixel from its cost curve.
//
// Fixed memory: everything is allocated by the constructor; compute() never allocates. See
// working_set_bytes() and docs/vision.md for the formula.
class StereoMatcher {
 public:
  // `pool`: the pool compute() runs the stripes on (it must outlive the matcher; its workers
  // must number at most config.threads); null: a pool of config.threads made here.
  explicit StereoMatcher(const StereoConfig& config, SimdPath path = best_simd_path(),
                         ThreadPool* pool = nullptr);
  ~StereoMatcher();
  StereoMatcher(const StereoMatcher&) = delete;
  StereoMatcher& operator=(const StereoMatcher&) = delete;

  // Disparity x16 of the left image (kInvalidDisparity where unknown). The view stays valid
  // until the next call. Throws Error if either image differs from the configured size.
  ImageView<const std::int16_t> compute(GrayView left, GrayView right);

  // compute() cut into tasks for a pool that runs other work beside: start() checks the images
  // and returns the number of stripes; run_stripe(i, worker) for each (at once on different
  // workers below config().threads); then finish() gives what compute() would. The images must
  // stay unchanged until finish().
  int start(GrayView left, GrayView right);
  void run_stripe(int stripe, int worker);
  ImageView<const std::int16_t> finish();

  // With config.confidence, after finish(): how clearly each pixel's disparity won, 1..255, from
  // the aggregated cost curve: 255 * (c2 - c1) / c2 with c1 the winner's cost and c2 the lowest
  // outside the winner +-1 (a margin ratio; uniqueness is the same test with a threshold). 0
  // where the disparity is invalid, and where a post-filter (hole filling) made it up rather
  // than measured it. Empty without config.confidence.
  ImageView<const std::uint8_t> confidence() const { return confidence_.view(); }
  // The temporal filter forgets the pairs before (the next one passes unfiltered): after a gap
  // in the sequence, such as a camera reopened or the stage turned off for a while.
  void reset_history();

  std::size_t working_set_bytes() const;
  const StereoConfig& config() const { return config_; }
  SimdPath simd_path() const { return path_; }

  struct Worker;  // per-thread row buffers (stereo.cpp)

 private:
  // Rows y0..y1 of the disparity of the pair start() was given.
  void sgm_stripe(Worker& w, int y0, int y1);
  void bm_stripe(Worker& w, int y0, int y1);

  void fill_occlusions();
  // Row y of the confidence, or null without config.confidence.
  std::uint8_t* confidence_row(int y) {
    return confidence_.empty() ? nullptr : confidence_.view().row(y);
  }

  StereoConfig config_;
  SimdPath path_;
  std::unique_ptr<ThreadPool> own_pool_;  // when the constructor was given none
  ThreadPool* pool_;
  GrayView left_, right_;  // the pair of the stripes in progress (start() .. finish())
  std::vector<std::unique_ptr<Worker>> workers_;
  std::vector<std::int16_t> padded_;          // the output with a border of one invalid pixel
  ImageView<std::int16_t> disparity_;         // the output: padded_ without its border
  std::unique_ptr<SpeckleFilter> speckles_;   // with config.speckle_size
  std::unique_ptr<SpatialFilter> spatial_;    // with config.spatial_percent
  std::unique_ptr<TemporalFilter> temporal_;  // with config.temporal_percent
  Image<std::uint8_t> confidence_;            // with config.confidence
};

}  // namespace epipole::vision

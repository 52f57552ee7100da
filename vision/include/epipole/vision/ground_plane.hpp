#pragma once

// The ground under a stereo rig, found in its dense disparity (x16, invalid below 0: stereo.hpp).
//
// A plane in front of a rectified pair has a disparity that is affine in the pixel:
// d(u, v) = a u + b v + c. For the ground, b > 0 (nearer, larger disparities lower in the image)
// and |a| is small beside b (a rolls with the rig). The finder:
//  1. accumulates the v-disparity: per image row, a histogram of the integer disparities (a
//     scalar kernel and NEON, ground_plane_kernels.hpp);
//  2. finds the ground's line in it, d = slope * (v - horizon), by a Hough transform: every
//     v-disparity cell with enough pixels votes, weighted by its count, for each admitted slope
//     (log-spaced) at the horizon row that line through it has; the accumulator's peak wins;
//  3. takes the pixels of a sparse grid whose disparity lies near that line (allowing for the
//     admitted roll) and fits d = a u + b v + c to them by RANSAC (three pixels a sample,
//     a deterministic seed and a fixed budget of iterations), then least squares on the
//     inliers, twice.
// The plane in metres is for the caller, through Q (the firmware's ground stage).
//
// Fixed memory: the constructor allocates everything; find() never allocates.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"

namespace epipole::vision {

struct GroundPlaneConfig {
  int width = 0;  // the disparity image
  int height = 0;
  int max_disparity = 64;  // v-disparity bins: integer disparities 1 .. max_disparity - 1
  // The lines the Hough transform admits, d = slope * (v - horizon): slopes in disparity pixels
  // per row (min_slope > 0), horizons in rows (they may lie outside the image).
  double min_slope = 0.01;
  double max_slope = 2.0;
  double min_horizon = -500;
  double max_horizon = 500;
  int slope_bins = 64;
  int horizon_bins = 256;
  // A v-disparity cell votes when at least this many pixels of its row have its disparity.
  int min_votes = 8;
  // What makes the measured disparities those of the geometry (0 at infinity): Q's disparity
  // offset, Q(3,3) / Q(3,2), when the rectified principal points differ (cx - cx'). The ground's
  // horizon is where the disparity plus this is 0; the fit returned is the measured one's.
  double disparity_offset = 0;
  // The principal point's column, and the largest |a| / b a plane may have (tan of the largest
  // roll): the band of candidates around the Hough line widens with it away from the centre.
  double centre_column = 0;
  double max_tilt = 0.58;
  // Candidates: one pixel in grid_step x grid_step whose disparity is within
  // band_px + band_share * d of the Hough line's d (and the roll's allowance).
  int grid_step = 6;
  double band_px = 2.0;
  double band_share = 0.08;
  // RANSAC: a pixel is an inlier within inlier_px of the plane's disparity.
  double inlier_px = 1.0;
  int iterations = 64;
  std::uint64_t seed = 0x9E3779B97F4A7C15ull;
  // A plane is found with at least this share of the grid's valid pixels as inliers, and at
  // most max_beyond_share of those where it lies in front of the rig seen beyond it (farther by
  // more than 2 inlier distances and 10 %): nothing is seen through the ground, but the plane of a
  // tilted board or table top has the room behind it.
  double min_inlier_share = 0.15;
  double max_beyond_share = 0.1;
};

struct GroundPlaneFit {
  bool found = false;
  double a = 0, b = 0, c = 0;  // d(u, v) = a u + b v + c, disparity pixels
  int inliers = 0;             // of the grid's pixels
  int candidates = 0;          // the grid's pixels near the Hough line
  int valid = 0;               // the grid's pixels with a valid disparity
  int beyond = 0;              // those seen beyond the plane
  // The Hough transform's line, d = slope * (v - horizon); votes 0: no line.
  double slope = 0, horizon = 0;
  std::uint64_t votes = 0;
};

class GroundPlaneFinder {
 public:
  // Throws Error for a bad configuration (sizes, ranges, max_disparity above 4096, a width
  // above 65535).
  GroundPlaneFinder(const GroundPlaneConfig& config, SimdPath path);

  const GroundPlaneFit& find(ImageView<const std::int16_t> disparity);

  // The last find()'s v-disparity: height rows of max_disparity counts.
  ImageView<const std::uint16_t> v_disparity() const;
  const GroundPlaneConfig& config() const { return config_; }
  std::size_t working_set_bytes() const;

 private:
  struct Candidate {
    float u, v, d;
  };
  struct Plane {
    double a = 0, b = 0, c = 0;
  };
  void accumulate(ImageView<const std::int16_t> disparity);
  void vote();
  void gather(ImageView<const std::int16_t> disparity);
  void fit();
  int count_beyond(ImageView<const std::int16_t> disparity, int& in_front) const;
  int count_inliers(const Plane& p) const;
  bool admitted(const Plane& p) const;
  bool least_squares(const Plane& around, double within, Plane& out) const;

  using RowKernel = void(const std::int16_t*, int, int, std::uint16_t*, std::uint16_t*);
  GroundPlaneConfig config_;
  RowKernel* row_kernel_;
  Image<std::uint16_t> v_disparity_;
  std::vector<std::uint16_t> scratch_;      // the kernel's partial histograms
  std::vector<double> inverse_slopes_;      // per slope bin
  std::vector<std::uint32_t> accumulator_;  // slope_bins x horizon_bins
  std::vector<Candidate> candidates_;       // the grid's pixels near the line
  int grid_pixels_ = 0;
  GroundPlaneFit fit_;
};

}  // namespace epipole::vision

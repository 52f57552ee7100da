#include "epipole/vision/ground_plane.hpp"

#include <algorithm>
#include <cmath>

#include "epipole/core/error.hpp"
#include "epipole/core/splitmix.hpp"
#include "ground_plane_kernels.hpp"
#include "kernel_set.hpp"

namespace epipole::vision {

namespace kernels {

void v_disparity_row_ref(const std::int16_t* row, int width, int bins, std::uint16_t* counts,
                         std::uint16_t* /*scratch*/) {
  std::fill_n(counts, bins, std::uint16_t{0});
  for (int x = 0; x < width; ++x) {
    const int d = row[x] >> 4;  // rounds down: -16 (invalid) is -1
    if (d >= 1 && d < bins) ++counts[d];
  }
}

}  // namespace kernels

namespace {

constexpr KernelSet<kernels::VDisparityRow> kRowKernels{kernels::v_disparity_row_ref,
                                                        kernels::v_disparity_row_neon, nullptr};

// Solves the 3x3 system m x = r by Cramer's rule; false when it is (nearly) singular.
bool solve3(const double m[3][3], const double r[3], double x[3]) {
  const auto det = [](const double a[3][3]) {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  };
  const double d = det(m);
  double scale = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) scale = std::max(scale, std::abs(m[i][j]));
  }
  if (!(std::abs(d) > 1e-12 * scale * scale * scale)) return false;
  for (int k = 0; k < 3; ++k) {
    double a[3][3];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) a[i][j] = j == k ? r[i] : m[i][j];
    }
    x[k] = det(a) / d;
  }
  return true;
}

}  // namespace

GroundPlaneFinder::GroundPlaneFinder(const GroundPlaneConfig& config, SimdPath path)
    : config_(config), row_kernel_(kRowKernels.pick(path)) {
  const GroundPlaneConfig& c = config;
  require(c.width > 0 && c.height > 0 && c.width <= 65535, "ground: image size ", c.width, "x",
          c.height, " is not within 1..65535 wide");
  require(c.max_disparity >= 2 && c.max_disparity <= 4096, "ground: ", c.max_disparity,
          " disparities is outside 2..4096");
  require(std::isfinite(c.min_slope) && std::isfinite(c.max_slope) && c.min_slope > 0 &&
              c.max_slope > c.min_slope,
          "ground: slopes ", c.min_slope, "..", c.max_slope, " are not a positive range");
  require(std::isfinite(c.min_horizon) && std::isfinite(c.max_horizon) &&
              c.max_horizon > c.min_horizon &&
              std::isfinite(c.horizon_bins / (c.max_horizon - c.min_horizon)),
          "ground: horizons ", c.min_horizon, "..", c.max_horizon, " are not a range");
  require(std::isfinite(c.disparity_offset), "ground: the disparity offset is not a number");
  require(
      c.slope_bins >= 2 && c.slope_bins <= 1024 && c.horizon_bins >= 2 && c.horizon_bins <= 4096,
      "ground: ", c.slope_bins, "x", c.horizon_bins, " Hough bins is outside 2..1024 x 2..4096");
  require(c.min_votes >= 1, "ground: min_votes ", c.min_votes, " is below 1");
  require(std::isfinite(c.centre_column) && std::isfinite(c.max_tilt) && c.max_tilt >= 0,
          "ground: the centre column and the tilt must be finite, the tilt not negative");
  require(c.grid_step >= 1 && c.grid_step <= 64, "ground: grid step ", c.grid_step,
          " is outside 1..64");
  require(c.band_px > 0 && c.band_share >= 0 && c.inlier_px > 0 && std::isfinite(c.band_px) &&
              std::isfinite(c.band_share) && std::isfinite(c.inlier_px),
          "ground: the band and the inlier distance must be positive");
  require(c.iterations >= 1 && c.iterations <= 100'000, "ground: ", c.iterations,
          " iterations is outside 1..100000");
  require(c.min_inlier_share >= 0 && c.min_inlier_share <= 1 && c.max_beyond_share >= 0 &&
              c.max_beyond_share <= 1,
          "ground: min_inlier_share ", c.min_inlier_share, " or max_beyond_share ",
          c.max_beyond_share, " is outside 0..1");
  v_disparity_ = Image<std::uint16_t>(c.max_disparity, c.height);
  scratch_.assign(static_cast<std::size_t>(kernels::kVDisparityLanes * c.max_disparity), 0);
  inverse_slopes_.resize(static_cast<std::size_t>(c.slope_bins));
  const double ratio = std::log(c.max_slope / c.min_slope) / (c.slope_bins - 1);
  for (int k = 0; k < c.slope_bins; ++k) {
    inverse_slopes_[static_cast<std::size_t>(k)] = 1.0 / (c.min_slope * std::exp(ratio * k));
  }
  accumulator_.assign(static_cast<std::size_t>(c.slope_bins) * c.horizon_bins, 0);
  const int columns = (c.width + c.grid_step - 1) / c.grid_step;
  const int rows = (c.height + c.grid_step - 1) / c.grid_step;
  grid_pixels_ = columns * rows;
  candidates_.resize(static_cast<std::size_t>(grid_pixels_));
}

std::size_t GroundPlaneFinder::working_set_bytes() const {
  return v_disparity_.size_bytes() + scratch_.size() * sizeof(std::uint16_t) +
         inverse_slopes_.size() * sizeof(double) + accumulator_.size() * sizeof(std::uint32_t) +
         candidates_.size() * sizeof(Candidate);
}

ImageView<const std::uint16_t> GroundPlaneFinder::v_disparity() const {
  return v_disparity_.view();
}

const GroundPlaneFit& GroundPlaneFinder::find(ImageView<const std::int16_t> disparity) {
  require(disparity.width() == config_.width && disparity.height() == config_.height,
          "ground: disparity image ", disparity.width(), "x", disparity.height(),
          " is not the configured ", config_.width, "x", config_.height);
  fit_ = GroundPlaneFit{};
  accumulate(disparity);
  vote();
  if (fit_.votes == 0) return fit_;
  gather(disparity);
  fit();
  if (fit_.found) {
    int in_front = 0;
    fit_.beyond = count_beyond(disparity, in_front);
    fit_.found = fit_.beyond <= config_.max_beyond_share * in_front;
  }
  return fit_;
}

void GroundPlaneFinder::accumulate(ImageView<const std::int16_t> disparity) {
  for (int y = 0; y < config_.height; ++y) {
    row_kernel_(disparity.row(y), config_.width, config_.max_disparity, v_disparity_.view().row(y),
                scratch_.data());
  }
}

// Each cell with enough pixels votes, with its count, for the line through its centre at each
// admitted slope; the peak is the line with the most pixels along it.
void GroundPlaneFinder::vote() {
  std::fill(accumulator_.begin(), accumulator_.end(), 0u);
  const int bins = config_.horizon_bins;
  const double per_bin = bins / (config_.max_horizon - config_.min_horizon);
  const std::size_t slopes = inverse_slopes_.size();
  for (int y = 0; y < config_.height; ++y) {
    const std::uint16_t* counts = v_disparity_.view().row(y);
    for (int d = 1; d < config_.max_disparity; ++d) {
      const std::uint32_t count = counts[d];
      if (count < static_cast<std::uint32_t>(config_.min_votes)) continue;
      const double centre = d + 0.5 + config_.disparity_offset;  // the bin holds d .. d + 1
      for (std::size_t k = 0; k < slopes; ++k) {
        const double horizon = (y - centre * inverse_slopes_[k] - config_.min_horizon) * per_bin;
        if (!(horizon >= 0 && horizon < bins)) continue;  // NaN too
        accumulator_[k * static_cast<std::size_t>(bins) + static_cast<std::size_t>(horizon)] +=
            count;
      }
    }
  }
  std::uint32_t best = 0;
  std::size_t best_k = 0, best_h = 0;
  for (std::size_t k = 0; k < slopes; ++k) {
    for (std::size_t h = 0; h < static_cast<std::size_t>(bins); ++h) {
      const std::uint32_t votes = accumulator_[k * static_cast<std::size_t>(bins) + h];
      if (votes > best) {
        best = votes;
        best_k = k;
        best_h = h;
      }
    }
  }
  fit_.votes = best;
  fit_.slope = 1.0 / inverse_slopes_[best_k];
  fit_.horizon = config_.min_horizon + (static_cast<double>(best_h) + 0.5) / per_bin;
}

// The grid's pixels whose disparity is near the Hough line, the band widening with the
// disparity (the line's bins are coarse) and away from the centre column (a rolled rig's ground
// leans across the image).
void GroundPlaneFinder::gather(ImageView<const std::int16_t> disparity) {
  const int step = config_.grid_step;
  const double tilt = fit_.slope * config_.max_tilt;
  std::size_t n = 0;
  int valid = 0;
  for (int y = step / 2; y < config_.height; y += step) {
    const double line = fit_.slope * (y - fit_.horizon);
    const std::int16_t* row = disparity.row(y);
    for (int x = step / 2; x < config_.width; x += step) {
      if (row[x] < 0) continue;
      ++valid;
      const double d = row[x] / 16.0 + config_.disparity_offset;
      const double band =
          config_.band_px + config_.band_share * line + tilt * std::abs(x - config_.centre_column);
      if (line <= 0 || std::abs(d - line) > band) continue;
      candidates_[n++] = {static_cast<float>(x), static_cast<float>(y), static_cast<float>(d)};
    }
  }
  fit_.valid = valid;
  fit_.candidates = static_cast<int>(n);
}

// The grid's valid pixels where the plane lies in front of the rig (its disparity positive),
// and of them those seen clearly beyond it.
int GroundPlaneFinder::count_beyond(ImageView<const std::int16_t> disparity, int& in_front) const {
  const int step = config_.grid_step;
  int beyond = 0;
  in_front = 0;
  for (int y = step / 2; y < config_.height; y += step) {
    const std::int16_t* row = disparity.row(y);
    for (int x = step / 2; x < config_.width; x += step) {
      const double plane = fit_.a * x + fit_.b * y + fit_.c + config_.disparity_offset;
      if (row[x] < 0 || plane <= 0) continue;
      ++in_front;
      const double d = row[x] / 16.0 + config_.disparity_offset;
      beyond += d < plane - 2 * config_.inlier_px - 0.1 * plane ? 1 : 0;
    }
  }
  return beyond;
}

int GroundPlaneFinder::count_inliers(const Plane& p) const {
  const auto n = static_cast<std::size_t>(fit_.candidates);
  const auto a = static_cast<float>(p.a), b = static_cast<float>(p.b), c = static_cast<float>(p.c);
  const auto within = static_cast<float>(config_.inlier_px);
  int inliers = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Candidate& q = candidates_[i];
    inliers += std::abs(a * q.u + b * q.v + c - q.d) <= within ? 1 : 0;
  }
  return inliers;
}

// A ground: lower is nearer, as steeply as the Hough transform admits, with its horizon where
// it admits, and it leans across the image no more than the roll
// admitted.
bool GroundPlaneFinder::admitted(const Plane& p) const {
  if (!(std::isfinite(p.a) && std::isfinite(p.b) && std::isfinite(p.c))) return false;
  if (p.b < config_.min_slope || p.b > config_.max_slope) return false;
  const double horizon = -(p.c + p.a * config_.centre_column) / p.b;
  return std::abs(p.a) <= p.b * config_.max_tilt && horizon >= config_.min_horizon &&
         horizon <= config_.max_horizon;
}

// The least-squares plane through the inliers of `around`, centred for conditioning.
bool GroundPlaneFinder::least_squares(const Plane& around, double within, Plane& out) const {
  const auto n = static_cast<std::size_t>(fit_.candidates);
  const double cu = config_.width / 2.0, cv = config_.height / 2.0;
  double m[3][3] = {};
  double r[3] = {};
  int used = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Candidate& q = candidates_[i];
    const auto u = static_cast<double>(q.u), v = static_cast<double>(q.v);
    const auto d = static_cast<double>(q.d);
    if (std::abs(around.a * u + around.b * v + around.c - d) > within) continue;
    const double row[3] = {u - cu, v - cv, 1.0};
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) m[j][k] += row[j] * row[k];
      r[j] += row[j] * d;
    }
    ++used;
  }
  double x[3];
  if (used < 3 || !solve3(m, r, x)) return false;
  out = {x[0], x[1], x[2] - x[0] * cu - x[1] * cv};
  return true;
}

void GroundPlaneFinder::fit() {
  const int n = fit_.candidates;
  if (n < 3) return;
  SplitMix64 random(config_.seed);
  Plane best;
  int best_inliers = 0;
  for (int i = 0; i < config_.iterations; ++i) {
    const Candidate* s[3];
    for (auto& pick : s) {
      pick = &candidates_[static_cast<std::size_t>(random.below(static_cast<unsigned>(n)))];
    }
    double m[3][3], r[3];
    for (int j = 0; j < 3; ++j) {
      m[j][0] = static_cast<double>(s[j]->u);
      m[j][1] = static_cast<double>(s[j]->v);
      m[j][2] = 1;
      r[j] = static_cast<double>(s[j]->d);
    }
    double x[3];
    if (!solve3(m, r, x)) continue;  // the same pixel twice, or three in a line
    const Plane p{x[0], x[1], x[2]};
    if (!admitted(p)) continue;
    const int inliers = count_inliers(p);
    if (inliers > best_inliers) {
      best_inliers = inliers;
      best = p;
    }
  }
  if (best_inliers < 3) return;
  // Least squares on the inliers, then again on those of the refined plane within half the
  // distance: what only touches the ground (a wall's foot, a box's) pulls it less. A refined
  // plane that is no ground says the sample was none either.
  for (const double within : {config_.inlier_px, config_.inlier_px / 2}) {
    if (!least_squares(best, within, best) || !admitted(best)) return;
  }
  fit_.a = best.a;
  fit_.b = best.b;
  fit_.c = best.c - config_.disparity_offset;  // the measured disparities' plane
  fit_.inliers = count_inliers(best);
  fit_.found = fit_.inliers >= 3 && fit_.inliers >= config_.min_inlier_share * fit_.valid;
}

}  // namespace epipole::vision

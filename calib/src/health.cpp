#include "epipole/calib/health.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "epipole/core/error.hpp"

namespace epipole::calib {

namespace {

// The p-quantile of values[0, n), linear between order statistics; reorders the values.
double quantile(float* values, int n, double p) {
  const double position = p * (n - 1);
  const int below = static_cast<int>(std::floor(position));
  const double t = position - below;
  std::nth_element(values, values + below, values + n);
  const double low = static_cast<double>(values[below]);
  if (t == 0 || below + 1 >= n) return low;
  // The next order statistic is the smallest value above position `below`.
  const double high = static_cast<double>(*std::min_element(values + below + 1, values + n));
  return low + t * (high - low);
}

}  // namespace

CalibrationHealth::CalibrationHealth(int max_matches) : capacity_(max_matches) {
  require(max_matches >= 1, "calibration health: max_matches ", max_matches, " must be >= 1");
  absolute_ = std::make_unique<float[]>(static_cast<std::size_t>(max_matches));
  signed_ = std::make_unique<float[]>(static_cast<std::size_t>(max_matches));
}

HealthFigure CalibrationHealth::measure(std::span<const RectifiedMatch> matches) {
  require(matches.size() <= static_cast<std::size_t>(capacity_),
          "calibration health: ", matches.size(), " matches, more than the ", capacity_,
          " it was sized for");
  int n = 0;
  for (const RectifiedMatch& m : matches) {
    const float offset = m.right_y - m.left_y;
    if (!std::isfinite(offset)) continue;
    signed_[static_cast<std::size_t>(n)] = offset;
    absolute_[static_cast<std::size_t>(n)] = std::abs(offset);
    ++n;
  }
  HealthFigure figure;
  figure.matches = n;
  if (n == 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    figure.median_px = figure.p90_px = figure.median_signed_px = nan;
    return figure;
  }
  figure.median_px = quantile(absolute_.get(), n, 0.5);
  figure.p90_px = quantile(absolute_.get(), n, 0.9);
  figure.median_signed_px = quantile(signed_.get(), n, 0.5);
  return figure;
}

}  // namespace epipole::calib

// The right camera's turn from the rows of its matches (drift_estimator.hpp).
//
// In the rectified frame the right camera sits at B = (b, 0, 0) from the left. A turn M of the
// right camera since the calibration shows a point X at the right ray r = M (X - B), its left
// ray being X. X, X - B and B are coplanar: (M^T r)^T [B]x X = 0, the epipolar constraint with
// E = M [B]x. With s = M^T r (the right ray turned back), it says s_y / s_z = y_l: the left row
// in normalised coordinates, whatever the depth. For a small turn w = (wx, wy, wz) the row
// offset is y_r - y_l = -wx (1 + y_r^2) + wz x_r + wy x_r y_r; yaw's term is second order
// (and shows as a depth bias instead), so pitch (wx) and roll (wz) are estimated.
#include "epipole/calib/drift_estimator.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "epipole/calib/camera_turn.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/resident.hpp"

namespace epipole::calib {

namespace {

// M = exp([w]x), w = (wx, 0, wz).
Eigen::Matrix3d turn_of(double wx, double wz) {
  const Eigen::Vector3d w(wx, 0, wz);
  const double angle = w.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// The median of values[0, n) (reorders them).
double median_of(std::span<double> values) {
  if (values.empty()) return 0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

DriftEstimator::DriftEstimator(const StereoCalibration& rig, const DriftEstimatorConfig& config)
    : config_(config), random_(config.seed) {
  require(config.window_pairs >= 3 && config.window_pairs <= 1000, "drift window of ",
          config.window_pairs, " pairs is outside 3..1000");
  require(config.pair_matches >= 8 && config.pair_matches <= 4096, "drift: ", config.pair_matches,
          " matches a pair is outside 8..4096");
  require(config.min_matches >= 2 && config.min_matches <= config.pair_matches,
          "drift: min_matches ", config.min_matches, " is outside 2..", config.pair_matches);
  require(config.iterations >= 1 && config.inlier_px > 0, "drift: RANSAC needs iterations and a ",
          "positive inlier distance");
  require(config.max_matches >= 1, "drift: max_matches must be positive");
  const auto window = static_cast<std::size_t>(config.window_pairs);
  window_.resize(window * static_cast<std::size_t>(config.pair_matches));
  window_use_.assign(window_.size(), 0);
  offsets_.assign(window_.size(), 0.0);
  slot_count_.assign(window, 0);
  slot_fit_.assign(window, PairFit{});
  reserve_resident(scratch_, static_cast<std::size_t>(config.max_matches));
  inlier_.assign(static_cast<std::size_t>(config.max_matches), 0);
  set_rig(rig);
}

void DriftEstimator::set_rig(const StereoCalibration& rig) {
  fx_ = rig.right.projection(0, 0);
  fy_ = rig.left.projection(1, 1);
  left_cy_ = rig.left.projection(1, 2);
  right_cx_ = rig.right.projection(0, 2);
  right_cy_ = rig.right.projection(1, 2);
  r2_ = rig.right.rectification;
  clear();
}

void DriftEstimator::clear() {
  std::fill(slot_count_.begin(), slot_count_.end(), 0);
  std::fill(window_use_.begin(), window_use_.end(), std::uint8_t{0});
  std::fill(slot_fit_.begin(), slot_fit_.end(), PairFit{});
  next_slot_ = 0;
}

std::size_t DriftEstimator::working_set_bytes() const {
  return scratch_.capacity() * sizeof(Observation) + inlier_.capacity() +
         window_.capacity() * sizeof(Observation) + window_use_.capacity() +
         offsets_.capacity() * sizeof(double) + slot_count_.capacity() * sizeof(int) +
         slot_fit_.capacity() * sizeof(PairFit);
}

double DriftEstimator::residual(const Eigen::Matrix3d& mt, const Observation& o) {
  const Eigen::Vector3d s = mt * Eigen::Vector3d(o.xr, o.yr, 1.0);
  return s.y() / s.z() - o.yl;
}

DriftEstimator::PairFit DriftEstimator::least_squares(std::span<const Observation> observations,
                                                      std::span<const std::uint8_t> use, double wx,
                                                      double wz) const {
  PairFit fit{wx, wz, false};
  for (int iteration = 0; iteration < 4; ++iteration) {
    const Eigen::Matrix3d mt = turn_of(fit.wx, fit.wz).transpose();
    Eigen::Matrix2d jtj = Eigen::Matrix2d::Zero();
    Eigen::Vector2d jte = Eigen::Vector2d::Zero();
    int n = 0;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (!use.empty() && use[i] == 0) continue;
      const Observation& o = observations[i];
      const Eigen::Vector3d s = mt * Eigen::Vector3d(o.xr, o.yr, 1.0);
      const double row = s.y() / s.z();
      // d(row)/d(delta) for M exp([delta]x), delta = (dx, 0, dz).
      const Eigen::Vector2d j(1 + row * row, -s.x() / s.z());
      jtj += j * j.transpose();
      jte += j * (row - o.yl);
      ++n;
    }
    if (n < 2 || std::abs(jtj.determinant()) < 1e-12) return fit;
    const Eigen::Vector2d delta = -jtj.ldlt().solve(jte);
    // M exp([delta]x) stays close to exp([w + delta]x) for the small turns estimated here.
    fit.wx += delta.x();
    fit.wz += delta.y();
    fit.valid = true;
    if (delta.norm() < 1e-9) break;
  }
  return fit;
}

DriftEstimator::PairFit DriftEstimator::fit_pair(std::span<const Observation> pair) {
  const auto n = pair.size();
  const double threshold = config_.inlier_px / fy_;
  // The small-turn model, linear in (wx, wz): y_r - y_l = -wx (1 + y_r^2) + wz x_r.
  const auto offset = [](const Observation& o, double wx, double wz) {
    return -wx * (1 + o.yr * o.yr) + wz * o.xr;
  };
  int best = 0;
  double best_wx = 0, best_wz = 0;
  for (int iteration = 0; iteration < config_.iterations; ++iteration) {
    const auto a = static_cast<std::size_t>(random_.below(n));
    const auto b = static_cast<std::size_t>(random_.below(n));
    if (a == b) continue;
    const Observation &p = pair[a], &q = pair[b];
    const double a11 = -(1 + p.yr * p.yr), a12 = p.xr;
    const double a21 = -(1 + q.yr * q.yr), a22 = q.xr;
    const double det = a11 * a22 - a12 * a21;
    if (std::abs(det) < 1e-4) continue;  // two matches in one column say nothing of roll
    const double dp = p.yr - p.yl, dq = q.yr - q.yl;
    const double wx = (dp * a22 - a12 * dq) / det;
    const double wz = (a11 * dq - a21 * dp) / det;
    int count = 0;
    for (const Observation& o : pair) {
      count += std::abs(o.yr - o.yl - offset(o, wx, wz)) < threshold ? 1 : 0;
    }
    if (count > best) {
      best = count;
      best_wx = wx;
      best_wz = wz;
    }
  }
  if (best < config_.min_matches) return {};
  for (std::size_t i = 0; i < n; ++i) {
    const Observation& o = pair[i];
    inlier_[i] = std::abs(o.yr - o.yl - offset(o, best_wx, best_wz)) < threshold;
  }
  return least_squares(pair, {inlier_.data(), n}, best_wx, best_wz);
}

int DriftEstimator::add_pair(std::span<const RectifiedMatch> matches) {
  require(matches.size() <= static_cast<std::size_t>(config_.max_matches),
          "drift: ", matches.size(), " matches, more than the ", config_.max_matches,
          " it was sized for");
  scratch_.clear();
  for (const RectifiedMatch& m : matches) {
    if (!std::isfinite(m.left_y) || !std::isfinite(m.right_x) || !std::isfinite(m.right_y)) {
      continue;
    }
    scratch_.push_back({(static_cast<double>(m.left_y) - left_cy_) / fy_,
                        (static_cast<double>(m.right_x) - right_cx_) / fx_,
                        (static_cast<double>(m.right_y) - right_cy_) / fy_});
  }
  const auto slot = static_cast<std::size_t>(next_slot_);
  const auto first = slot * static_cast<std::size_t>(config_.pair_matches);
  slot_count_[slot] = 0;
  slot_fit_[slot] = PairFit{};
  std::fill_n(window_use_.begin() + static_cast<std::ptrdiff_t>(first), config_.pair_matches,
              std::uint8_t{0});
  next_slot_ = (next_slot_ + 1) % config_.window_pairs;
  if (scratch_.size() < static_cast<std::size_t>(config_.min_matches)) return 0;
  const PairFit fit = fit_pair(scratch_);
  if (!fit.valid) return 0;
  // The inliers under the refined turn, kept evenly over the pair (its matches are in row order).
  const Eigen::Matrix3d mt = turn_of(fit.wx, fit.wz).transpose();
  const double threshold = config_.inlier_px / fy_;
  int inliers = 0;
  for (std::size_t i = 0; i < scratch_.size(); ++i) {
    const Observation& o = scratch_[i];
    inlier_[i] = std::abs(residual(mt, o)) < threshold;
    inliers += inlier_[i];
  }
  if (inliers < config_.min_matches) return 0;
  const int step = (inliers + config_.pair_matches - 1) / config_.pair_matches;
  int kept = 0, seen = 0;
  for (std::size_t i = 0; i < scratch_.size() && kept < config_.pair_matches; ++i) {
    if (inlier_[i] == 0 || seen++ % step != 0) continue;
    window_[first + static_cast<std::size_t>(kept)] = scratch_[i];
    window_use_[first + static_cast<std::size_t>(kept)] = 1;
    ++kept;
  }
  slot_count_[slot] = kept;
  slot_fit_[slot] = fit;
  return inliers;
}

DriftEstimate DriftEstimator::estimate() const {
  DriftEstimate e;
  double mean_wx = 0, mean_wz = 0;
  for (std::size_t slot = 0; slot < slot_fit_.size(); ++slot) {
    if (slot_count_[slot] == 0) continue;
    ++e.pairs;
    e.matches += slot_count_[slot];
    mean_wx += slot_fit_[slot].wx;
    mean_wz += slot_fit_[slot].wz;
  }
  if (e.pairs == 0) return e;
  mean_wx /= e.pairs;
  mean_wz /= e.pairs;
  double spread_wx = 0, spread_wz = 0;
  for (std::size_t slot = 0; slot < slot_fit_.size(); ++slot) {
    if (slot_count_[slot] == 0) continue;
    spread_wx += std::pow(slot_fit_[slot].wx - mean_wx, 2);
    spread_wz += std::pow(slot_fit_[slot].wz - mean_wz, 2);
  }
  const PairFit fit = least_squares(window_, window_use_, mean_wx, mean_wz);
  // The offsets, as measured and once the turn is undone (pixels).
  const Eigen::Matrix3d mt = turn_of(fit.wx, fit.wz).transpose();
  std::size_t n = 0;
  for (std::size_t i = 0; i < window_.size(); ++i) {
    if (window_use_[i] != 0) {
      offsets_[n++] = std::abs(window_[i].yr - window_[i].yl) * fy_;
    }
  }
  e.median_offset_px = median_of({offsets_.data(), n});
  n = 0;
  for (std::size_t i = 0; i < window_.size(); ++i) {
    if (window_use_[i] == 0) continue;
    offsets_[n++] = std::abs(residual(mt, window_[i])) * fy_;
  }
  e.median_corrected_px = median_of({offsets_.data(), n});
  // The rectified frame's turn M back into the right camera's frame: D = R2^T M^T R2.
  const Eigen::Matrix3d d = r2_.transpose() * mt * r2_;
  const CameraTurn turn = turn_angles(d);
  e.pitch = turn.pitch;
  e.roll = turn.roll;
  if (e.pairs >= 2) {
    e.pitch_sigma = std::sqrt(spread_wx / (e.pairs - 1) / e.pairs);
    e.roll_sigma = std::sqrt(spread_wz / (e.pairs - 1) / e.pairs);
  }
  e.valid = fit.valid && e.pairs >= 3;
  return e;
}

}  // namespace epipole::calib

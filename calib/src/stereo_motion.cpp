// The rig's motion between two pairs (stereo_motion.hpp).
//
// A match's point X (the earlier pair's left frame) is x = R X + t in the later pair's; its
// reprojections are (f x/z + left_cx, f y/z + cy) in the left image and
// (f (x - baseline)/z + right_cx, same row) in the right. The refinement perturbs the motion on
// the left, x' = exp([w]x) x + v, whose Jacobian at 0 is [-[x]x | I].
#include "epipole/calib/stereo_motion.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "epipole/core/error.hpp"

namespace epipole::calib {

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

Eigen::Matrix3d exp_rotation(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// A match's residuals (pixels) under a motion and their Jacobians: 2 in the left image, 1 more
// in the right when it was seen there (same row: its row residual is the left's).
struct Residuals {
  int count = 0;  // 0: the point is behind the later camera
  double r[3] = {0, 0, 0};
  Eigen::Matrix<double, 1, 3> d[3];  // by the point in the later frame
  Eigen::Vector3d x;
};

Residuals residuals(const RectifiedStereoCameras& c, const MotionMatch& m, const RigidMotion& mo) {
  Residuals out;
  out.x = mo.apply(m.point);
  const double z = out.x.z();
  if (!(z > 1e-6)) return out;
  const double iz = 1 / z, f = c.f;
  out.r[0] = f * out.x.x() * iz + c.left_cx - m.left_x;
  out.r[1] = f * out.x.y() * iz + c.cy - m.left_y;
  out.d[0] << f * iz, 0, -f * out.x.x() * iz * iz;
  out.d[1] << 0, f * iz, -f * out.x.y() * iz * iz;
  out.count = 2;
  if (std::isfinite(m.right_x)) {
    const double xr = out.x.x() - c.baseline;
    out.r[2] = f * xr * iz + c.right_cx - m.right_x;
    out.d[2] << f * iz, 0, -f * xr * iz * iz;
    out.count = 3;
  }
  return out;
}

}  // namespace

RectifiedStereoCameras RectifiedStereoCameras::of(const StereoCalibration& rig) {
  const auto& p1 = rig.left.projection;
  const auto& p2 = rig.right.projection;
  return {p1(0, 0), p1(0, 2), p2(0, 2), p1(1, 2), -p2(0, 3) / p2(0, 0)};
}

StereoMotionEstimator::StereoMotionEstimator(const RectifiedStereoCameras& cameras,
                                             const StereoMotionConfig& config)
    : cameras_(cameras), config_(config), random_(config.seed) {
  require(config.max_matches >= 3 && config.max_matches <= 100000,
          "stereo motion: max_matches must be 3..100000");
  require(config.iterations >= 1 && config.iterations <= 100000,
          "stereo motion: iterations must be 1..100000");
  require(config.inlier_px > 0 && config.inlier_px <= 20,
          "stereo motion: inlier_px must be in (0, 20]");
  require(config.min_inliers >= 3, "stereo motion: min_inliers must be 3 or more");
  require(config.min_inlier_ratio >= 0 && config.min_inlier_ratio <= 1,
          "stereo motion: min_inlier_ratio must be 0..1");
  require(config.refine_iterations >= 0 && config.refine_iterations <= 100,
          "stereo motion: refine_iterations must be 0..100");
  require(config.confidence > 0 && config.confidence < 1,
          "stereo motion: confidence must be in (0, 1)");
  require(cameras.f > 0 && cameras.baseline > 0,
          "stereo motion: the rig's focal length and baseline must be positive");
  const auto n = static_cast<std::size_t>(config.max_matches);
  bearings_.resize(n);
  inlier_.resize(n);
  candidate_.resize(n);
}

std::size_t StereoMotionEstimator::working_set_bytes() const {
  return sizeof(*this) + bearings_.capacity() * sizeof(Eigen::Vector3d) + inlier_.capacity() +
         candidate_.capacity();
}

int StereoMotionEstimator::classify(std::span<const MotionMatch> matches, const RigidMotion& motion,
                                    std::uint8_t* flags) const {
  const double limit = config_.inlier_px * config_.inlier_px;
  int count = 0;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    const Residuals r = residuals(cameras_, matches[i], motion);
    bool in = r.count > 0 && r.r[0] * r.r[0] + r.r[1] * r.r[1] <= limit;
    if (in && r.count == 3) in = r.r[2] * r.r[2] <= limit;
    flags[i] = in ? 1 : 0;
    count += in ? 1 : 0;
  }
  return count;
}

RigidMotion StereoMotionEstimator::refine(std::span<const MotionMatch> matches,
                                          const std::uint8_t* flags, RigidMotion motion,
                                          double& cost, int& count, Matrix6d& information) const {
  const auto evaluate = [&](const RigidMotion& m, Matrix6d* h, Vector6d* g, int* n) {
    double sum = 0;
    int used = 0;
    if (h != nullptr) {
      h->setZero();
      g->setZero();
    }
    for (std::size_t i = 0; i < matches.size(); ++i) {
      if (flags[i] == 0) continue;
      const Residuals r = residuals(cameras_, matches[i], m);
      if (r.count == 0) {
        sum += 2 * config_.inlier_px * config_.inlier_px;  // behind: as bad as an outlier
        used += 2;
        continue;
      }
      Eigen::Matrix<double, 3, 6> dx;
      dx << -skew(r.x), Eigen::Matrix3d::Identity();
      for (int k = 0; k < r.count; ++k) {
        sum += r.r[k] * r.r[k];
        ++used;
        if (h == nullptr) continue;
        const Eigen::Matrix<double, 1, 6> j = r.d[k] * dx;
        *h += j.transpose() * j;
        *g += j.transpose() * r.r[k];
      }
    }
    if (n != nullptr) *n = used;
    return sum;
  };
  Matrix6d h;
  Vector6d g;
  int used = 0;
  cost = evaluate(motion, &h, &g, &used);
  double lambda = 1e-4;
  for (int it = 0; it < config_.refine_iterations; ++it) {
    Matrix6d damped = h;
    damped.diagonal() *= 1 + lambda;
    const Vector6d step = damped.ldlt().solve(-g);
    if (!step.allFinite()) break;
    const Eigen::Matrix3d turn = exp_rotation(step.head<3>());
    const RigidMotion tried{turn * motion.rotation, turn * motion.translation + step.tail<3>()};
    const double tried_cost = evaluate(tried, nullptr, nullptr, nullptr);
    if (tried_cost < cost) {
      motion = tried;
      lambda = std::max(lambda / 10, 1e-9);
      cost = evaluate(motion, &h, &g, &used);
      if (step.norm() < 1e-10) break;
    } else {
      lambda *= 10;
      if (lambda > 1e6) break;
    }
  }
  count = used;
  information = h;
  return motion;
}

StereoMotion StereoMotionEstimator::estimate(std::span<const MotionMatch> matches,
                                             const RigidMotion& prediction) {
  require(matches.size() <= bearings_.size(), "stereo motion: ", matches.size(),
          " matches, more than max_matches (", bearings_.size(), ")");
  StereoMotion out;
  const int n = static_cast<int>(matches.size());
  out.matches = n;
  last_count_ = matches.size();
  std::fill_n(inlier_.begin(), matches.size(), std::uint8_t{0});
  if (n < std::max(3, config_.min_inliers)) return out;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    bearings_[i] = Eigen::Vector3d((matches[i].left_x - cameras_.left_cx) / cameras_.f,
                                   (matches[i].left_y - cameras_.cy) / cameras_.f, 1)
                       .normalized();
  }
  // The prediction first: at walking pace it is often right already.
  RigidMotion best = prediction;
  int best_count = classify(matches, best, inlier_.data());
  const double log_miss = std::log(1 - config_.confidence);
  // The samples that still could find a better motion at the best's inlier ratio.
  const auto samples_needed = [&](int inliers) {
    const double w = static_cast<double>(inliers) / n;
    const double miss = 1 - w * w * w;
    if (miss <= 0) return 0;
    if (miss >= 1) return config_.iterations;
    return static_cast<int>(
        std::min<double>(config_.iterations, std::ceil(log_miss / std::log(miss))));
  };
  int needed = samples_needed(best_count);
  std::array<RigidMotion, 4> poses;
  for (int s = 0; s < std::min(needed, config_.iterations); ++s) {
    ++out.samples;
    std::array<int, 3> k{};
    k[0] = static_cast<int>(random_.below(static_cast<std::uint64_t>(n)));
    do k[1] = static_cast<int>(random_.below(static_cast<std::uint64_t>(n)));
    while (k[1] == k[0]);
    do k[2] = static_cast<int>(random_.below(static_cast<std::uint64_t>(n)));
    while (k[2] == k[0] || k[2] == k[1]);
    const auto at = [&](int i) { return static_cast<std::size_t>(i); };
    const std::array<Eigen::Vector3d, 3> points = {matches[at(k[0])].point, matches[at(k[1])].point,
                                                   matches[at(k[2])].point};
    const std::array<Eigen::Vector3d, 3> rays = {bearings_[at(k[0])], bearings_[at(k[1])],
                                                 bearings_[at(k[2])]};
    const int solutions = solve_p3p(points, rays, poses);
    for (int p = 0; p < solutions; ++p) {
      const int count = classify(matches, poses[static_cast<std::size_t>(p)], candidate_.data());
      if (count <= best_count) continue;
      best_count = count;
      best = poses[static_cast<std::size_t>(p)];
      std::copy_n(candidate_.begin(), matches.size(), inlier_.begin());
      needed = samples_needed(best_count);
    }
  }
  if (best_count < 3) {
    std::fill_n(inlier_.begin(), matches.size(), std::uint8_t{0});
    return out;
  }
  // Refined on the inliers, the inliers found again with the refined motion, refined again.
  double cost = 0;
  int residual_count = 0;
  Matrix6d information;
  for (int round = 0; round < 2; ++round) {
    best = refine(matches, inlier_.data(), best, cost, residual_count, information);
    best_count = classify(matches, best, inlier_.data());
    if (best_count < 3) {
      std::fill_n(inlier_.begin(), matches.size(), std::uint8_t{0});
      return out;
    }
  }
  out.motion = best;
  out.inliers = best_count;
  out.rms_px = residual_count > 0 ? std::sqrt(cost / residual_count) : 0;
  const double variance = residual_count > 6 ? cost / (residual_count - 6) : 0;
  // J^T J must be invertible (every direction of the motion observed), with residuals to
  // spare over the 6 parameters; else no motion (and no covariance) is claimed.
  const Eigen::LDLT<Matrix6d> ldlt(information);
  const bool observed = ldlt.info() == Eigen::Success && ldlt.isPositive() &&
                        ldlt.vectorD().minCoeff() > 1e-12 * ldlt.vectorD().maxCoeff() &&
                        residual_count > 6;
  out.covariance = variance * ldlt.solve(Matrix6d::Identity());
  out.valid = observed && best_count >= config_.min_inliers &&
              best_count >= config_.min_inlier_ratio * n && out.covariance.allFinite() &&
              std::isfinite(out.rms_px);
  return out;
}

}  // namespace epipole::calib

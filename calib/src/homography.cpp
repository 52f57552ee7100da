#include "epipole/calib/homography.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <optional>

#include "epipole/core/error.hpp"
#include "epipole/core/splitmix.hpp"

namespace epipole::calib {

namespace {

using Points = std::span<const Eigen::Vector2d>;

// Hartley's normalisation: the points' centroid to the origin, their mean distance from it to
// sqrt 2. None for coincident points.
std::optional<Eigen::Matrix3d> normalisation(Points points, std::span<const int> use) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const int i : use) centroid += points[static_cast<std::size_t>(i)];
  centroid /= static_cast<double>(use.size());
  double mean = 0;
  for (const int i : use) mean += (points[static_cast<std::size_t>(i)] - centroid).norm();
  mean /= static_cast<double>(use.size());
  if (!(mean > 0) || !std::isfinite(mean)) return std::nullopt;
  const double s = std::sqrt(2.0) / mean;
  Eigen::Matrix3d T;
  T << s, 0, -s * centroid.x(), 0, s, -s * centroid.y(), 0, 0, 1;
  return T;
}

// The normalised DLT through the correspondences `use`; none when they do not determine a
// homography (a null space of more than one dimension, or H(2,2) = 0).
std::optional<Eigen::Matrix3d> dlt(Points from, Points to, std::span<const int> use) {
  const auto tf = normalisation(from, use);
  const auto tt = normalisation(to, use);
  if (!tf || !tt) return std::nullopt;
  Eigen::MatrixXd A(2 * static_cast<Eigen::Index>(std::max<std::size_t>(use.size(), 5)), 9);
  A.setZero();  // a fifth, empty pair of rows for four points: a square-enough system for SVD
  Eigen::Index row = 0;
  for (const int i : use) {
    const Eigen::Vector3d x = *tf * from[static_cast<std::size_t>(i)].homogeneous();
    const Eigen::Vector3d y = *tt * to[static_cast<std::size_t>(i)].homogeneous();
    A.row(row++) << -x.x(), -x.y(), -1, 0, 0, 0, y.x() * x.x(), y.x() * x.y(), y.x();
    A.row(row++) << 0, 0, 0, -x.x(), -x.y(), -1, y.y() * x.x(), y.y() * x.y(), y.y();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  // Eight independent equations (four points, no three on a line) leave one null direction.
  if (!(sigma(7) > 1e-9 * sigma(0))) return std::nullopt;
  const Eigen::VectorXd h = svd.matrixV().col(8);
  Eigen::Matrix3d Hn;
  Hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  Eigen::Matrix3d H = tt->inverse() * Hn * *tf;
  if (!(std::abs(H(2, 2)) > 1e-12 * H.norm()) || !H.allFinite()) return std::nullopt;
  return H / H(2, 2);
}

void check_input(Points from, Points to) {
  require(from.size() == to.size(), "homography: ", from.size(), " points but ", to.size(),
          " matching points");
  require(from.size() >= 4, "homography: ", from.size(),
          " correspondences; four at least determine one");
  for (std::size_t i = 0; i < from.size(); ++i) {
    require(from[i].allFinite() && to[i].allFinite(), "homography: point ", i,
            " is not a finite number");
  }
}

double error_px(const Eigen::Matrix3d& H, const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  return (apply_homography(H, from) - to).norm();
}

// Levenberg-Marquardt on the eight parameters of H (H(2,2) = 1) minimising the reprojection
// error of `use` in the second view, with the analytic Jacobian.
Eigen::Matrix3d refine(const Eigen::Matrix3d& start, Points from, Points to,
                       std::span<const int> use, int iterations) {
  const auto cost_and_normal = [&](const Eigen::Matrix<double, 8, 1>& p,
                                   Eigen::Matrix<double, 8, 8>* jtj,
                                   Eigen::Matrix<double, 8, 1>* jtr) {
    double cost = 0;
    if (jtj != nullptr) {
      jtj->setZero();
      jtr->setZero();
    }
    for (const int i : use) {
      const Eigen::Vector2d& x = from[static_cast<std::size_t>(i)];
      const double w = p(6) * x.x() + p(7) * x.y() + 1;
      const double u = (p(0) * x.x() + p(1) * x.y() + p(2)) / w;
      const double v = (p(3) * x.x() + p(4) * x.y() + p(5)) / w;
      const Eigen::Vector2d r(u - to[static_cast<std::size_t>(i)].x(),
                              v - to[static_cast<std::size_t>(i)].y());
      cost += r.squaredNorm();
      if (jtj == nullptr) continue;
      Eigen::Matrix<double, 2, 8> J;
      J << x.x() / w, x.y() / w, 1 / w, 0, 0, 0, -u * x.x() / w, -u * x.y() / w,  //
          0, 0, 0, x.x() / w, x.y() / w, 1 / w, -v * x.x() / w, -v * x.y() / w;
      *jtj += J.transpose() * J;
      *jtr += J.transpose() * r;
    }
    return cost;
  };
  Eigen::Matrix<double, 8, 1> p;
  p << start(0, 0), start(0, 1), start(0, 2), start(1, 0), start(1, 1), start(1, 2), start(2, 0),
      start(2, 1);
  double lambda = 1e-3;
  for (int it = 0; it < iterations; ++it) {
    Eigen::Matrix<double, 8, 8> jtj;
    Eigen::Matrix<double, 8, 1> jtr;
    const double cost = cost_and_normal(p, &jtj, &jtr);
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Eigen::Matrix<double, 8, 8> damped = jtj;
      damped.diagonal() *= 1 + lambda;
      const Eigen::Matrix<double, 8, 1> step = damped.ldlt().solve(-jtr);
      if (!step.allFinite()) break;
      const Eigen::Matrix<double, 8, 1> next = p + step;
      if (cost_and_normal(next, nullptr, nullptr) < cost) {
        p = next;
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;  // a minimum, as far as the damping can tell
  }
  Eigen::Matrix3d H;
  H << p(0), p(1), p(2), p(3), p(4), p(5), p(6), p(7), 1;
  return H;
}

}  // namespace

Eigen::Vector2d apply_homography(const Eigen::Matrix3d& H, const Eigen::Vector2d& x) {
  return (H * x.homogeneous()).hnormalized();
}

Eigen::Matrix3d homography_dlt(Points from, Points to) {
  check_input(from, to);
  std::vector<int> all(from.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  const auto H = dlt(from, to, all);
  require(H.has_value(),
          "homography: the points do not determine one (coincident, or three of four on a line)");
  return *H;
}

HomographyFit find_homography(Points from, Points to, const HomographyOptions& options) {
  check_input(from, to);
  require(options.inlier_px > 0 && options.max_iterations >= 1 && options.confidence > 0 &&
              options.confidence < 1,
          "homography: RANSAC needs a positive inlier distance, iterations and a confidence "
          "below 1");
  const auto n = static_cast<int>(from.size());
  SplitMix64 random(options.seed);
  HomographyFit fit;
  std::optional<Eigen::Matrix3d> best;
  int best_count = 0;
  double needed = options.max_iterations;
  const auto count_inliers = [&](const Eigen::Matrix3d& H) {
    int count = 0;
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      count += error_px(H, from[k], to[k]) <= options.inlier_px ? 1 : 0;
    }
    return count;
  };
  for (fit.iterations = 0; fit.iterations < std::min<double>(needed, options.max_iterations);
       ++fit.iterations) {
    int sample[4];
    for (int k = 0; k < 4; ++k) {
      bool repeated = true;
      while (repeated) {
        sample[k] = static_cast<int>(random.below(static_cast<std::uint64_t>(n)));
        repeated = std::find(sample, sample + k, sample[k]) != sample + k;
      }
    }
    const auto H = dlt(from, to, sample);
    if (!H) continue;
    const int count = count_inliers(*H);
    if (count <= best_count) continue;
    best_count = count;
    best = H;
    // The samples needed for one of inliers only with the given confidence, at this ratio.
    const double w = static_cast<double>(count) / n;
    const double all_in = std::pow(w, 4);
    // log1p: for a small ratio, 1 - w^4 rounds to 1 and log() to 0.
    const double samples = std::log1p(-options.confidence) / std::log1p(-all_in);
    needed = all_in >= 1 ? 0 : std::isfinite(samples) ? samples : options.max_iterations;
  }
  require(best.has_value(), "homography: no four of the ", n,
          " points determine one (coincident, or three of four on a line)");
  // Four points always agree with their own homography: with more, one more must confirm it.
  require(best_count >= std::min(n, 5), "homography: of ", n,
          " correspondences, no more than a sample of four agree on one");
  // The DLT on every inlier of the best sample, then its own inliers refined.
  std::vector<int> use;
  const auto inliers_of = [&](const Eigen::Matrix3d& H) {
    use.clear();
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (error_px(H, from[k], to[k]) <= options.inlier_px) use.push_back(i);
    }
  };
  inliers_of(*best);
  Eigen::Matrix3d H = dlt(from, to, use).value_or(*best);
  inliers_of(H);
  if (use.size() < 4) {
    H = *best;
    inliers_of(H);
  }
  H = refine(H, from, to, use, options.refine_iterations);
  inliers_of(H);
  fit.H = H;
  fit.inliers.assign(from.size(), false);
  double sum = 0;
  for (const int i : use) {
    const auto k = static_cast<std::size_t>(i);
    fit.inliers[k] = true;
    sum += std::pow(error_px(H, from[k], to[k]), 2);
  }
  fit.inlier_count = static_cast<int>(use.size());
  fit.rms_px = use.empty() ? 0 : std::sqrt(sum / static_cast<double>(use.size()));
  return fit;
}

}  // namespace epipole::calib

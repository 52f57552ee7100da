// Homographies: the normalised DLT exact on exact correspondences, RANSAC and Levenberg-Marquardt
// through noise and outliers, and clear errors where the points determine none.
#include "epipole/calib/homography.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole::calib {
namespace {

Eigen::Matrix3d perspective() {
  Eigen::Matrix3d H;
  H << 0.76, -0.30, 225.7, 0.33, 1.01, -77.0, 3.5e-4, -1.4e-5, 1;
  return H;
}

// The largest distance between where H and the truth send the points of a grid over the view.
double transfer_error(const Eigen::Matrix3d& H, const Eigen::Matrix3d& truth) {
  double worst = 0;
  for (double y = 0; y <= 640; y += 40) {
    for (double x = 0; x <= 800; x += 40) {
      const Eigen::Vector2d p(x, y);
      worst = std::max(worst, (apply_homography(H, p) - apply_homography(truth, p)).norm());
    }
  }
  return worst;
}

TEST(Homography, TheDltIsExactOnExactCorrespondences) {
  const Eigen::Matrix3d truth = perspective();
  std::vector<Eigen::Vector2d> from = {{10, 20}, {700, 40}, {650, 600}, {30, 560}};
  std::vector<Eigen::Vector2d> to;
  for (const auto& p : from) to.push_back(apply_homography(truth, p));
  EXPECT_LT(transfer_error(homography_dlt(from, to), truth), 1e-8);
  // Far from the origin and at a large scale: the normalisation keeps it exact.
  for (auto& p : from) p = p * 1000 + Eigen::Vector2d(1e6, -2e6);
  Eigen::Matrix3d scaled = truth;
  to.clear();
  for (const auto& p : from) to.push_back(apply_homography(scaled, p));
  const Eigen::Matrix3d H = homography_dlt(from, to);
  for (const auto& p : from)
    EXPECT_LT((apply_homography(H, p) - apply_homography(scaled, p)).norm(), 1e-6);
}

TEST(Homography, RansacAndRefinementThroughNoiseAndOutliers) {
  const Eigen::Matrix3d truth = perspective();
  std::mt19937 random(3);
  std::uniform_real_distribution<double> x(0, 800), y(0, 640), anywhere(-100, 900);
  std::normal_distribution<double> noise(0, 0.5);
  std::vector<Eigen::Vector2d> from, to;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector2d p(x(random), y(random));
    from.push_back(p);
    if (i % 10 < 4) {  // 40 % outliers
      to.emplace_back(anywhere(random), anywhere(random));
    } else {
      to.push_back(apply_homography(truth, p) + Eigen::Vector2d(noise(random), noise(random)));
    }
  }
  const HomographyFit fit = find_homography(from, to);
  EXPECT_LT(transfer_error(fit.H, truth), 1.0);
  EXPECT_GE(fit.inlier_count, 175);
  EXPECT_LE(fit.inlier_count, 185);
  EXPECT_LT(fit.rms_px, 1.0);
  EXPECT_GT(fit.rms_px, 0.3);
  // RANSAC stopped once a clean sample was likely (w = 0.6: about 50 samples for 99.9 %).
  EXPECT_LT(fit.iterations, 200);
  // The refinement lowers the error of the DLT on the same inliers.
  std::vector<Eigen::Vector2d> in_from, in_to;
  for (std::size_t i = 0; i < from.size(); ++i) {
    if (!fit.inliers[i]) continue;
    in_from.push_back(from[i]);
    in_to.push_back(to[i]);
  }
  const Eigen::Matrix3d linear = homography_dlt(in_from, in_to);
  double linear_sum = 0, refined_sum = 0;
  for (std::size_t i = 0; i < in_from.size(); ++i) {
    linear_sum += (apply_homography(linear, in_from[i]) - in_to[i]).squaredNorm();
    refined_sum += (apply_homography(fit.H, in_from[i]) - in_to[i]).squaredNorm();
  }
  EXPECT_LE(refined_sum, linear_sum);
}

TEST(Homography, PointsThatDetermineNoneAreAClearError) {
  const std::vector<Eigen::Vector2d> three = {{0, 0}, {1, 0}, {0, 1}};
  EXPECT_THROW(homography_dlt(three, three), Error);
  const std::vector<Eigen::Vector2d> collinear = {{0, 0}, {1, 1}, {2, 2}, {5, 0}};
  const std::vector<Eigen::Vector2d> square = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  EXPECT_THROW(homography_dlt(collinear, square), Error);
  const std::vector<Eigen::Vector2d> same = {{1, 1}, {1, 1}, {1, 1}, {1, 1}};
  EXPECT_THROW(homography_dlt(same, square), Error);
  const std::vector<Eigen::Vector2d> nan = {{0, 0}, {1, 0}, {1, std::nan("")}, {0, 1}};
  EXPECT_THROW(homography_dlt(nan, square), Error);
  EXPECT_THROW(homography_dlt(square, three), Error);
  // No four agree: every correspondence wild.
  std::vector<Eigen::Vector2d> from, to;
  std::mt19937 random(1);
  std::uniform_real_distribution<double> any(0, 1000);
  for (int i = 0; i < 12; ++i) {
    from.emplace_back(any(random), any(random));
    to.emplace_back(any(random), any(random));
  }
  HomographyOptions strict;
  strict.inlier_px = 1e-6;
  EXPECT_THROW(find_homography(from, to, strict), Error);
}

}  // namespace
}  // namespace epipole::calib

#pragma once

// Homographies between two views of a plane (x' ~ H x), as the lectures estimate them:
// the normalised direct linear transform (Hartley's normalisation: each point set moved to its
// centroid and scaled to a mean distance of sqrt 2, so that the linear system is well
// conditioned), RANSAC over four-point samples against outliers, then Levenberg-Marquardt on the
// inliers' reprojection error in the second view (H with H(2,2) = 1: eight parameters).
// Eigen only (host tools and the firmware alike).
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace epipole::calib {

// The DLT through at least four correspondences (all of them, least squares), normalised.
// Throws Error for fewer than four, mismatched counts, non-finite points, or a degenerate set
// (three of four on a line, all on a line): no homography is determined.
Eigen::Matrix3d homography_dlt(std::span<const Eigen::Vector2d> from,
                               std::span<const Eigen::Vector2d> to);

struct HomographyOptions {
  // An inlier's reprojection error in the second view. OpenCV's default is 3 px; on real
  // matches (the graffiti pair) wrong ones cluster within 3 px of the truth and pull the fit,
  // 2 px leaves them out (docs/vision.md).
  double inlier_px = 2.0;
  int max_iterations = 2000;
  double confidence = 0.999;  // stop when a sample of inliers was drawn with this probability
  std::uint64_t seed = 1;
  int refine_iterations = 20;  // Levenberg-Marquardt's
};

struct HomographyFit {
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();  // H(2,2) = 1
  std::vector<bool> inliers;                        // per correspondence
  int inlier_count = 0;
  int iterations = 0;  // RANSAC's samples drawn
  double rms_px = 0;   // the inliers' reprojection error after refinement
};

// RANSAC (with four correspondences, the DLT is exact) then the DLT on the best sample's inliers
// and Levenberg-Marquardt on them. Throws Error as homography_dlt() does, or, for more than four
// correspondences, when no sample's homography has an inlier beyond the sample itself.
HomographyFit find_homography(std::span<const Eigen::Vector2d> from,
                              std::span<const Eigen::Vector2d> to,
                              const HomographyOptions& options = {});

// H x, dehomogenised.
Eigen::Vector2d apply_homography(const Eigen::Matrix3d& H, const Eigen::Vector2d& x);

}  // namespace epipole::calib

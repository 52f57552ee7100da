#pragma once

// The rig's motion between two pairs from their features (docs/odometry.md): the 3-D points of
// the earlier pair, triangulated by the stereo matches, seen again in the later pair's rectified
// images; P3P (p3p.hpp) inside RANSAC with a budget of samples, then Levenberg-Marquardt on the
// reprojection error in both of the later pair's images.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/p3p.hpp"
#include "epipole/core/splitmix.hpp"

namespace epipole::calib {

// The rectified pair as the motion sees it: one focal length (pixels), the principal points and
// the baseline (metres; the right camera at (baseline, 0, 0) of the left's frame).
struct RectifiedStereoCameras {
  double f = 1, left_cx = 0, right_cx = 0, cy = 0, baseline = 0;
  static RectifiedStereoCameras of(const StereoCalibration& rig);  // from P1 and P2
};

// A feature of the earlier pair found again in the later one.
struct MotionMatch {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // the earlier pair's left frame, metres
  double left_x = 0, left_y = 0;                    // the later pair's rectified left image, pixels
  double right_x = 0;  // and its right image (the same row); NaN: not seen there
};

struct StereoMotionConfig {
  int max_matches = 2000;         // estimate() takes at most this many
  int iterations = 200;           // RANSAC's samples at most: the board's time budget
  double inlier_px = 1.0;         // a match's reprojection error in each image, at most
  int min_inliers = 20;           // fewer: no motion (tracking is lost)
  double min_inlier_ratio = 0.2;  // of the matches
  int refine_iterations = 10;     // Levenberg-Marquardt's, each of its two rounds
  double confidence = 0.999;      // RANSAC stops once a better sample is this unlikely
  std::uint64_t seed = 0x0D0u;
};

struct StereoMotion {
  bool valid = false;
  // Points of the earlier pair's left frame into the later pair's: the camera's motion inverted.
  RigidMotion motion;
  int matches = 0;
  int inliers = 0;
  int samples = 0;    // RANSAC samples drawn
  double rms_px = 0;  // the inliers' reprojection error after refinement
  // Of the perturbation d = (rotation vector, translation) of motion' = exp(d) motion:
  // radians and metres squared, from the inliers' residuals (Gauss-Newton's J^T J).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

// Fixed memory: the constructor allocates per match of max_matches; estimate() never allocates.
class StereoMotionEstimator {
 public:
  // Throws Error for settings out of range.
  StereoMotionEstimator(const RectifiedStereoCameras& cameras, const StereoMotionConfig& config);

  // `prediction`: the motion expected (the one before, for constant velocity), tried first.
  // At most max_matches matches (Error beyond).
  StereoMotion estimate(std::span<const MotionMatch> matches, const RigidMotion& prediction);
  // Per match of the last estimate: 1 for an inlier of its motion.
  std::span<const std::uint8_t> inliers() const { return {inlier_.data(), last_count_}; }
  const StereoMotionConfig& config() const { return config_; }
  std::size_t working_set_bytes() const;

 private:
  // The inliers of `motion` into `flags`; returns their count.
  int classify(std::span<const MotionMatch> matches, const RigidMotion& motion,
               std::uint8_t* flags) const;
  // Levenberg-Marquardt over the inliers `flags` marks; the sum of squared residuals and their
  // count, and J^T J at the result.
  RigidMotion refine(std::span<const MotionMatch> matches, const std::uint8_t* flags,
                     RigidMotion motion, double& cost, int& residuals,
                     Eigen::Matrix<double, 6, 6>& information) const;

  RectifiedStereoCameras cameras_;
  StereoMotionConfig config_;
  SplitMix64 random_;
  std::vector<Eigen::Vector3d> bearings_;  // per match: its later left ray, unit length
  std::vector<std::uint8_t> inlier_, candidate_;
  std::size_t last_count_ = 0;
};

}  // namespace epipole::calib

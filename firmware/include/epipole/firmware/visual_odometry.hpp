#pragma once

// Stereo visual odometry (docs/odometry.md): where the rig is and how it moves, from the sparse
// stage's features of each pair. A keyframe keeps its stereo matches' 3-D points and
// descriptors; each later pair finds them again in its left image, in a window around where the
// motion so far predicts them (vision::WindowMatcher), and the rig's motion since the keyframe
// comes from those (calib::StereoMotionEstimator: P3P in RANSAC, then Levenberg-Marquardt on the
// reprojection in both images). A new keyframe is taken when the rig has moved or turned far
// enough, or too few of the keyframe's features are still seen; standing still, the keyframe
// stays and nothing drifts. A pair whose motion cannot be found (too few features, a blank
// wall, a motion beyond the board's bounds) reports the tracking lost, never a made-up pose.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "epipole/calib/stereo_motion.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/firmware/sparse_points.hpp"
#include "epipole/hal/clock.hpp"
#include "epipole/vision/window_matcher.hpp"

namespace epipole::firmware {

struct OdometryConfig {
  int max_landmarks = 1000;            // a keyframe's features followed (its most distinctive)
  int search_radius_px = 40;           // the window around each feature's predicted place; a
                                       // pair whose motion is not found so is searched again at 3x
                                       // (a turn begun since the pair before: up to 256)
  int max_distance = 64;               // descriptors' Hamming distance, as the sparse stage's
  int ratio = 80;                      // percent, as the sparse stage's
  calib::StereoMotionConfig motion;    // RANSAC's budget and thresholds
  double keyframe_distance_m = 0.3;    // a new keyframe past this far from the last
  double keyframe_angle_deg = 10;      // or turned this much
  double keyframe_inlier_ratio = 0.4;  // or when fewer of its features are inliers
  int lost_pairs_to_reset = 3;         // lost this many pairs in a row: start again from here
  double max_speed_mps = 10;           // a motion faster than these is refused (lost), not reported
  double max_turn_dps = 360;
};

struct OdometryState {
  enum class Status : std::uint8_t { starting, tracking, lost };
  Status status = Status::starting;
  // The left camera's pose in the odometry frame: the first keyframe's left camera (OpenCV's
  // axes: x right, y down, z forward). odometry point = pose.apply(camera point).
  calib::RigidMotion pose;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();          // the camera's, odometry frame, m/s
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // the camera's frame, rad/s
  // Of the pose's perturbation (rotation vector, translation), both in the odometry frame.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  int features = 0;                // the keyframe's features looked for
  int tracked = 0;                 // found again in this pair
  int inliers = 0;                 // consistent with its motion
  int quality = 0;                 // MAVLink's: 1..100, -1 lost, 0 not yet known
  std::uint8_t reset_counter = 0;  // the pose started again (after lost tracking)
  std::uint32_t keyframes = 0;
  hal::Nanoseconds time = 0;  // the pair's
};

// Fixed memory: the constructor allocates; update() never does.
class VisualOdometry {
 public:
  // Throws Error for settings out of range.
  VisualOdometry(const calib::RectifiedStereoCameras& cameras, int width, int height,
                 int max_corners, int max_points, const OdometryConfig& config,
                 SimdPath path = best_simd_path());

  // A pair: its time, its left image's described corners and its stereo matches' 3-D points
  // (SparsePoint::left_feature indexing `left`).
  const OdometryState& update(hal::Nanoseconds time, const vision::DescribedCorners& left,
                              std::span<const SparsePoint> points);
  // Starts again at the next pair, from the pose it has (the cameras were lost, pairs missed):
  // reset_counter counts it.
  void restart();
  const OdometryState& state() const { return state_; }
  std::size_t working_set_bytes() const;

 private:
  // The keyframe's features found in `left` from the motion `predicted`, with `window`: the
  // motion since the keyframe.
  calib::StereoMotion follow(vision::WindowMatcher& window, const vision::DescribedCorners& left,
                             const calib::RigidMotion& predicted);
  // This pair becomes the keyframe, at the current pose; false with too few features for one
  // (the keyframe before, if any, stays).
  bool make_keyframe(const vision::DescribedCorners& left, std::span<const SparsePoint> points);
  void lose();

  calib::RectifiedStereoCameras cameras_;
  int height_;
  OdometryConfig config_;
  vision::WindowMatcher window_, wide_window_;
  calib::StereoMotionEstimator motion_;
  // The keyframe: its features' points (its left camera's frame) and descriptors, its pose.
  std::vector<Eigen::Vector3d> landmarks_;
  std::vector<std::uint8_t> descriptors_;
  int landmark_count_ = 0;
  bool have_keyframe_ = false;
  bool pending_reset_ = false;  // restart() was called: the next keyframe counts a reset
  calib::RigidMotion keyframe_pose_;
  Eigen::Matrix<double, 6, 6> keyframe_covariance_ = Eigen::Matrix<double, 6, 6>::Zero();
  // Since the keyframe: its points into the current camera (the last pair's).
  calib::RigidMotion since_keyframe_;
  // The last step's twist per second (rotation vector, translation; the camera's frame), for
  // the prediction.
  Eigen::Matrix<double, 6, 1> twist_ = Eigen::Matrix<double, 6, 1>::Zero();
  // The time of the pair since_keyframe_ describes (the last one tracked, or the keyframe's):
  // the step since it spans every pair lost meanwhile.
  hal::Nanoseconds tracked_time_ = 0;
  int lost_pairs_ = 0;
  // Per pair: the queries' predicted places, each corner's right column.
  std::vector<float> query_x_, query_y_;
  std::vector<float> right_x_;        // per corner of the left image, NaN: no stereo match
  std::vector<std::uint32_t> order_;  // the pair's points by descriptor distance
  std::vector<calib::MotionMatch> matches_;
  OdometryState state_;
};

}  // namespace epipole::firmware

// Stereo visual odometry (visual_odometry.hpp, docs/odometry.md).
#include "epipole/firmware/visual_odometry.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"

namespace epipole::firmware {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd a(r);
  return a.angle() * a.axis();
}

Eigen::Matrix3d rotation_of(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

vision::WindowMatchConfig window_config(int width, int height, int max_corners,
                                        const OdometryConfig& c, int radius) {
  vision::WindowMatchConfig w;
  w.width = width;
  w.height = height;
  w.max_queries = c.max_landmarks;
  w.max_corners = max_corners;
  w.radius = radius;
  w.max_distance = c.max_distance;
  w.ratio = c.ratio;
  return w;
}

calib::StereoMotionConfig motion_config(const OdometryConfig& c) {
  calib::StereoMotionConfig m = c.motion;
  m.max_matches = c.max_landmarks;
  return m;
}

}  // namespace

VisualOdometry::VisualOdometry(const calib::RectifiedStereoCameras& cameras, int width, int height,
                               int max_corners, int max_points, const OdometryConfig& config,
                               SimdPath path)
    : cameras_(cameras),
      height_(height),
      config_(config),
      window_(window_config(width, height, max_corners, config, config.search_radius_px), path),
      wide_window_(window_config(width, height, max_corners, config,
                                 std::min(3 * std::max(config.search_radius_px, 1), 256)),
                   path),
      motion_(cameras, motion_config(config)) {
  require(config.max_landmarks >= config.motion.min_inliers && config.max_landmarks <= 100000,
          "odometry: max_landmarks must be at least motion's min_inliers, at most 100000");
  require(config.keyframe_distance_m > 0 && config.keyframe_angle_deg > 0,
          "odometry: the keyframe's distance and angle must be positive");
  require(config.keyframe_inlier_ratio >= 0 && config.keyframe_inlier_ratio <= 1,
          "odometry: keyframe_inlier_ratio must be 0..1");
  require(config.lost_pairs_to_reset >= 1, "odometry: lost_pairs_to_reset must be 1 or more");
  require(config.max_speed_mps > 0 && config.max_turn_dps > 0,
          "odometry: max_speed_mps and max_turn_dps must be positive");
  require(max_corners >= 1 && max_points >= 0, "odometry: no corners to follow");
  const auto landmarks = static_cast<std::size_t>(config.max_landmarks);
  landmarks_.resize(landmarks);
  descriptors_.resize(landmarks * vision::SparseStereoMatcher::kDescriptorBytes);
  query_x_.resize(landmarks);
  query_y_.resize(landmarks);
  matches_.resize(landmarks);
  right_x_.resize(static_cast<std::size_t>(max_corners));
  order_.resize(static_cast<std::size_t>(max_points));
}

std::size_t VisualOdometry::working_set_bytes() const {
  return sizeof(*this) + window_.working_set_bytes() + wide_window_.working_set_bytes() +
         motion_.working_set_bytes() + landmarks_.capacity() * sizeof(Eigen::Vector3d) +
         descriptors_.capacity() +
         (query_x_.capacity() + query_y_.capacity() + right_x_.capacity()) * sizeof(float) +
         order_.capacity() * 4 + matches_.capacity() * sizeof(calib::MotionMatch);
}

void VisualOdometry::restart() {
  have_keyframe_ = false;
  pending_reset_ = true;
  twist_.setZero();
  state_.velocity.setZero();
  state_.angular_velocity.setZero();
  lost_pairs_ = 0;
}

bool VisualOdometry::make_keyframe(const vision::DescribedCorners& left,
                                   std::span<const SparsePoint> points) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < points.size() && n < order_.size(); ++i) {
    const SparsePoint& p = points[i];
    if (p.left_feature >= 0 && p.left_feature < left.count() && p.z > 0) {
      order_[n++] = static_cast<std::uint32_t>(i);
    }
  }
  // The most distinctive first (smallest stereo descriptor distance).
  const std::size_t kept = std::min(n, landmarks_.size());
  std::partial_sort(
      order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(kept),
      order_.begin() + static_cast<std::ptrdiff_t>(n), [&](std::uint32_t a, std::uint32_t b) {
        return points[a].distance != points[b].distance ? points[a].distance < points[b].distance
                                                        : a < b;
      });
  if (static_cast<int>(kept) < config_.motion.min_inliers) return false;
  constexpr std::size_t kBytes = vision::SparseStereoMatcher::kDescriptorBytes;
  for (std::size_t k = 0; k < kept; ++k) {
    const SparsePoint& p = points[order_[k]];
    landmarks_[k] = Eigen::Vector3d(static_cast<double>(p.x), static_cast<double>(p.y),
                                    static_cast<double>(p.z));
    std::copy_n(left.descriptors.data() + static_cast<std::size_t>(p.left_feature) * kBytes, kBytes,
                descriptors_.data() + k * kBytes);
  }
  landmark_count_ = static_cast<int>(kept);
  have_keyframe_ = true;
  tracked_time_ = state_.time;
  keyframe_pose_ = state_.pose;
  keyframe_covariance_ = state_.covariance;
  since_keyframe_ = {};
  ++state_.keyframes;
  if (pending_reset_) {
    ++state_.reset_counter;
    pending_reset_ = false;
  }
  return true;
}

void VisualOdometry::lose() {
  state_.status = OdometryState::Status::lost;
  state_.quality = -1;
  state_.velocity.setZero();
  state_.angular_velocity.setZero();
  if (++lost_pairs_ >= config_.lost_pairs_to_reset) restart();
}

calib::StereoMotion VisualOdometry::follow(vision::WindowMatcher& window,
                                           const vision::DescribedCorners& left,
                                           const calib::RigidMotion& predicted) {
  const auto count = static_cast<std::size_t>(landmark_count_);
  for (std::size_t j = 0; j < count; ++j) {
    const Eigen::Vector3d x = predicted.apply(landmarks_[j]);
    const bool ahead = x.z() > 0.05;
    query_x_[j] = ahead ? static_cast<float>(cameras_.f * x.x() / x.z() + cameras_.left_cx)
                        : std::numeric_limits<float>::quiet_NaN();
    query_y_[j] = ahead ? static_cast<float>(cameras_.f * x.y() / x.z() + cameras_.cy)
                        : std::numeric_limits<float>::quiet_NaN();
  }
  constexpr std::size_t kBytes = vision::SparseStereoMatcher::kDescriptorBytes;
  const auto found =
      window.match(std::span(descriptors_).first(count * kBytes), std::span(query_x_).first(count),
                   std::span(query_y_).first(count), left);
  std::size_t m = 0;
  for (const vision::WindowMatch& w : found) {
    const auto c = static_cast<std::size_t>(w.corner);
    calib::MotionMatch& match = matches_[m++];
    match.point = landmarks_[static_cast<std::size_t>(w.query)];
    match.left_x = left.x[c];
    match.left_y = left.y[c];
    match.right_x = static_cast<double>(right_x_[c]);
  }
  state_.features = landmark_count_;
  state_.tracked = static_cast<int>(m);
  return motion_.estimate(std::span(matches_).first(m), predicted);
}

const OdometryState& VisualOdometry::update(hal::Nanoseconds time,
                                            const vision::DescribedCorners& left,
                                            std::span<const SparsePoint> points) {
  constexpr std::size_t kBytes = vision::SparseStereoMatcher::kDescriptorBytes;
  const auto corners = static_cast<std::size_t>(left.count());
  require(corners <= right_x_.size(), "odometry: ", corners, " corners, more than ",
          right_x_.size());
  require(left.y.size() == corners && left.descriptors.size() == corners * kBytes &&
              left.row_start.size() == static_cast<std::size_t>(height_) + 1,
          "odometry: corners of another image size or without their descriptors");
  state_.time = time;
  state_.tracked = state_.inliers = 0;
  std::fill_n(right_x_.begin(), corners, std::numeric_limits<float>::quiet_NaN());
  for (const SparsePoint& p : points) {
    if (p.left_feature >= 0 && static_cast<std::size_t>(p.left_feature) < corners) {
      right_x_[static_cast<std::size_t>(p.left_feature)] = p.xr;
    }
  }
  if (!have_keyframe_) {
    // The first pair, or a start again: this pair is where the odometry stands.
    if (make_keyframe(left, points)) {
      state_.status = OdometryState::Status::tracking;
      state_.quality = 0;  // a pose, but no motion measured yet
      state_.features = landmark_count_;
    } else {
      state_.status = state_.keyframes == 0 && !pending_reset_ ? OdometryState::Status::starting
                                                               : OdometryState::Status::lost;
      state_.quality = state_.keyframes == 0 && !pending_reset_ ? 0 : -1;
      state_.features = 0;
    }
    return state_;
  }
  // Since the pair the motion so far describes: over the pairs lost meanwhile too.
  const double dt = static_cast<double>(time - tracked_time_) / 1e9;

  // Where the keyframe's features should be: the motion so far, and the last step's again; that
  // failing, in a wider window, and then as the last tracked pair saw them.
  const calib::RigidMotion step{rotation_of(twist_.head<3>() * dt), twist_.tail<3>() * dt};
  const calib::RigidMotion predicted = step.after(since_keyframe_);
  calib::StereoMotion estimate = follow(window_, left, predicted);
  if (!estimate.valid) estimate = follow(wide_window_, left, predicted);
  // The motion changed (a turn ended, the rig stopped): where the last tracked pair saw them.
  if (!estimate.valid && dt > 0 && !twist_.isZero()) {
    estimate = follow(wide_window_, left, since_keyframe_);
  }
  state_.inliers = estimate.inliers;

  // The step from the last pair, refused when faster than the board allows (a wrong motion).
  const calib::RigidMotion last_step = estimate.motion.after(since_keyframe_.inverse());
  const double angle = Eigen::AngleAxisd(last_step.rotation).angle();
  const double moved = last_step.inverse().translation.norm();
  const bool wild =
      dt > 0 && (moved > config_.max_speed_mps * dt || angle > radians(config_.max_turn_dps) * dt);
  if (!estimate.valid || wild) {
    lose();
    return state_;
  }
  lost_pairs_ = 0;
  tracked_time_ = time;
  const Eigen::Vector3d before = state_.pose.translation;
  since_keyframe_ = estimate.motion;
  state_.pose = keyframe_pose_.after(since_keyframe_.inverse());
  if (dt > 0) {
    twist_.head<3>() = rotation_vector(last_step.rotation) / dt;
    twist_.tail<3>() = last_step.translation / dt;
    state_.velocity = (state_.pose.translation - before) / dt;
    state_.angular_velocity = -twist_.head<3>();  // the camera turns against its points
  }
  // The motion's uncertainty, in the current camera's frame, turned into the odometry frame, and
  // the keyframe's carried to the current pose: its heading's error moves the position by the
  // lever arm from the keyframe (first order; docs/odometry.md).
  Matrix6d turn = Matrix6d::Zero();
  turn.topLeftCorner<3, 3>() = state_.pose.rotation;
  turn.bottomRightCorner<3, 3>() = state_.pose.rotation;
  const Eigen::Vector3d arm = state_.pose.translation - keyframe_pose_.translation;
  Eigen::Matrix3d arm_cross;
  arm_cross << 0, -arm.z(), arm.y(), arm.z(), 0, -arm.x(), -arm.y(), arm.x(), 0;
  Matrix6d carry = Matrix6d::Identity();
  carry.bottomLeftCorner<3, 3>() = -arm_cross;
  state_.covariance = carry * keyframe_covariance_ * carry.transpose() +
                      turn * estimate.covariance * turn.transpose();
  state_.status = OdometryState::Status::tracking;
  state_.quality = static_cast<int>(std::clamp(
      std::lround(100.0 * estimate.inliers / (4.0 * config_.motion.min_inliers)), 1L, 100L));

  const double keyframe_angle = Eigen::AngleAxisd(since_keyframe_.rotation).angle();
  const double keyframe_distance = since_keyframe_.inverse().translation.norm();
  if (estimate.inliers < config_.keyframe_inlier_ratio * landmark_count_ ||
      keyframe_distance > config_.keyframe_distance_m ||
      keyframe_angle > radians(config_.keyframe_angle_deg)) {
    make_keyframe(left, points);  // too few features: the old keyframe stays
  }
  return state_;
}

}  // namespace epipole::firmware

#include "epipole/firmware/odometry_messages.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "epipole/core/angles.hpp"
#include "wire_units.hpp"

namespace epipole::firmware {

using detail::in_units;

namespace {

// The unit quaternion of a rotation, w >= 0 (q and -q are the same rotation).
Eigen::Quaterniond unit_quaternion(const Eigen::Matrix3d& rotation) {
  Eigen::Quaterniond q(rotation);
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

// Camera axes (x right, y down, z forward) to a body's FRD (x forward, y right, z down).
Eigen::Matrix3d camera_to_frd() {
  Eigen::Matrix3d p;
  p << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  return p;
}

std::uint64_t non_negative_us(hal::Nanoseconds ns) {
  return static_cast<std::uint64_t>(std::max<hal::Nanoseconds>(ns, 0)) / 1000;
}

}  // namespace

protocol::Odometry odometry_message(const OdometryState& s, std::uint32_t frame,
                                    hal::Nanoseconds trigger_ns) {
  protocol::Odometry m;
  m.frame = frame;
  m.trigger_ns = static_cast<std::uint64_t>(std::max<hal::Nanoseconds>(trigger_ns, 0));
  m.reset_counter = s.reset_counter;
  m.keyframes = s.keyframes;
  if (s.status == OdometryState::Status::starting) return m;
  m.status = s.status == OdometryState::Status::tracking ? protocol::OdometryStatus::tracking
                                                         : protocol::OdometryStatus::lost;
  m.quality = static_cast<std::uint8_t>(std::clamp(s.quality, 0, 100));
  const Eigen::Vector3d& t = s.pose.translation;
  m.x_mm = in_units<std::int32_t>(t.x(), 1e-3);
  m.y_mm = in_units<std::int32_t>(t.y(), 1e-3);
  m.z_mm = in_units<std::int32_t>(t.z(), 1e-3);
  const Eigen::Quaterniond q = unit_quaternion(s.pose.rotation);
  m.qw_e9 = in_units<std::int32_t>(q.w(), 1e-9);
  m.qx_e9 = in_units<std::int32_t>(q.x(), 1e-9);
  m.qy_e9 = in_units<std::int32_t>(q.y(), 1e-9);
  m.qz_e9 = in_units<std::int32_t>(q.z(), 1e-9);
  m.vx_mm_s = in_units<std::int32_t>(s.velocity.x(), 1e-3);
  m.vy_mm_s = in_units<std::int32_t>(s.velocity.y(), 1e-3);
  m.vz_mm_s = in_units<std::int32_t>(s.velocity.z(), 1e-3);
  m.wx_mrad_s = in_units<std::int32_t>(s.angular_velocity.x(), 1e-3);
  m.wy_mrad_s = in_units<std::int32_t>(s.angular_velocity.y(), 1e-3);
  m.wz_mrad_s = in_units<std::int32_t>(s.angular_velocity.z(), 1e-3);
  // The covariance is of (rotation vector, translation).
  const auto sigma = [&](int i) { return std::sqrt(std::max(s.covariance(i, i), 0.0)); };
  m.srx_cdeg = in_units<std::uint16_t>(sigma(0), radians(0.01));
  m.sry_cdeg = in_units<std::uint16_t>(sigma(1), radians(0.01));
  m.srz_cdeg = in_units<std::uint16_t>(sigma(2), radians(0.01));
  m.sx_mm = in_units<std::uint16_t>(sigma(3), 1e-3);
  m.sy_mm = in_units<std::uint16_t>(sigma(4), 1e-3);
  m.sz_mm = in_units<std::uint16_t>(sigma(5), 1e-3);
  m.features = detail::saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(s.features, 0)));
  m.tracked = detail::saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(s.tracked, 0)));
  m.inliers = detail::saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(s.inliers, 0)));
  return m;
}

mavlink::Odometry mavlink_odometry(const OdometryState& s, hal::Nanoseconds trigger_ns) {
  const Eigen::Matrix3d p = camera_to_frd();
  mavlink::Odometry m;
  m.time_usec = non_negative_us(trigger_ns);
  const Eigen::Vector3d position = p * s.pose.translation;
  m.x = static_cast<float>(position.x());
  m.y = static_cast<float>(position.y());
  m.z = static_cast<float>(position.z());
  const Eigen::Quaterniond q = unit_quaternion(p * s.pose.rotation * p.transpose());
  m.q = {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()),
         static_cast<float>(q.z())};
  const Eigen::Vector3d velocity = p * (s.pose.rotation.transpose() * s.velocity);
  const Eigen::Vector3d rates = p * s.angular_velocity;
  m.vx = static_cast<float>(velocity.x());
  m.vy = static_cast<float>(velocity.y());
  m.vz = static_cast<float>(velocity.z());
  m.rollspeed = static_cast<float>(rates.x());
  m.pitchspeed = static_cast<float>(rates.y());
  m.yawspeed = static_cast<float>(rates.z());
  // (rotation vector, translation) in the camera's axes to (translation, rotation) in FRD's.
  Eigen::Matrix<double, 6, 6> j = Eigen::Matrix<double, 6, 6>::Zero();
  j.block<3, 3>(0, 3) = p;
  j.block<3, 3>(3, 0) = p;
  const Eigen::Matrix<double, 6, 6> c = j * s.covariance * j.transpose();
  std::size_t k = 0;
  for (int row = 0; row < 6; ++row) {
    for (int col = row; col < 6; ++col) m.pose_covariance[k++] = static_cast<float>(c(row, col));
  }
  m.velocity_covariance.fill(0.0f);
  m.velocity_covariance[0] = std::numeric_limits<float>::quiet_NaN();
  m.reset_counter = s.reset_counter;
  m.quality = static_cast<std::int8_t>(
      s.status == OdometryState::Status::lost ? -1 : std::clamp(s.quality, 0, 100));
  return m;
}

}  // namespace epipole::firmware

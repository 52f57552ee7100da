// The odometry as the robot receives it: the native message's units, and MAVLink's ODOMETRY in
// the frames PX4 and ArduPilot expect (LOCAL_FRD / BODY_FRD), from a state with known motion.
#include "epipole/firmware/odometry_messages.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "epipole/core/angles.hpp"

namespace epipole::firmware {
namespace {

// The camera 2 m ahead of where it started (its z), 0.5 m right, turned 90 degrees to the right
// (about its y, which points down), moving at 1 m/s along the odometry frame's x (its own
// forward now) and still turning right at 0.5 rad/s.
OdometryState turned_right() {
  OdometryState s;
  s.status = OdometryState::Status::tracking;
  s.pose.rotation = Eigen::AngleAxisd(radians(90), Eigen::Vector3d::UnitY()).toRotationMatrix();
  s.pose.translation = {0.5, 0.0, 2.0};
  s.velocity = {1.0, 0.0, 0.0};
  s.angular_velocity = {0.0, 0.5, 0.0};
  s.covariance.diagonal() << 1e-4, 4e-4, 9e-4, 1e-2, 2e-2, 3e-2;
  s.quality = 87;
  s.reset_counter = 2;
  s.features = 500;
  s.tracked = 420;
  s.inliers = 400;
  s.keyframes = 9;
  return s;
}

TEST(OdometryMessages, TheNativeMessageInTheProtocolsUnits) {
  const protocol::Odometry m = odometry_message(turned_right(), 77, 5'000'000'123);
  EXPECT_EQ(m.frame, 77u);
  EXPECT_EQ(m.trigger_ns, 5'000'000'123u);
  EXPECT_EQ(m.status, protocol::OdometryStatus::tracking);
  EXPECT_EQ(m.quality, 87);
  EXPECT_EQ(m.reset_counter, 2);
  EXPECT_EQ(m.x_mm, 500);
  EXPECT_EQ(m.y_mm, 0);
  EXPECT_EQ(m.z_mm, 2000);
  EXPECT_EQ(m.qw_e9, 707'106'781);
  EXPECT_EQ(m.qy_e9, 707'106'781);
  EXPECT_EQ(m.qx_e9, 0);
  EXPECT_EQ(m.vx_mm_s, 1000);
  EXPECT_EQ(m.wy_mrad_s, 500);
  EXPECT_EQ(m.srx_cdeg, std::lround(degrees(0.01) * 100));
  EXPECT_EQ(m.srz_cdeg, std::lround(degrees(0.03) * 100));
  EXPECT_EQ(m.sx_mm, 100);
  EXPECT_EQ(m.sy_mm, std::lround(std::sqrt(2e-2) * 1000));
  EXPECT_EQ(m.features, 500);
  EXPECT_EQ(m.tracked, 420);
  EXPECT_EQ(m.inliers, 400);
  EXPECT_EQ(m.keyframes, 9u);
}

TEST(OdometryMessages, StartingSaysNothingButItsFrameAndLostKeepsThePose) {
  OdometryState s = turned_right();
  s.status = OdometryState::Status::starting;
  protocol::Odometry m = odometry_message(s, 1, 10);
  EXPECT_EQ(m.status, protocol::OdometryStatus::starting);
  EXPECT_EQ(m.x_mm, 0);
  EXPECT_EQ(m.qw_e9, 1'000'000'000);
  EXPECT_EQ(m.quality, 0);
  s.status = OdometryState::Status::lost;
  s.quality = -1;
  m = odometry_message(s, 2, 20);
  EXPECT_EQ(m.status, protocol::OdometryStatus::lost);
  EXPECT_EQ(m.quality, 0);
  EXPECT_EQ(m.z_mm, 2000) << "the last pose, kept";
  EXPECT_EQ(mavlink_odometry(s, 20).quality, -1) << "MAVLink's 'failed'";
}

// FRD: x along the optical axis, y right, z down. The camera went 2 m forward and 0.5 m right,
// then yawed right by 90 degrees (positive about z down); moving forward, turning right.
TEST(OdometryMessages, MavlinkOdometryInTheVehiclesFrames) {
  const mavlink::Odometry m = mavlink_odometry(turned_right(), 5'000'000'123);
  EXPECT_EQ(m.time_usec, 5'000'000u);
  EXPECT_EQ(m.frame_id, mavlink::kMavFrameLocalFrd);
  EXPECT_EQ(m.child_frame_id, mavlink::kMavFrameBodyFrd);
  EXPECT_EQ(m.estimator_type, mavlink::kMavEstimatorTypeVio);
  EXPECT_FLOAT_EQ(m.x, 2.0f);
  EXPECT_FLOAT_EQ(m.y, 0.5f);
  EXPECT_NEAR(m.z, 0.0f, 1e-7);
  EXPECT_NEAR(m.q[0], std::sqrt(0.5), 1e-7);  // w
  EXPECT_NEAR(m.q[1], 0.0, 1e-7);
  EXPECT_NEAR(m.q[2], 0.0, 1e-7);
  EXPECT_NEAR(m.q[3], std::sqrt(0.5), 1e-7);  // about z down: yaw right
  EXPECT_NEAR(m.vx, 1.0f, 1e-7) << "in the body's frame: straight ahead";
  EXPECT_NEAR(m.vy, 0.0f, 1e-7);
  EXPECT_NEAR(m.vz, 0.0f, 1e-7);
  EXPECT_NEAR(m.yawspeed, 0.5f, 1e-7);
  EXPECT_NEAR(m.rollspeed, 0.0f, 1e-7);
  // Upper triangle, row-major: (x,x) 0, (y,y) 6, (z,z) 11, (roll,roll) 15, (pitch,pitch) 18,
  // (yaw,yaw) 20; x is the camera's z, y its x, z its y.
  EXPECT_FLOAT_EQ(m.pose_covariance[0], 3e-2f);
  EXPECT_FLOAT_EQ(m.pose_covariance[6], 1e-2f);
  EXPECT_FLOAT_EQ(m.pose_covariance[11], 2e-2f);
  EXPECT_FLOAT_EQ(m.pose_covariance[15], 9e-4f);
  EXPECT_FLOAT_EQ(m.pose_covariance[18], 1e-4f);
  EXPECT_FLOAT_EQ(m.pose_covariance[20], 4e-4f);
  EXPECT_FLOAT_EQ(m.pose_covariance[1], 0.0f);
  EXPECT_TRUE(std::isnan(m.velocity_covariance[0])) << "unknown";
  EXPECT_EQ(m.reset_counter, 2);
  EXPECT_EQ(m.quality, 87);
}

}  // namespace
}  // namespace epipole::firmware

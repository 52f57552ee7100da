#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/p3p.hpp"
#include "epipole/core/image.hpp"
#include "sim/sim_files.hpp"
#include "sim/world_settings.hpp"

namespace epipole::hal {

// A world (world_settings.hpp: SimWorld, RigPose) rendered by the simulated cameras through a
// rig's calibration, and its exact truth (builds with image files; world_scene.cpp).
//
// The cameras' orientation: level, the left camera's x, y, z (OpenCV's: right, down, forward)
// are the world's X, -Y, Z; pitch turns z down (z = (0, -sin p, cos p)), roll then turns x
// towards y about z (positive: the image's right side lower), yaw turns the level heading
// towards +X. The right camera is where the calibration puts it (x_right = R x_left + T).

// The raw pairs of the world seen from world_poses(world) (world.frames pairs of one geometry, or
// one pair per pose of its path), each camera's noise its own per frame (deterministic). Each raw
// pixel averages 2x2 rays cast through PinholeCamera::normalize() (distortion included; a ray
// outside the lens's domain is black), the nearest hit's texture sampled trilinearly from its mip
// pyramid at the ray's footprint; no hit is black. Textures are read with load_gray. Throws Error
// when the calibration is not width x height, or naming a texture that cannot be read.
StereoImages render_world(const SimWorld& world, const calib::StereoCalibration& rig, int width,
                          int height);
// The same, one pair per pose (a trajectory), frame i's noise that of frame i above; pairs of
// the same pose as the one before are rendered once.
StereoImages render_world(const SimWorld& world, std::span<const RigPose> poses,
                          const calib::StereoCalibration& rig, int width, int height);

// The rectified left camera's pose at each pair of world_poses(world), in the first pair's
// rectified left camera frame (where the firmware's odometry starts): the odometry's truth.
// odometry point = trajectory[i].apply(point in pair i's rectified left frame).
std::vector<calib::RigidMotion> world_trajectory(const SimWorld& world,
                                                 const calib::StereoCalibration& rig);

// Poses as a TUM trajectory file's lines (timestamp tx ty tz qx qy qz qw), pose i at i / rate_hz.
std::string tum_trajectory(std::span<const calib::RigidMotion> poses, double rate_hz);
// One pose's line of a TUM trajectory file at `seconds`.
std::string tum_line(double seconds, const calib::RigidMotion& pose);

// The floor in the rectified left camera frame (R1 * left), as the firmware defines it.
struct GroundTruth {
  Eigen::Vector3d normal_down = Eigen::Vector3d::Zero();  // unit, from the camera to the floor
  double height_m = 0;   // the camera centre's distance from the floor
  double pitch_deg = 0;  // asin(normal_down.z): looking down positive
  double roll_deg = 0;   // atan2(normal_down.x, normal_down.y): right side lower positive
};
GroundTruth ground_truth(const RigPose& pose, const calib::StereoCalibration& rig);
GroundTruth world_ground_truth(const SimWorld& world, const calib::StereoCalibration& rig);

// The rectified left view's truth, rig.width x rig.height (P1's pixels): for each pixel the
// depth Z (rectified left frame, metres) of the nearest hit of its ray and the disparity Q
// gives that depth; both 0 where the ray hits nothing.
struct TrueDepth {
  Image<float> disparity;
  Image<float> depth_m;
};
TrueDepth world_true_depth(const SimWorld& world, const RigPose& pose,
                           const calib::StereoCalibration& rig);
Image<float> world_true_disparity(const SimWorld& world, const calib::StereoCalibration& rig);

// The disparity of depth z (rectified left frame) by the rig's Q.
double disparity_of_depth(const calib::StereoCalibration& rig, double z);

// Writes into `directory` (made when missing): truth.yaml (the GroundTruth of world.rig, the
// pose, the wall's distance, each box's front face and X range) and true_disparity.png (16-bit,
// disparity x 16, 0 unknown). Throws Error naming the file.
void write_world_truth(const SimWorld& world, const calib::StereoCalibration& rig,
                       const std::filesystem::path& directory);

}  // namespace epipole::hal

#pragma once

// ROS 2 messages of a pair's results, in CDR (epipole/core/cdr_writer.hpp), with their `ros2msg`
// schemas: what the recordings hold and what the graph and the live view carry. Each write_*()
// appends one whole message (its encapsulation header first) to a buffer the caller owns; none
// allocates when the buffer's capacity holds it.

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/disparity_plane.hpp"
#include "epipole/calib/triangulation.hpp"
#include "epipole/core/image.hpp"
#include "epipole/firmware/depth_cells.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/firmware/sparse_points.hpp"

namespace epipole::firmware::ros {

// A message type: its ROS name and its definition with those of the types it uses, as `ros2msg`
// schemas hold them (each dependency after a line of 80 '=' and "MSG: <type>").
struct MessageType {
  std::string_view name;  // "sensor_msgs/msg/Image"
  std::string_view schema;
};
MessageType image_type();
MessageType camera_info_type();
MessageType disparity_image_type();
MessageType point_cloud_type();
MessageType tf_message_type();
MessageType diagnostic_array_type();

// builtin_interfaces/Time of a time on the system clock (ns since the epoch).
struct Time {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
};
Time time_of(std::int64_t system_ns);

// A rectified camera as sensor_msgs/CameraInfo describes it: no distortion, R the identity,
// K the left 3x3 of P; the right camera's P[3] is -fx * baseline (metres).
struct RectifiedCamera {
  int width = 0, height = 0;
  std::array<double, 12> p{};  // row-major 3x4
};
RectifiedCamera rectified_left(const calib::StereoCalibration& calibration);
RectifiedCamera rectified_right(const calib::StereoCalibration& calibration);
// K: the left 3x3 of P, row-major.
std::array<double, 9> camera_k(const RectifiedCamera& camera);

// The ground's frame seen from the camera's optical frame (a transform parent: optical, child:
// ground): its origin the foot of the camera on the ground (distance along the normal), z up
// (against the downward normal), x the optical axis along the ground (the camera's heading), y
// to its left (REP 103). Rotation as x y z w.
struct GroundTransform {
  std::array<double, 3> translation{};
  std::array<double, 4> rotation{};
};
GroundTransform ground_transform(const calib::MetricPlane& ground);

// The rotation of a body frame (x forward, y left, z up) to its optical frame (z forward, x
// right, y down), REP 103, as x y z w.
inline constexpr std::array<double, 4> kBodyToOptical = {-0.5, 0.5, -0.5, 0.5};

// The rig's fixed transforms: <prefix>left (x forward, y left, z up) to its optical frame (z
// forward, x right, y down), and the left optical frame to the right one (the baseline along x).
struct FrameNames {
  std::string_view left_body;     // "epipole_left"
  std::string_view left_optical;  // "epipole_left_optical_frame"
  std::string_view right_optical;
};

// The pixel data of the messages, shared by every output that sends them (little endian, rows
// without padding): written into `out`, which holds width * height values (features: 4 floats a
// point).
void disparity_pixels(ImageView<const std::int16_t> disparity16, float* out);  // -1: none
void depth_pixels(ImageView<const std::int16_t> disparity16,
                  std::span<const std::uint16_t> depth_mm, std::uint16_t* out);  // 0: unknown
void feature_points(std::span<const SparsePoint> points, GrayView left, float* out);
// The organised cloud of every `step`th pixel of every `step`th row: x y z (metres, NaN where
// the disparity has none) and intensity, 4 floats a point; (width / step) x (height / step).
// With `keep`, points whose pixel is outside it are NaN too (the ground's PixelHalfSpace: only
// what stands clear of the ground).
void organised_points(ImageView<const std::int16_t> disparity16, GrayView left,
                      const calib::Triangulator& triangulator, int step, float* out,
                      const PixelHalfSpace* keep = nullptr);

void write_image(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                 GrayView image);
// 16UC1, millimetres along the optical axis, 0 where unknown (REP 118), from the disparity x16
// through a table of depths by disparity (depth_mm_by_disparity16).
void write_depth_image(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                       ImageView<const std::int16_t> disparity16,
                       std::span<const std::uint16_t> depth_mm);
// The depth in millimetres of every disparity x16 up to max_disparity * 16 (0: none, or beyond
// 65535 mm), for write_depth_image().
std::vector<std::uint16_t> depth_mm_by_disparity16(const calib::Triangulator& triangulator,
                                                   int max_disparity);
void write_camera_info(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                       const RectifiedCamera& camera);
// stereo_msgs/DisparityImage: 32FC1 disparities in pixels, -1 where there is none; f the focal
// length in pixels, t the baseline in metres (0 and 0 without a calibration).
void write_disparity_image(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                           ImageView<const std::int16_t> disparity16, float f, float t,
                           int max_disparity);
// The sparse 3-D points as an unorganised cloud: x y z (metres, the left optical frame) and
// intensity (the rectified left image at the point; 0 without it), float32 each.
void write_feature_cloud(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                         std::span<const SparsePoint> points, GrayView left);
// An organised cloud of width x height points, 4 floats each (organised_points()), NaN where
// unknown.
void write_point_cloud(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                       std::size_t width, std::size_t height, const float* points);
void write_rig_transforms(std::vector<std::uint8_t>& out, Time stamp, const FrameNames& frames,
                          double baseline_m);

}  // namespace epipole::firmware::ros

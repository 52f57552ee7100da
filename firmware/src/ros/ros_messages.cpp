#include "ros/ros_messages.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "epipole/core/cdr_writer.hpp"
#include "epipole/core/error.hpp"
#include "epipole/vision/stereo.hpp"
#include "ros/message_schema.hpp"

namespace epipole::firmware::ros {

using cdr::CdrWriter;

static_assert(std::endian::native == std::endian::little, "CDR is written as little endian");

namespace {

// The message definitions (ROS 2's own .msg files, without their comments).
constexpr std::string_view kImage =
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n"
    "uint32 step\nuint8[] data\n";
constexpr std::string_view kRegionOfInterest =
    "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n";
constexpr std::string_view kCameraInfo =
    "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\n"
    "float64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n"
    "sensor_msgs/RegionOfInterest roi\n";
constexpr std::string_view kDisparityImage =
    "std_msgs/Header header\nsensor_msgs/Image image\nfloat32 f\nfloat32 t\n"
    "sensor_msgs/RegionOfInterest valid_window\nfloat32 min_disparity\nfloat32 max_disparity\n"
    "float32 delta_d\n";
constexpr std::string_view kPointField =
    "uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\nuint8 INT32 = 5\n"
    "uint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\nstring name\nuint32 offset\n"
    "uint8 datatype\nuint32 count\n";
constexpr std::string_view kPointCloud2 =
    "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\n"
    "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n";
constexpr std::string_view kVector3 = "float64 x\nfloat64 y\nfloat64 z\n";
constexpr std::string_view kQuaternion = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
constexpr std::string_view kTransform =
    "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n";
constexpr std::string_view kTransformStamped =
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n";
constexpr std::string_view kTFMessage = "geometry_msgs/TransformStamped[] transforms\n";
constexpr std::string_view kDiagnosticArray =
    "std_msgs/Header header\ndiagnostic_msgs/DiagnosticStatus[] status\n";
constexpr std::string_view kDiagnosticStatus =
    "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\nbyte level\nstring name\n"
    "string message\nstring hardware_id\ndiagnostic_msgs/KeyValue[] values\n";
constexpr std::string_view kKeyValue = "string key\nstring value\n";

void header(CdrWriter& w, Time stamp, std::string_view frame) {
  w.i32(stamp.sec);
  w.u32(stamp.nanosec);
  w.string(frame);
}

void image_fields(CdrWriter& w, int width, int height, std::string_view encoding, int step) {
  w.u32(static_cast<std::uint32_t>(height));
  w.u32(static_cast<std::uint32_t>(width));
  w.string(encoding);
  w.u8(0);  // little endian
  w.u32(static_cast<std::uint32_t>(step));
}

void region(CdrWriter& w, int x, int y, int width, int height) {
  w.u32(static_cast<std::uint32_t>(x));
  w.u32(static_cast<std::uint32_t>(y));
  w.u32(static_cast<std::uint32_t>(height));
  w.u32(static_cast<std::uint32_t>(width));
  w.boolean(false);
}

void point_field(CdrWriter& w, std::string_view name, std::uint32_t offset) {
  w.string(name);
  w.u32(offset);
  w.u8(7);  // FLOAT32
  w.u32(1);
}

}  // namespace

MessageType image_type() {
  static std::string s;
  static const std::string_view text = schema(s, kImage, {kHeaderDeps[0], kHeaderDeps[1]});
  return {"sensor_msgs/msg/Image", text};
}

MessageType camera_info_type() {
  static std::string s;
  static const std::string_view text =
      schema(s, kCameraInfo,
             {kHeaderDeps[0], kHeaderDeps[1], {"sensor_msgs/RegionOfInterest", kRegionOfInterest}});
  return {"sensor_msgs/msg/CameraInfo", text};
}

MessageType disparity_image_type() {
  static std::string s;
  static const std::string_view text =
      schema(s, kDisparityImage,
             {kHeaderDeps[0],
              kHeaderDeps[1],
              {"sensor_msgs/Image", kImage},
              {"sensor_msgs/RegionOfInterest", kRegionOfInterest}});
  return {"stereo_msgs/msg/DisparityImage", text};
}

MessageType point_cloud_type() {
  static std::string s;
  static const std::string_view text = schema(
      s, kPointCloud2, {kHeaderDeps[0], kHeaderDeps[1], {"sensor_msgs/PointField", kPointField}});
  return {"sensor_msgs/msg/PointCloud2", text};
}

MessageType tf_message_type() {
  static std::string s;
  static const std::string_view text =
      schema(s, kTFMessage,
             {{"geometry_msgs/TransformStamped", kTransformStamped},
              kHeaderDeps[0],
              kHeaderDeps[1],
              {"geometry_msgs/Transform", kTransform},
              {"geometry_msgs/Vector3", kVector3},
              {"geometry_msgs/Quaternion", kQuaternion}});
  return {"tf2_msgs/msg/TFMessage", text};
}

MessageType diagnostic_array_type() {
  static std::string s;
  static const std::string_view text =
      schema(s, kDiagnosticArray,
             {kHeaderDeps[0],
              kHeaderDeps[1],
              {"diagnostic_msgs/DiagnosticStatus", kDiagnosticStatus},
              {"diagnostic_msgs/KeyValue", kKeyValue}});
  return {"diagnostic_msgs/msg/DiagnosticArray", text};
}

Time time_of(std::int64_t system_ns) {
  std::int64_t sec = system_ns / 1'000'000'000;
  std::int64_t nsec = system_ns % 1'000'000'000;
  if (nsec < 0) {
    nsec += 1'000'000'000;
    --sec;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nsec)};
}

namespace {

RectifiedCamera rectified(const calib::StereoCalibration& c, const calib::CameraCalibration& cam) {
  RectifiedCamera r;
  r.width = c.width;
  r.height = c.height;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) r.p[static_cast<std::size_t>(i * 4 + j)] = cam.projection(i, j);
  }
  return r;
}

}  // namespace

RectifiedCamera rectified_left(const calib::StereoCalibration& c) {
  return rectified(c, c.left);
}
RectifiedCamera rectified_right(const calib::StereoCalibration& c) {
  return rectified(c, c.right);
}

std::array<double, 9> camera_k(const RectifiedCamera& camera) {
  const auto& p = camera.p;
  return {p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]};
}

void write_image(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                 GrayView image) {
  CdrWriter w(out);
  header(w, stamp, frame);
  image_fields(w, image.width(), image.height(), "mono8", image.width());
  std::uint8_t* data = w.byte_sequence(static_cast<std::size_t>(image.width()) * image.height());
  for (int y = 0; y < image.height(); ++y) {
    std::memcpy(data + static_cast<std::size_t>(y) * image.width(), image.row(y),
                static_cast<std::size_t>(image.width()));
  }
}

std::vector<std::uint16_t> depth_mm_by_disparity16(const calib::Triangulator& triangulator,
                                                   int max_disparity) {
  std::vector<std::uint16_t> table(static_cast<std::size_t>(max_disparity) * 16 + 1, 0);
  for (std::size_t d = 1; d < table.size(); ++d) {
    const double z_mm = triangulator.depth(static_cast<double>(d) / 16.0) * 1000.0;
    if (std::isfinite(z_mm) && z_mm > 0 && z_mm < 65535.5) {
      table[d] = static_cast<std::uint16_t>(std::lround(z_mm));
    }
  }
  return table;
}

void disparity_pixels(ImageView<const std::int16_t> disparity16, float* out) {
  for (int y = 0; y < disparity16.height(); ++y) {
    const std::int16_t* row = disparity16.row(y);
    float* to = out + static_cast<std::size_t>(y) * disparity16.width();
    for (int x = 0; x < disparity16.width(); ++x) {
      to[x] = row[x] == vision::kInvalidDisparity ? -1.0f : static_cast<float>(row[x]) / 16;
    }
  }
}

void depth_pixels(ImageView<const std::int16_t> disparity16,
                  std::span<const std::uint16_t> depth_mm, std::uint16_t* out) {
  for (int y = 0; y < disparity16.height(); ++y) {
    const std::int16_t* row = disparity16.row(y);
    std::uint16_t* to = out + static_cast<std::size_t>(y) * disparity16.width();
    for (int x = 0; x < disparity16.width(); ++x) {
      const int d = row[x];
      to[x] = d > 0 && static_cast<std::size_t>(d) < depth_mm.size() ? depth_mm[d] : 0;
    }
  }
}

namespace {

float intensity_at(GrayView left, int x, int y) {
  const bool inside = !left.empty() && x >= 0 && y >= 0 && x < left.width() && y < left.height();
  return inside ? static_cast<float>(left.row(y)[x]) : 0.0f;
}

}  // namespace

void feature_points(std::span<const SparsePoint> points, GrayView left, float* out) {
  for (const SparsePoint& p : points) {
    *out++ = p.x;
    *out++ = p.y;
    *out++ = p.z;
    *out++ = intensity_at(left, static_cast<int>(std::lround(p.xl)),
                          static_cast<int>(std::lround(p.yl)));
  }
}

void organised_points(ImageView<const std::int16_t> disparity16, GrayView left,
                      const calib::Triangulator& triangulator, int step, float* out,
                      const PixelHalfSpace* keep) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto kept = [keep](int x, int y, double d) {
    return keep == nullptr ||
           keep->u_factor * x + keep->v_factor * y + keep->d_factor * d + keep->constant >= 0;
  };
  for (int j = 0; j < disparity16.height() / step; ++j) {
    const int y = j * step;
    for (int i = 0; i < disparity16.width() / step; ++i) {
      const int x = i * step;
      const int d = disparity16.row(y)[x];
      const double none = std::numeric_limits<double>::quiet_NaN();
      Eigen::Vector3d p(none, none, none);
      if (d != vision::kInvalidDisparity && d > 0 && kept(x, y, d / 16.0)) {
        p = triangulator.point(x, y, d / 16.0);
      }
      const bool finite = p.allFinite();
      *out++ = finite ? static_cast<float>(p.x()) : nan;
      *out++ = finite ? static_cast<float>(p.y()) : nan;
      *out++ = finite ? static_cast<float>(p.z()) : nan;
      *out++ = intensity_at(left, x, y);
    }
  }
}

GroundTransform ground_transform(const calib::MetricPlane& ground) {
  const Eigen::Vector3d up = -ground.normal;
  // The optical axis along the ground; a camera looking straight down has none: its image's up.
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ() - up * up.z();
  if (forward.norm() < 1e-6) forward = -Eigen::Vector3d::UnitY() - up * -up.y();
  forward.normalize();
  Eigen::Matrix3d axes;  // the ground frame's axes in the optical frame, as columns
  axes.col(0) = forward;
  axes.col(1) = up.cross(forward);
  axes.col(2) = up;
  const Eigen::Quaterniond q(axes);
  const Eigen::Vector3d origin = ground.normal * ground.distance;
  return {{origin.x(), origin.y(), origin.z()}, {q.x(), q.y(), q.z(), q.w()}};
}

void write_depth_image(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                       ImageView<const std::int16_t> disparity16,
                       std::span<const std::uint16_t> depth_mm) {
  CdrWriter w(out);
  header(w, stamp, frame);
  const int width = disparity16.width();
  image_fields(w, width, disparity16.height(), "16UC1", width * 2);
  std::uint8_t* data = w.byte_sequence(static_cast<std::size_t>(width) * disparity16.height() * 2);
  // Row by row through an aligned row: the message may start anywhere in its buffer.
  std::array<std::uint16_t, 4096> row{};
  for (int y = 0; y < disparity16.height(); ++y) {
    for (int x0 = 0; x0 < width; x0 += static_cast<int>(row.size())) {
      const int n = std::min(width - x0, static_cast<int>(row.size()));
      depth_pixels(disparity16.sub(x0, y, n, 1), depth_mm, row.data());
      std::memcpy(data + (static_cast<std::size_t>(y) * width + x0) * 2, row.data(),
                  static_cast<std::size_t>(n) * 2);
    }
  }
}

void write_camera_info(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                       const RectifiedCamera& camera) {
  CdrWriter w(out);
  header(w, stamp, frame);
  w.u32(static_cast<std::uint32_t>(camera.height));
  w.u32(static_cast<std::uint32_t>(camera.width));
  w.string("plumb_bob");
  w.u32(5);  // d: no distortion left in rectified images
  for (int i = 0; i < 5; ++i) w.f64(0.0);
  w.f64s(camera_k(camera));
  const std::array<double, 9> r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  w.f64s(r);
  w.f64s(camera.p);
  w.u32(0);  // binning
  w.u32(0);
  region(w, 0, 0, 0, 0);  // the whole image
}

void write_disparity_image(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                           ImageView<const std::int16_t> disparity16, float f, float t,
                           int max_disparity) {
  CdrWriter w(out);
  header(w, stamp, frame);
  header(w, stamp, frame);  // the image's own header
  const int width = disparity16.width();
  image_fields(w, width, disparity16.height(), "32FC1", width * 4);
  std::uint8_t* data = w.byte_sequence(static_cast<std::size_t>(width) * disparity16.height() * 4);
  std::array<float, 2048> row{};  // aligned, as depth's
  for (int y = 0; y < disparity16.height(); ++y) {
    for (int x0 = 0; x0 < width; x0 += static_cast<int>(row.size())) {
      const int n = std::min(width - x0, static_cast<int>(row.size()));
      disparity_pixels(disparity16.sub(x0, y, n, 1), row.data());
      std::memcpy(data + (static_cast<std::size_t>(y) * width + x0) * 4, row.data(),
                  static_cast<std::size_t>(n) * 4);
    }
  }
  w.f32(f);
  w.f32(t);
  region(w, 0, 0, width, disparity16.height());
  w.f32(0.0f);
  w.f32(static_cast<float>(max_disparity));
  w.f32(1.0f / 16);
}

namespace {

// A cloud of x y z intensity (float32 each) up to its data, which the caller writes at the
// returned pointer (16 bytes a point), then closes with is_dense.
std::uint8_t* cloud(CdrWriter& w, Time stamp, std::string_view frame, std::size_t width,
                    std::size_t height) {
  header(w, stamp, frame);
  w.u32(static_cast<std::uint32_t>(height));
  w.u32(static_cast<std::uint32_t>(width));
  w.u32(4);
  point_field(w, "x", 0);
  point_field(w, "y", 4);
  point_field(w, "z", 8);
  point_field(w, "intensity", 12);
  w.boolean(false);
  w.u32(16);
  w.u32(static_cast<std::uint32_t>(16 * width));
  return w.byte_sequence(16 * width * height);
}

}  // namespace

void write_feature_cloud(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                         std::span<const SparsePoint> points, GrayView left) {
  CdrWriter w(out);
  std::uint8_t* data = cloud(w, stamp, frame, points.size(), 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    float point[4];
    feature_points(points.subspan(i, 1), left, point);
    std::memcpy(data + 16 * i, point, sizeof point);
  }
  w.boolean(true);  // every point is finite
}

void write_point_cloud(std::vector<std::uint8_t>& out, Time stamp, std::string_view frame,
                       std::size_t width, std::size_t height, const float* points) {
  CdrWriter w(out);
  std::memcpy(cloud(w, stamp, frame, width, height), points, 16 * width * height);
  w.boolean(false);  // NaN where a pixel has no disparity
}

void write_rig_transforms(std::vector<std::uint8_t>& out, Time stamp, const FrameNames& frames,
                          double baseline_m) {
  CdrWriter w(out);
  w.u32(2);
  // The body frame to the optical frame: z forward, x right, y down (REP 103).
  header(w, stamp, frames.left_body);
  w.string(frames.left_optical);
  for (int i = 0; i < 3; ++i) w.f64(0.0);
  w.f64s(kBodyToOptical);
  // The left optical frame to the right one, rectified: parallel, the baseline along x.
  header(w, stamp, frames.left_optical);
  w.string(frames.right_optical);
  for (const double v : {baseline_m, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0}) w.f64(v);
}

}  // namespace epipole::firmware::ros

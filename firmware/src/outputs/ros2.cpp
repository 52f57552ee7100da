// The ROS 2 output: the pairs' results as ROS 2 topics over DDS (CycloneDDS), an ordinary
// participant of the robot's ROS 2 graph with no ROS installation on the board (docs/ros2.md).
//
//   outputs:
//     ros2: {domain: 0, namespace: /epipole, frame_prefix: epipole_, interfaces: [lo],
//            multicast: false, peers: [127.0.0.1], depth: 5, points_step: 4,
//            every: {images: 1, camera_info: 1, disparity: 0, depth: 1, points: 1, features: 1}}

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "epipole/firmware/journal.hpp"
#include "output_files.hpp"
#include "ros/diagnostics.hpp"
#include "ros/rig_model.hpp"
#include "ros/ros_messages.hpp"
#include "ros2/dds_participant.hpp"
#include "ros2_types.h"
#include "system_time.hpp"

namespace epipole::firmware::outputs {

namespace {

// How often each group of topics is published: every Nth pair (by the pair's number), 0 never.
struct Rates {
  int images = 1;  // left/image_rect, right/image_rect
  int camera_info = 1;
  int disparity = 0;  // the depth and the points carry it already: on when asked for
  int depth = 1;
  int points = 1;
  int features = 1;
  int ground = 1;  // the ground's transform on /tf, when one is found
};

struct Ros2Settings final : OutputSettings {
  int domain = -1;  // -1: ROS_DOMAIN_ID, else 0
  ros::RosNames names;
  ros2::DdsNetwork network{{"lo"}, false, {"127.0.0.1"}};
  int depth = 5;
  int points_step = 4;
  bool points_above_ground = false;  // the ground stage's floor left out of `points`
  Rates every;
  std::unique_ptr<OutputSettings> clone() const override {
    return std::make_unique<Ros2Settings>(*this);
  }
};

std::vector<std::string> texts(const yaml::Fields& f, const YAML::Node& n, const std::string& key) {
  if (!n.IsSequence()) f.fail(key, "must be a list");
  std::vector<std::string> out;
  for (std::size_t i = 0; i < n.size(); ++i) out.push_back(f.text(n[i], cat(key, "[", i, "]")));
  return out;
}

void read_rates(const YAML::Node& n, const yaml::Fields& f, const std::string& path, Rates& r) {
  f.only_keys(n, path,
              {"images", "camera_info", "disparity", "depth", "points", "features", "ground"});
  const auto rate = [&](const char* key, int& out) {
    f.if_present(n, path, key, [&](const YAML::Node& v, const std::string& k) {
      out = f.integer_in(v, k, 0, 1000);
    });
  };
  rate("images", r.images);
  rate("camera_info", r.camera_info);
  rate("disparity", r.disparity);
  rate("depth", r.depth);
  rate("points", r.points);
  rate("features", r.features);
  rate("ground", r.ground);
}

std::unique_ptr<OutputSettings> read_settings(const YAML::Node& n, const yaml::Fields& f) {
  auto s = std::make_unique<Ros2Settings>();
  if (!n.IsDefined() || n.IsNull()) return s;
  const std::string path = "outputs.ros2";
  f.only_keys(n, path,
              {"domain", "namespace", "frame_prefix", "interfaces", "multicast", "peers", "depth",
               "points_step", "points_above_ground", "every"});
  f.if_present(n, path, "domain", [&](const YAML::Node& v, const std::string& k) {
    s->domain = f.integer_in(v, k, 0, 232);
  });
  ros::read_ros_names(n, f, path, s->names);
  bool loopback_only = true;
  f.if_present(n, path, "interfaces", [&](const YAML::Node& v, const std::string& k) {
    s->network.interfaces = texts(f, v, k);
    loopback_only = s->network.interfaces == std::vector<std::string>{"lo"};
  });
  // Loopback carries no multicast: the board's own peers are asked directly.
  s->network.multicast = !loopback_only;
  if (!loopback_only) s->network.peers.clear();
  f.if_present(n, path, "multicast", [&](const YAML::Node& v, const std::string& k) {
    s->network.multicast = f.boolean(v, k);
  });
  f.if_present(n, path, "peers", [&](const YAML::Node& v, const std::string& k) {
    s->network.peers = texts(f, v, k);
  });
  if (!s->network.multicast && s->network.peers.empty()) {
    f.fail(path + ".peers", "without multicast DDS needs the addresses of its peers");
  }
  f.if_present(n, path, "depth", [&](const YAML::Node& v, const std::string& k) {
    s->depth = f.integer_in(v, k, 1, 100);
  });
  f.if_present(n, path, "points_step", [&](const YAML::Node& v, const std::string& k) {
    s->points_step = f.integer_in(v, k, 1, 64);
  });
  f.if_present(n, path, "points_above_ground", [&](const YAML::Node& v, const std::string& k) {
    s->points_above_ground = f.boolean(v, k);
  });
  f.if_present(n, path, "every",
               [&](const YAML::Node& v, const std::string& k) { read_rates(v, f, k, s->every); });
  return s;
}

int domain_of(const Ros2Settings& s) {
  if (s.domain >= 0) return s.domain;
  const char* id = std::getenv("ROS_DOMAIN_ID");  // as ROS 2 nodes take it
  if (id == nullptr || *id == '\0') return 0;
  char* end = nullptr;
  const long value = std::strtol(id, &end, 10);
  require(*end == '\0' && value >= 0 && value <= 232, "ROS_DOMAIN_ID=", id,
          ": not a domain (0..232)");
  return static_cast<int>(value);
}

bool due(int every, std::uint32_t frame) {
  return every > 0 && frame % static_cast<std::uint32_t>(every) == 0;
}

// A string field of a sample: DDS only reads it.
char* text(const std::string& s) {
  return const_cast<char*>(s.c_str());
}
char* text(const char* s) {
  return const_cast<char*>(s);
}

template <typename Sequence, typename T>
void borrow(Sequence& sequence, T* data, std::size_t count) {
  sequence._buffer = data;
  sequence._length = static_cast<std::uint32_t>(count);
  sequence._maximum = static_cast<std::uint32_t>(count);
  sequence._release = false;
}

void set_header(std_msgs_msg_dds__Header_& h, ros::Time t, const std::string& frame) {
  h.stamp.sec = t.sec;
  h.stamp.nanosec = t.nanosec;
  h.frame_id = text(frame);
}

void set_image(sensor_msgs_msg_dds__Image_& m, ros::Time t, const std::string& frame,
               const char* encoding, int width, int height, std::size_t step, const void* data) {
  set_header(m.header, t, frame);
  m.height = static_cast<std::uint32_t>(height);
  m.width = static_cast<std::uint32_t>(width);
  m.encoding = text(encoding);
  m.is_bigendian = 0;
  m.step = static_cast<std::uint32_t>(step);
  borrow(m.data, static_cast<std::uint8_t*>(const_cast<void*>(data)), step * height);
}

// x y z intensity, float32 each.
std::array<sensor_msgs_msg_dds__PointField_, 4> point_fields() {
  std::array<sensor_msgs_msg_dds__PointField_, 4> f{};
  const char* names[] = {"x", "y", "z", "intensity"};
  for (std::size_t i = 0; i < f.size(); ++i) {
    f[i].name = text(names[i]);
    f[i].offset = static_cast<std::uint32_t>(4 * i);
    f[i].datatype = 7;  // FLOAT32
    f[i].count = 1;
  }
  return f;
}

class Ros2Output final : public Output {
 public:
  explicit Ros2Output(const OutputContext& context)
      : settings_(settings_of<Ros2Settings>(context, "ros2")),
        board_(context.board),
        calibration_(context.calibration),
        rig_(settings_.names, context.calibration, context.board.stereo.max_disparity),
        fields_(point_fields()),
        delivery_(
            "ros2", context.board, kRectified | kDisparity | kPoints,
            [this](const PairCopy& pair) { publish(pair); },
            [this](const HealthReport& report) { publish_health(report); }) {
    const std::size_t pixels = static_cast<std::size_t>(board_.width()) * board_.height();
    disparity_.resize(pixels);
    if (calibration_) {
      triangulator_.emplace(*calibration_);
      depth_.resize(pixels);
      const int step = settings_.points_step;
      cloud_.resize(static_cast<std::size_t>(board_.width() / step) * (board_.height() / step) * 4);
      features_.resize(static_cast<std::size_t>(board_.sparse.max_matches) * 4);
    }
    if (!context.offline) join_graph();
  }

  void start() override { delivery_.start(); }
  void stop() override { delivery_.stop(); }
  void offer(const FrameResult& result, const PairStamp& stamp) override {
    const Rates& e = settings_.every;
    const std::uint32_t f = result.frame;
    if (due(e.images, f) || due(e.camera_info, f) || due(e.disparity, f) || due(e.depth, f) ||
        due(e.points, f) || due(e.features, f) || (result.ground_plane && due(e.ground, f))) {
      delivery_.offer(result, stamp);
    }
  }
  void offer_health(const HealthReport& report) override { delivery_.offer_health(report); }
  DeliveryCounters counters() const override { return delivery_.counters(); }
  std::size_t working_set_bytes() const override {
    return delivery_.working_set_bytes() + disparity_.capacity() * 4 + depth_.capacity() * 2 +
           cloud_.capacity() * 4 + features_.capacity() * 4 + rig_.depth_mm.capacity() * 2;
  }

 private:
  // The participant and its writers (and the rig's transforms, latched).
  void join_graph() {
    participant_.emplace(domain_of(settings_), ros2::cyclonedds_config(settings_.network));
    if (participant_->configured_by_environment()) {
      journal(Priority::info, "output ros2: DDS configured by CYCLONEDDS_URI");
    }
    const int depth = settings_.depth;
    const auto writer = [&](const char* name, const dds_topic_descriptor_t* type) {
      return participant_->writer("rt" + settings_.names.topic(name), type, depth);
    };
    left_rect_ = writer("left/image_rect", &sensor_msgs_msg_dds__Image__desc);
    right_rect_ = writer("right/image_rect", &sensor_msgs_msg_dds__Image__desc);
    disparity_writer_ = writer("disparity", &stereo_msgs_msg_dds__DisparityImage__desc);
    diagnostics_ = writer("/diagnostics", &diagnostic_msgs_msg_dds__DiagnosticArray__desc);
    if (!calibration_) return;
    left_info_ = writer("left/camera_info", &sensor_msgs_msg_dds__CameraInfo__desc);
    right_info_ = writer("right/camera_info", &sensor_msgs_msg_dds__CameraInfo__desc);
    depth_writer_ = writer("depth", &sensor_msgs_msg_dds__Image__desc);
    points_ = writer("points", &sensor_msgs_msg_dds__PointCloud2__desc);
    features_writer_ = writer("features", &sensor_msgs_msg_dds__PointCloud2__desc);
    tf_ = writer("/tf", &tf2_msgs_msg_dds__TFMessage__desc);
    tf_static_ = participant_->writer("rt" + settings_.names.topic("/tf_static"),
                                      &tf2_msgs_msg_dds__TFMessage__desc, 1,
                                      ros2::Durability::transient_local);
    publish_rig_transforms();
  }

  void write(dds_entity_t writer, const void* sample) {
    if (const dds_return_t rc = dds_write(writer, sample); rc < 0) {
      throw Error(cat("ros2: write: ", dds_strretcode(rc)));
    }
  }

  void publish_rig_transforms() {
    const ros::Time t = ros::time_of(detail::system_now_ns());
    std::array<geometry_msgs_msg_dds__TransformStamped_, 2> transforms{};
    set_header(transforms[0].header, t, rig_.left_body);
    transforms[0].child_frame_id = text(rig_.left_optical);
    const auto& q = ros::kBodyToOptical;
    transforms[0].transform.rotation = {q[0], q[1], q[2], q[3]};
    set_header(transforms[1].header, t, rig_.left_optical);
    transforms[1].child_frame_id = text(rig_.right_optical);
    transforms[1].transform.translation.x = rig_.baseline_m;
    transforms[1].transform.rotation.w = 1.0;
    tf2_msgs_msg_dds__TFMessage_ m{};
    borrow(m.transforms, transforms.data(), transforms.size());
    write(tf_static_, &m);
  }

  // The ground's frame under the left optical frame, on /tf (tf2 looks it up at the pair's stamp).
  void publish_ground(ros::Time t, const GroundPlane& ground) {
    const ros::GroundTransform g = ros::ground_transform(ground.plane);
    geometry_msgs_msg_dds__TransformStamped_ transform{};
    set_header(transform.header, t, rig_.left_optical);
    transform.child_frame_id = text(rig_.ground);
    transform.transform.translation = {g.translation[0], g.translation[1], g.translation[2]};
    transform.transform.rotation = {g.rotation[0], g.rotation[1], g.rotation[2], g.rotation[3]};
    tf2_msgs_msg_dds__TFMessage_ m{};
    borrow(m.transforms, &transform, 1);
    write(tf_, &m);
  }

  void publish_camera_info(dds_entity_t writer, ros::Time t, const std::string& frame,
                           const ros::RectifiedCamera& camera) {
    static double no_distortion[5] = {0, 0, 0, 0, 0};
    sensor_msgs_msg_dds__CameraInfo_ m{};
    set_header(m.header, t, frame);
    m.height = static_cast<std::uint32_t>(camera.height);
    m.width = static_cast<std::uint32_t>(camera.width);
    m.distortion_model = text("plumb_bob");
    borrow(m.d, no_distortion, 5);
    const std::array<double, 9> k = ros::camera_k(camera);
    std::memcpy(m.k, k.data(), sizeof m.k);
    const double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::memcpy(m.r, r, sizeof r);
    std::memcpy(m.p, camera.p.data(), sizeof m.p);
    write(writer, &m);
  }

  void publish_cloud(dds_entity_t writer, ros::Time t, std::size_t width, std::size_t height,
                     const float* data, bool dense) {
    sensor_msgs_msg_dds__PointCloud2_ m{};
    set_header(m.header, t, rig_.left_optical);
    m.height = static_cast<std::uint32_t>(height);
    m.width = static_cast<std::uint32_t>(width);
    borrow(m.fields, fields_.data(), fields_.size());
    m.is_bigendian = false;
    m.point_step = 16;
    m.row_step = static_cast<std::uint32_t>(16 * width);
    borrow(m.data, reinterpret_cast<std::uint8_t*>(const_cast<float*>(data)), 16 * width * height);
    m.is_dense = dense;
    write(writer, &m);
  }

  void publish(const PairCopy& pair) {
    const ros::Time t = ros::time_of(pair.stamp.system_ns);
    const Rates& e = settings_.every;
    const int w = board_.width(), h = board_.height();
    if (pair.has_rectified && due(e.images, pair.frame)) {
      sensor_msgs_msg_dds__Image_ m{};
      set_image(m, t, rig_.left_optical, "mono8", w, h,
                static_cast<std::size_t>(pair.left.stride()), pair.left.view().row(0));
      write(left_rect_, &m);
      set_image(m, t, rig_.right_optical, "mono8", w, h,
                static_cast<std::size_t>(pair.right.stride()), pair.right.view().row(0));
      write(right_rect_, &m);
    }
    if (calibration_ && due(e.camera_info, pair.frame)) {
      publish_camera_info(left_info_, t, rig_.left_optical, rig_.left);
      publish_camera_info(right_info_, t, rig_.right_optical, rig_.right);
    }
    if (pair.has_disparity && due(e.disparity, pair.frame)) {
      ros::disparity_pixels(pair.disparity.view(), disparity_.data());
      stereo_msgs_msg_dds__DisparityImage_ m{};
      set_header(m.header, t, rig_.left_optical);
      set_image(m.image, t, rig_.left_optical, "32FC1", w, h, static_cast<std::size_t>(w) * 4,
                disparity_.data());
      m.f = rig_.focal_px();
      m.t = static_cast<float>(rig_.baseline_m);
      m.valid_window = {0, 0, static_cast<std::uint32_t>(h), static_cast<std::uint32_t>(w), false};
      m.min_disparity = 0.0f;
      m.max_disparity = static_cast<float>(board_.stereo.max_disparity);
      m.delta_d = 1.0f / 16;
      write(disparity_writer_, &m);
    }
    if (!calibration_) return;
    if (pair.has_disparity && due(e.depth, pair.frame)) {
      ros::depth_pixels(pair.disparity.view(), rig_.depth_mm, depth_.data());
      sensor_msgs_msg_dds__Image_ m{};
      set_image(m, t, rig_.left_optical, "16UC1", w, h, static_cast<std::size_t>(w) * 2,
                depth_.data());
      write(depth_writer_, &m);
    }
    if (pair.has_disparity && due(e.points, pair.frame)) {
      const int step = settings_.points_step;
      const bool above = settings_.points_above_ground && pair.ground_plane;
      ros::organised_points(pair.disparity.view(),
                            pair.has_rectified ? pair.left.view() : GrayView(), *triangulator_,
                            step, cloud_.data(), above ? &pair.ground_plane->clear : nullptr);
      publish_cloud(points_, t, static_cast<std::size_t>(w / step),
                    static_cast<std::size_t>(h / step), cloud_.data(), false);
    }
    if (pair.ground_plane && due(e.ground, pair.frame)) publish_ground(t, *pair.ground_plane);
    if (due(e.features, pair.frame)) {
      const std::size_t n = std::min(pair.points.size(), features_.size() / 4);
      ros::feature_points(std::span(pair.points).first(n),
                          pair.has_rectified ? pair.left.view() : GrayView(), features_.data());
      publish_cloud(features_writer_, t, n, 1, features_.data(), true);
    }
  }

  void publish_health(const HealthReport& report) {
    const std::size_t n = ros::diagnostic_statuses(report, dropped_before_, statuses_);
    dropped_before_ = report.health.dropped;
    std::array<diagnostic_msgs_msg_dds__DiagnosticStatus_, 2> statuses{};
    for (std::size_t s = 0; s < n; ++s) {
      const ros::DiagnosticStatus& from = statuses_[s];
      auto& values = key_values_[s];
      for (std::size_t i = 0; i < from.field_count; ++i) {
        values[i].key = text(from.fields[i].key);
        values[i].value = const_cast<char*>(from.fields[i].value.data());
      }
      statuses[s].level = from.level;
      statuses[s].name = text(from.name);
      statuses[s].message = const_cast<char*>(from.message.data());
      statuses[s].hardware_id = text(board_.name);
      borrow(statuses[s].values, values.data(), from.field_count);
    }
    diagnostic_msgs_msg_dds__DiagnosticArray_ m{};
    const ros::Time t = ros::time_of(detail::system_now_ns());
    m.header.stamp.sec = t.sec;
    m.header.stamp.nanosec = t.nanosec;
    m.header.frame_id = text("");
    borrow(m.status, statuses.data(), n);
    write(diagnostics_, &m);
  }

  const Ros2Settings& settings_;
  const BoardConfig& board_;
  const std::optional<calib::StereoCalibration>& calibration_;
  std::optional<ros2::DdsParticipant> participant_;  // none when made offline (--check)
  ros::RigModel rig_;
  std::array<sensor_msgs_msg_dds__PointField_, 4> fields_;
  std::optional<calib::Triangulator> triangulator_;
  std::vector<float> disparity_;
  std::vector<std::uint16_t> depth_;
  std::vector<float> cloud_, features_;
  std::array<ros::DiagnosticStatus, 2> statuses_;  // health's, the calibration's
  std::array<std::array<diagnostic_msgs_msg_dds__KeyValue_, ros::kMaxDiagnosticFields>, 2>
      key_values_{};
  dds_entity_t left_rect_ = 0, right_rect_ = 0, left_info_ = 0, right_info_ = 0;
  dds_entity_t disparity_writer_ = 0, depth_writer_ = 0, points_ = 0, features_writer_ = 0;
  dds_entity_t tf_ = 0, tf_static_ = 0, diagnostics_ = 0;
  std::uint32_t dropped_before_ = 0;  // health's `dropped` in the message before
  PairDelivery delivery_;             // last: its thread stops before the rest goes
};

std::unique_ptr<Output> make(const OutputContext& context) {
  return std::make_unique<Ros2Output>(context);
}

}  // namespace

extern constinit const OutputDefinition ros2_output{read_settings, make};

}  // namespace epipole::firmware::outputs

// The live view: the pairs' results as ROS 2 messages over the Foxglove WebSocket protocol, for
// Foxglove and Lichtblick to connect to (docs/live-view.md). Off until the board file has
//
//   outputs:
//     view: {port: 8765, bind: 127.0.0.1, clients: 4, every: 1, points_step: 4,
//            picture_hz: 5, quality: 80, namespace: /epipole, frame_prefix: epipole_}
//
// It listens on the loopback interface unless `bind` says otherwise; the same port serves a page
// for any browser (view/view_pages.hpp). A message is made only for the channels a client is
// subscribed to, pictures only while a page asks for them; each client gets the freshest of each
// message (a slow one gets messages dropped and counted), never making the frame loop wait.

#include <arpa/inet.h>
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/resident.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "epipole/firmware/journal.hpp"
#include "output_files.hpp"
#include "ros/diagnostics.hpp"
#include "ros/image_annotations.hpp"
#include "ros/rig_model.hpp"
#include "ros/ros_messages.hpp"
#include "steady_time.hpp"
#include "system_time.hpp"
#include "view/foxglove_server.hpp"
#include "view/view_pages.hpp"

namespace epipole::firmware::outputs {

namespace {

struct ViewSettings final : OutputSettings {
  std::string bind = "127.0.0.1";
  int port = 8765;
  int clients = 4;
  int every = 1;  // every Nth pair is served
  int points_step = 4;
  view::PageSettings page;
  ros::RosNames names;
  std::unique_ptr<OutputSettings> clone() const override {
    return std::make_unique<ViewSettings>(*this);
  }
};

std::unique_ptr<OutputSettings> read_settings(const YAML::Node& n, const yaml::Fields& f) {
  auto s = std::make_unique<ViewSettings>();
  if (!n.IsDefined() || n.IsNull()) return s;
  const std::string path = "outputs.view";
  f.only_keys(n, path,
              {"bind", "port", "clients", "every", "points_step", "picture_hz", "quality",
               "namespace", "frame_prefix"});
  f.if_present(n, path, "bind", [&](const YAML::Node& v, const std::string& k) {
    s->bind = f.text(v, k);
    in_addr address{};
    if (::inet_pton(AF_INET, s->bind.c_str(), &address) != 1) {
      f.fail(k, cat("'", s->bind,
                    "' is not an IPv4 address (127.0.0.1: this board only; 0.0.0.0: every "
                    "interface; or one interface's own address)"));
    }
  });
  f.if_present(n, path, "port", [&](const YAML::Node& v, const std::string& k) {
    s->port = f.integer_in(v, k, 0, 65535);
  });
  f.if_present(n, path, "clients", [&](const YAML::Node& v, const std::string& k) {
    s->clients = f.integer_in(v, k, 1, 16);
  });
  f.if_present(n, path, "every", [&](const YAML::Node& v, const std::string& k) {
    s->every = f.integer_in(v, k, 1, 1000);
  });
  f.if_present(n, path, "points_step", [&](const YAML::Node& v, const std::string& k) {
    s->points_step = f.integer_in(v, k, 1, 64);
  });
  f.if_present(n, path, "picture_hz", [&](const YAML::Node& v, const std::string& k) {
    s->page.picture_hz = f.number_in(v, k, 0.1, 60);
  });
  f.if_present(n, path, "quality", [&](const YAML::Node& v, const std::string& k) {
    s->page.quality = f.integer_in(v, k, 1, 100);
  });
  ros::read_ros_names(n, f, path, s->names);
  return s;
}

// The channels, in the order of their ids.
enum Topic : std::uint16_t {
  kLeftRect,
  kRightRect,
  kLeftInfo,
  kRightInfo,
  kDisparity,
  kDepth,
  kPoints,
  kFeatures,
  kBoxes,  // the detections, with their distance
  kDiagnostics,
  kTfStatic,
  kTopicCount
};

struct TopicRow {
  const char* name;  // under the namespace; absolute when it starts with /
  ros::MessageType (*type)();
  bool latched;
};
constexpr TopicRow kTopics[kTopicCount] = {
    {"left/image_rect", ros::image_type, false},
    {"right/image_rect", ros::image_type, false},
    {"left/camera_info", ros::camera_info_type, false},
    {"right/camera_info", ros::camera_info_type, false},
    {"disparity", ros::disparity_image_type, false},
    {"depth", ros::image_type, false},
    {"points", ros::point_cloud_type, false},
    {"features", ros::point_cloud_type, false},
    {"detections", ros::image_annotations_type, false},
    {"/diagnostics", ros::diagnostic_array_type, false},
    {"/tf_static", ros::tf_message_type, true},
};

std::vector<view::Channel> channels(const BoardConfig& board, const ViewSettings& s) {
  const std::size_t pixels = static_cast<std::size_t>(board.width()) * board.height();
  const std::size_t step = static_cast<std::size_t>(s.points_step);
  const std::size_t largest[kTopicCount] = {
      pixels + 512,
      pixels + 512,
      1024,
      1024,
      pixels * 4 + 1024,
      pixels * 2 + 512,
      (pixels / (step * step)) * 16 + 1024,
      static_cast<std::size_t>(board.sparse.max_matches) * 16 + 1024,
      protocol::kMaxDetections * 512 + 64,
      8 * 1024,
      1024};
  std::vector<view::Channel> out;
  for (std::size_t i = 0; i < kTopicCount; ++i) {
    const ros::MessageType type = kTopics[i].type();
    out.push_back({s.names.topic(kTopics[i].name), std::string(type.name), std::string(type.schema),
                   largest[i], kTopics[i].latched});
  }
  return out;
}

class ViewOutput final : public Output {
 public:
  explicit ViewOutput(const OutputContext& context)
      : settings_(settings_of<ViewSettings>(context, "view")),
        board_(context.board),
        calibration_(context.calibration),
        offline_(context.offline),
        rig_(settings_.names, context.calibration, context.board.stereo.max_disparity),
        pages_(context.board, settings_.page),
        server_({settings_.bind, settings_.port, settings_.clients, "epipole " + board_.name},
                channels(context.board, settings_)),
        delivery_(
            "view", context.board,
            PairPart::kRectified | PairPart::kDisparity | PairPart::kPoints | PairPart::kCorners |
                PairPart::kDetections,
            [this](const PairCopy& pair) { serve(pair); },
            [this](const HealthReport& report) { serve_health(report); }) {
    std::size_t largest = 0;
    for (const view::Channel& c : channels(context.board, settings_)) {
      largest = std::max(largest, c.largest);
    }
    reserve_resident(message_, largest);
    server_.serve_http([this](mg_connection* conn) { return pages_.serve(conn); });
    if (calibration_) {
      triangulator_.emplace(*calibration_);
      const int step = settings_.points_step;
      cloud_.resize(static_cast<std::size_t>(board_.width() / step) * (board_.height() / step) * 4);
    }
  }

  void start() override {
    if (offline_) return;  // checking the board file: no socket
    server_.start();
    journal(Priority::info, "output view: Foxglove WebSocket on ws://%s:%d/",
            settings_.bind.c_str(), server_.port());
    if (calibration_) {
      const std::int64_t ns = detail::system_now_ns();
      ros::write_rig_transforms(begin(), ros::time_of(ns), rig_.frames(), rig_.baseline_m);
      server_.publish(kTfStatic, static_cast<std::uint64_t>(ns), message_);
    }
    delivery_.start();
  }
  void stop() override {
    delivery_.stop();
    server_.stop();
  }
  void offer(const FrameResult& result, const PairStamp& stamp) override {
    if (pairs_++ % static_cast<std::uint64_t>(settings_.every) != 0) return;
    // Nothing copied for no one.
    if (!any_subscribed() && !pages_.due(detail::steady_now())) return;
    delivery_.offer(result, stamp);
  }
  void offer_health(const HealthReport& report) override { delivery_.offer_health(report); }
  DeliveryCounters counters() const override {
    DeliveryCounters c = delivery_.counters();
    c.dropped += server_.counters().dropped;  // and what clients did not take in time
    return c;
  }
  std::size_t working_set_bytes() const override {
    return delivery_.working_set_bytes() + server_.working_set_bytes() +
           pages_.working_set_bytes() + message_.capacity() + cloud_.capacity() * 4 +
           rig_.depth_mm.capacity() * 2;
  }
  // The port it listens on (0 until it started): tests ask for any free port.
  int port() const { return server_.port(); }

 private:
  bool any_subscribed() const {
    for (std::uint16_t c = 0; c < kDiagnostics; ++c) {  // the pairs' channels
      if (server_.subscribed(c)) return true;
    }
    return false;
  }
  std::vector<std::uint8_t>& begin() {
    message_.clear();
    return message_;
  }
  void send(Topic topic, std::uint64_t time) { server_.publish(topic, time, message_); }

  void serve(const PairCopy& pair) {
    if (const std::int64_t now = detail::steady_now(); pages_.due(now)) pages_.picture(pair, now);
    const std::int64_t ns = pair.stamp.system_ns;
    const auto time = static_cast<std::uint64_t>(ns);
    const ros::Time stamp = ros::time_of(ns);
    const auto wanted = [&](Topic t) { return server_.subscribed(t); };
    if (pair.has_rectified && wanted(kLeftRect)) {
      ros::write_image(begin(), stamp, rig_.left_optical, pair.left.view());
      send(kLeftRect, time);
    }
    if (pair.has_rectified && wanted(kRightRect)) {
      ros::write_image(begin(), stamp, rig_.right_optical, pair.right.view());
      send(kRightRect, time);
    }
    if (pair.has_disparity && wanted(kDisparity)) {
      ros::write_disparity_image(begin(), stamp, rig_.left_optical, pair.disparity.view(),
                                 rig_.focal_px(), static_cast<float>(rig_.baseline_m),
                                 board_.stereo.max_disparity);
      send(kDisparity, time);
    }
    if (!calibration_) return;
    if (wanted(kLeftInfo)) {
      ros::write_camera_info(begin(), stamp, rig_.left_optical, rig_.left);
      send(kLeftInfo, time);
    }
    if (wanted(kRightInfo)) {
      ros::write_camera_info(begin(), stamp, rig_.right_optical, rig_.right);
      send(kRightInfo, time);
    }
    if (pair.has_disparity && wanted(kDepth)) {
      ros::write_depth_image(begin(), stamp, rig_.left_optical, pair.disparity.view(),
                             rig_.depth_mm);
      send(kDepth, time);
    }
    const GrayView left = pair.has_rectified ? pair.left.view() : GrayView();
    if (pair.has_disparity && wanted(kPoints)) {
      const int step = settings_.points_step;
      ros::organised_points(pair.disparity.view(), left, *triangulator_, step, cloud_.data());
      ros::write_point_cloud(begin(), stamp, rig_.left_optical,
                             static_cast<std::size_t>(board_.width() / step),
                             static_cast<std::size_t>(board_.height() / step), cloud_.data());
      send(kPoints, time);
    }
    if (wanted(kFeatures)) {
      ros::write_feature_cloud(begin(), stamp, rig_.left_optical, pair.points, left);
      send(kFeatures, time);
    }
    if (wanted(kBoxes) && protocol::has_stage(pair.stages, protocol::Stage::detect)) {
      ros::write_detection_annotations(begin(), stamp, pair.detections, pair.detection_depths);
      send(kBoxes, time);
    }
  }

  void serve_health(const HealthReport& report) {
    pages_.health(report.health);
    if (!server_.subscribed(kDiagnostics)) return;
    const std::int64_t ns = detail::system_now_ns();
    ros::write_diagnostics(begin(), ros::time_of(ns), board_.name, report, dropped_before_,
                           statuses_);
    dropped_before_ = report.health.dropped;
    send(kDiagnostics, static_cast<std::uint64_t>(ns));
  }

  const ViewSettings& settings_;
  const BoardConfig& board_;
  const std::optional<calib::StereoCalibration>& calibration_;
  bool offline_;
  ros::RigModel rig_;
  view::ViewPages pages_;  // before the server, whose threads call it
  view::FoxgloveServer server_;
  std::optional<calib::Triangulator> triangulator_;
  std::vector<float> cloud_;
  std::vector<std::uint8_t> message_;
  std::uint64_t pairs_ = 0;           // offered, on the frame loop's side
  std::uint32_t dropped_before_ = 0;  // health's `dropped` in the message before
  std::array<ros::DiagnosticStatus, 2> statuses_;
  PairDelivery delivery_;  // last: its thread stops before the rest goes
};

std::unique_ptr<Output> make(const OutputContext& context) {
  return std::make_unique<ViewOutput>(context);
}

}  // namespace

extern constinit const OutputDefinition view_output{read_settings, make};

}  // namespace epipole::firmware::outputs

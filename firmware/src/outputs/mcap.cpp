// The recording output: the pairs' results as ROS 2 messages in MCAP files (docs/outputs.md),
// into a ring of files bounded by size and free space.
//
//   outputs:
//     mcap: {directory: /var/lib/epipole/recordings, continuous: false, every: 10, file_mb: 256,
//            total_mb: 2048, min_free_mb: 512, namespace: /epipole, frame_prefix: epipole_}
//
// Continuous, it records from start-up; else between the robot's `record` start and stop.

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <atomic>
#include <string>
#include <vector>

#include "epipole/calib/triangulation.hpp"
#include "epipole/core/mcap_writer.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "epipole/firmware/build_info.hpp"
#include "epipole/firmware/journal.hpp"
#include "output_files.hpp"
#include "record/recorded_calibration.hpp"
#include "record/recording_ring.hpp"
#include "ros/diagnostics.hpp"
#include "ros/rig_model.hpp"
#include "ros/ros_messages.hpp"
#include "system_time.hpp"

namespace epipole::firmware::outputs {

namespace {

struct McapSettings final : OutputSettings {
  std::filesystem::path directory;
  bool continuous = false;  // from start-up; else between the robot's record start and stop
  int every = 10;           // every Nth pair is recorded (health, once a second, always)
  double file_mb = 256;
  double total_mb = 2048;
  double min_free_mb = 512;
  ros::RosNames names;
  std::unique_ptr<OutputSettings> clone() const override {
    return std::make_unique<McapSettings>(*this);
  }
};

std::unique_ptr<OutputSettings> read_settings(const YAML::Node& n, const yaml::Fields& f) {
  auto s = std::make_unique<McapSettings>();
  const std::string path = "outputs.mcap";
  if (!n.IsDefined() || n.IsNull()) f.fail(path + ".directory", "is missing (where to record)");
  f.only_keys(n, path,
              {"directory", "continuous", "every", "file_mb", "total_mb", "min_free_mb",
               "namespace", "frame_prefix"});
  s->directory = f.path(f.child(n, path, "directory"), path + ".directory");
  f.if_present(n, path, "continuous",
               [&](const YAML::Node& v, const std::string& k) { s->continuous = f.boolean(v, k); });
  f.if_present(n, path, "every", [&](const YAML::Node& v, const std::string& k) {
    s->every = f.integer_in(v, k, 1, 1000);
  });
  f.if_present(n, path, "file_mb", [&](const YAML::Node& v, const std::string& k) {
    s->file_mb = f.number_in(v, k, 1, 65536);
  });
  f.if_present(n, path, "total_mb", [&](const YAML::Node& v, const std::string& k) {
    s->total_mb = f.number_in(v, k, 1, 1 << 24);
  });
  f.if_present(n, path, "min_free_mb", [&](const YAML::Node& v, const std::string& k) {
    s->min_free_mb = f.number_in(v, k, 0, 1 << 24);
  });
  if (s->total_mb < s->file_mb) f.fail(path + ".total_mb", "is less than file_mb");
  ros::read_ros_names(n, f, path, s->names);
  return s;
}

// The recorded topics, in the order of the writer's channels.
enum Topic : std::uint16_t {
  kLeftRect,
  kRightRect,
  kLeftRaw,
  kRightRaw,
  kLeftInfo,
  kRightInfo,
  kDisparity,
  kDepth,
  kFeatures,
  kDiagnostics,
  kTfStatic,
  kTopicCount
};

struct TopicRow {
  Topic topic;
  const char* name;  // under the namespace; absolute when it starts with /
  ros::MessageType (*type)();
};
constexpr TopicRow kTopics[] = {
    {kLeftRect, "left/image_rect", ros::image_type},
    {kRightRect, "right/image_rect", ros::image_type},
    {kLeftRaw, "left/image_raw", ros::image_type},
    {kRightRaw, "right/image_raw", ros::image_type},
    {kLeftInfo, "left/camera_info", ros::camera_info_type},
    {kRightInfo, "right/camera_info", ros::camera_info_type},
    {kDisparity, "disparity", ros::disparity_image_type},
    {kDepth, "depth", ros::image_type},
    {kFeatures, "features", ros::point_cloud_type},
    {kDiagnostics, "/diagnostics", ros::diagnostic_array_type},
    {kTfStatic, "/tf_static", ros::tf_message_type},
};

// The writer's schemas (one per message type) and channels (one per topic).
mcap::Writer make_writer(const BoardConfig& board, const McapSettings& s) {
  std::vector<mcap::Schema> schemas;
  std::vector<mcap::Channel> channels;
  for (const TopicRow& row : kTopics) {
    const ros::MessageType type = row.type();
    std::uint16_t id = 0;
    for (std::size_t i = 0; i < schemas.size(); ++i) {
      if (schemas[i].name == type.name) id = static_cast<std::uint16_t>(i + 1);
    }
    if (id == 0) {
      schemas.push_back({std::string(type.name), "ros2msg", std::string(type.schema)});
      id = static_cast<std::uint16_t>(schemas.size());
    }
    channels.push_back({id, s.names.topic(row.name), "cdr", {}});
  }
  const std::size_t pixels = static_cast<std::size_t>(board.width()) * board.height();
  const std::size_t largest =
      std::max(pixels * 4, static_cast<std::size_t>(board.sparse.max_matches) * 16) + 4096;
  return mcap::Writer(std::move(schemas), std::move(channels), 4u << 20, largest);
}

// A folder the recording can write in, or make (its nearest existing parent writable): else the
// firmware does not start, rather than find out at the first pair.
void check_folder(const std::filesystem::path& directory) {
  std::filesystem::path p = directory;
  std::error_code ec;
  while (!std::filesystem::exists(p, ec) && p.has_parent_path() && p != p.parent_path()) {
    p = p.parent_path();
  }
  require(std::filesystem::is_directory(p, ec) && ::access(p.c_str(), W_OK | X_OK) == 0,
          "outputs.mcap.directory: ", directory.string(), ": ",
          p == directory ? "not a folder this firmware may write in"
                         : cat("cannot be made in ", p.string()));
}

class McapOutput final : public Output {
 public:
  explicit McapOutput(const OutputContext& context)
      : settings_(settings_of<McapSettings>(context, "mcap")),
        board_(context.board),
        calibration_(context.calibration),
        ring_(settings_.directory, {static_cast<std::uint64_t>(settings_.file_mb * (1 << 20)),
                                    static_cast<std::uint64_t>(settings_.total_mb * (1 << 20)),
                                    static_cast<std::uint64_t>(settings_.min_free_mb * (1 << 20))}),
        writer_(make_writer(context.board, settings_)),
        rig_(settings_.names, context.calibration, context.board.stereo.max_disparity),
        delivery_(
            "mcap", context.board,
            PairPart::kRectified | PairPart::kRaw | PairPart::kDisparity | PairPart::kPoints,
            [this](const PairCopy& pair) { record(pair); },
            [this](const HealthReport& report) { record_health(report); }) {
    check_folder(settings_.directory);
  }

  void start() override { delivery_.start(); }
  void stop() override {
    delivery_.stop();
    try {
      writer_.close();
    } catch (const Error& e) {
      journal(Priority::warning, "output mcap: %s", e.what());
    }
  }
  void offer(const FrameResult& result, const PairStamp& stamp) override {
    if (recording_ && stop_at_ != 0 && result.trigger_ns >= stop_at_) stop_recording();
    if (!recording_) return;
    if (pairs_++ % static_cast<std::uint64_t>(settings_.every) != 0) return;
    if (new_session_) {  // a start: its file begins with this pair
      new_session_ = false;
      session_first_frame_.store(result.frame);
      session_.fetch_add(1);
    }
    last_offered_frame_ = result.frame;
    delivery_.offer(result, stamp);
  }
  std::optional<CommandVerdict> command(const protocol::Message& message,
                                        hal::Nanoseconds now) override {
    const auto* record = std::get_if<protocol::Record>(&message);
    if (record == nullptr) return std::nullopt;
    if (record->action == protocol::RecordAction::stop) {
      stop_recording();
    } else {
      // A new file from the next pair on, stopped after the duration if one is given.
      recording_ = true;
      shared_recording_ = true;
      new_session_ = true;
      pairs_ = 0;
      stop_at_ =
          record->duration_s > 0 ? now + hal::Nanoseconds{record->duration_s} * 1'000'000'000 : 0;
    }
    return CommandVerdict{};
  }
  void offer_health(const HealthReport& report) override { delivery_.offer_health(report); }
  DeliveryCounters counters() const override { return delivery_.counters(); }
  std::size_t working_set_bytes() const override {
    return delivery_.working_set_bytes() + writer_.working_set_bytes() +
           rig_.depth_mm.capacity() * 2;
  }

 private:
  std::vector<std::uint8_t>& begin(Topic topic, std::uint64_t time) {
    return writer_.begin_message(topic, sequences_[topic]++, time, time);
  }

  // Frame loop side: no pair is offered until the next start; the file is closed on the output's
  // thread (at its next turn: health comes once a second).
  void stop_recording() {
    recording_ = false;
    stop_after_frame_.store(last_offered_frame_);
    shared_recording_ = false;
    stop_at_ = 0;
  }

  // Whether `pair` goes into a file: a new one when a start began with it (the file open is
  // closed), the one open otherwise; a pair of before a stop whose file is already closed
  // goes nowhere.
  bool file_for(const PairCopy& pair) {
    const std::uint32_t session = session_.load();
    if (session != session_seen_ && pair.frame >= session_first_frame_.load()) {
      session_seen_ = session;
      writer_.close();
      return true;
    }
    return session == session_seen_ || writer_.is_open();
  }

  // A new file when there is none or the one open is full.
  // A new file also when the open one's chunk index is nearly full (its 1024 chunks are 4 GiB
  // of messages before compression, which a file of highly compressible pairs can reach before
  // its file_mb): the index never grows, nothing is allocated.
  void open_if_needed(std::int64_t system_ns) {
    constexpr std::size_t kChunksAPairMayTake = 8;
    if (writer_.is_open() && writer_.bytes() < ring_.limits().file_bytes &&
        writer_.chunks_left() > kChunksAPairMayTake) {
      return;
    }
    writer_.close();
    writer_.open(ring_.next_file(system_ns), build_info());
    journal(Priority::info, "output mcap: recording into %s", writer_.file().c_str());
    const auto time = static_cast<std::uint64_t>(system_ns);
    if (calibration_) {
      const std::string yaml = calib::format_calibration(*calibration_);
      writer_.attach(firmware::record::kCalibrationAttachment, "application/yaml",
                     {reinterpret_cast<const std::uint8_t*>(yaml.data()), yaml.size()}, time);
      ros::write_rig_transforms(begin(kTfStatic, time), ros::time_of(system_ns), rig_.frames(),
                                rig_.baseline_m);
      writer_.end_message();
    }
  }

  void record(const PairCopy& pair) {
    const std::int64_t ns = pair.stamp.system_ns;
    if (!file_for(pair)) return;
    open_if_needed(ns);
    last_recorded_frame_ = pair.frame;
    const auto time = static_cast<std::uint64_t>(ns);
    const ros::Time stamp = ros::time_of(ns);
    const auto image = [&](Topic topic, const std::string& frame, GrayView view) {
      ros::write_image(begin(topic, time), stamp, frame, view);
      writer_.end_message();
    };
    if (pair.has_rectified) {
      image(kLeftRect, rig_.left_optical, pair.left.view());
      image(kRightRect, rig_.right_optical, pair.right.view());
    }
    if (pair.has_raw) {
      image(kLeftRaw, rig_.left_optical, pair.left_raw.view());
      image(kRightRaw, rig_.right_optical, pair.right_raw.view());
    }
    if (calibration_) {
      ros::write_camera_info(begin(kLeftInfo, time), stamp, rig_.left_optical, rig_.left);
      writer_.end_message();
      ros::write_camera_info(begin(kRightInfo, time), stamp, rig_.right_optical, rig_.right);
      writer_.end_message();
    }
    if (pair.has_disparity) {
      ros::write_disparity_image(begin(kDisparity, time), stamp, rig_.left_optical,
                                 pair.disparity.view(), rig_.focal_px(),
                                 static_cast<float>(rig_.baseline_m), board_.stereo.max_disparity);
      writer_.end_message();
      if (calibration_) {
        ros::write_depth_image(begin(kDepth, time), stamp, rig_.left_optical, pair.disparity.view(),
                               rig_.depth_mm);
        writer_.end_message();
      }
    }
    if (calibration_ && !pair.points.empty()) {
      ros::write_feature_cloud(begin(kFeatures, time), stamp, rig_.left_optical, pair.points,
                               pair.has_rectified ? pair.left.view() : GrayView());
      writer_.end_message();
    }
  }

  void record_health(const HealthReport& report) {
    // Stopped, and every pair offered before the stop done: the file is made whole.
    if (!shared_recording_ && last_recorded_frame_ >= stop_after_frame_.load()) writer_.close();
    if (!writer_.is_open()) return;  // recorded with the pairs: a file is opened by a pair
    const std::int64_t ns = detail::system_now_ns();
    ros::write_diagnostics(begin(kDiagnostics, static_cast<std::uint64_t>(ns)), ros::time_of(ns),
                           board_.name, report, dropped_before_, statuses_);
    dropped_before_ = report.health.dropped;
    writer_.end_message();
  }

  const McapSettings& settings_;
  const BoardConfig& board_;
  const std::optional<calib::StereoCalibration>& calibration_;
  firmware::record::RecordingRing ring_;
  mcap::Writer writer_;
  ros::RigModel rig_;
  std::array<std::uint32_t, kTopicCount> sequences_{};
  // The frame loop's side: whether pairs are recorded, until when (board clock; 0: until stopped),
  // and how many were offered since the start.
  bool recording_ = settings_.continuous;
  hal::Nanoseconds stop_at_ = 0;
  std::uint64_t pairs_ = 0;
  bool new_session_ = false;  // a start whose first pair is still to come
  std::uint32_t last_offered_frame_ = 0;
  // Told to the output's thread: whether it records, and in the pairs' terms each start's number
  // and the pair it began with, and the last pair offered before a stop.
  std::atomic<bool> shared_recording_{settings_.continuous};
  std::atomic<std::uint32_t> session_{0};
  std::atomic<std::uint32_t> session_first_frame_{0};
  std::atomic<std::uint32_t> stop_after_frame_{0};
  // The output's thread's own.
  std::uint32_t session_seen_ = 0;
  std::uint32_t last_recorded_frame_ = 0;
  std::uint32_t dropped_before_ = 0;  // health's `dropped` in the message before
  std::array<ros::DiagnosticStatus, 2> statuses_;
  PairDelivery delivery_;  // last: its thread stops before the rest goes
};

std::unique_ptr<Output> make(const OutputContext& context) {
  return std::make_unique<McapOutput>(context);
}

}  // namespace

extern constinit const OutputDefinition mcap_output{read_settings, make};

}  // namespace epipole::firmware::outputs

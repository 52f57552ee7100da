// epipole sim: the firmware on the simulated board, scene by scene, with what a person wants to
// look at: the rectified pair with epipolar lines, corners, colour disparity with a legend, the
// decoded serial stream (read from the simulated link's far end, as a robot would) and a
// summary.
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/hal/registry.hpp"
#include "epipole/hal/serial_port.hpp"
#include "epipole/tools/cascade_xml.hpp"
#include "epipole/tools/progress.hpp"
#include "message_json.hpp"
#include "pictures.hpp"
#include "sim/sim.hpp"
#include "sim/sim_settings.hpp"
#include "sim/world_scene.hpp"
#include "stereo_preview.hpp"
#include "trajectory_check.hpp"

namespace epipole::tools {

namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kDefaultFrames = 30;  // a replayed scene's pairs without --frames

struct SimOptions {
  std::string board = "board/sim";
  std::vector<std::string> scenes;  // empty: every scene of the board
  std::uint64_t frames = 0;         // 0 (not given): 30, and a rendered path's whole path
  int pictures = 1;
  std::string out = "out/sim";
  bool json = false;                // the summary on stdout instead of a line per scene
  std::vector<std::string> record;  // scenes recorded (every pair, MCAP) into <out>/<scene>/
  std::vector<std::string> replay;  // recordings replayed, each a scene named after its file
};

// A recording's scene: named after its file (letters, digits, - and _), the recording's raw pairs
// and calibration replayed (docs/outputs.md).
struct ReplayedScene {
  std::string name;
  std::string setting;  // the board file override that adds it
};
ReplayedScene replayed_scene(const fs::path& recording) {
  require(fs::is_regular_file(recording), "--replay ", recording.string(), ": no such file");
  std::string name = recording.stem().string();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  }
  // The path as a YAML string (JSON's quoting is YAML's).
  return {name, "sim.scenes." + name +
                    ".recording=" + nlohmann::json(fs::absolute(recording).string()).dump()};
}

// The board file's recording output turned on for a scene: every pair into `directory`.
std::vector<std::string> recording_overrides(const fs::path& directory) {
  return {"outputs.mcap.directory=" + fs::absolute(directory).string(), "outputs.mcap.every=1",
          "outputs.mcap.continuous=true"};
}

// Reads the simulated link's far end, as the robot would, keeping the raw bytes and decoding
// them, in the board's protocol, into JSON lines.
class LinkRecorder {
 public:
  LinkRecorder(const std::string& peer, JsonStreamDecoder::Protocol protocol,
               const fs::path& directory)
      : port_(hal::BackendRegistry::builtin().create_serial("termios", {peer, 115200})),
        raw_(directory / "serial.bin", std::ios::binary),
        lines_(directory / "serial.jsonl"),
        decoder_(protocol) {
    require(raw_.good() && lines_.good(), directory.string(), ": cannot write the serial stream");
    thread_ = std::thread([this] { run(); });
  }
  // Reads what is still in the link, then stops.
  void finish() {
    stopping_ = true;
    thread_.join();
    decoder_.finish([this](const nlohmann::json& json) { return record(json); });
    lines_ << decoder_.stats().dump() << "\n";
  }
  const std::map<std::string, int>& counts() const { return counts_; }
  nlohmann::json stats() const { return decoder_.stats(); }
  const nlohmann::json& last_health() const { return last_health_; }
  const nlohmann::json& last_ground() const { return last_ground_; }
  // The native odometry messages, in order (after finish()).
  const std::vector<nlohmann::json>& odometry() const { return odometry_; }

 private:
  void run() {
    std::array<std::byte, 4096> buffer{};
    for (;;) {
      const hal::IoResult r = port_->read(buffer, 50'000'000);
      if (r.status != hal::IoStatus::ok) {
        if (stopping_) return;
        continue;
      }
      raw_.write(reinterpret_cast<const char*>(buffer.data()),
                 static_cast<std::streamsize>(r.bytes));
      decoder_.feed(std::span(reinterpret_cast<const std::uint8_t*>(buffer.data()), r.bytes),
                    [this](const nlohmann::json& json) { return record(json); });
    }
  }
  // Every message is kept: true.
  bool record(const nlohmann::json& json) {
    lines_ << json.dump() << "\n";
    ++counts_[json["type"].get<std::string>()];
    if (json["type"] == "health") last_health_ = json;
    if (json["type"] == "ground") last_ground_ = json;
    // The native message (MAVLink's ODOMETRY is in the vehicle's frames).
    if (json["type"] == "odometry" && json.contains("status")) odometry_.push_back(json);
    return true;
  }

  std::unique_ptr<hal::SerialPort> port_;  // the robot's end: a terminal like any UART
  std::ofstream raw_;
  std::ofstream lines_;
  JsonStreamDecoder decoder_;
  std::map<std::string, int> counts_;
  nlohmann::json last_health_;
  nlohmann::json last_ground_;
  std::vector<nlohmann::json> odometry_;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

// The rectified left image with each detection's box and, when known, its distance.
RgbImage detections_picture(const firmware::FrameResult& r) {
  RgbImage picture = rgb_picture(r.left);
  cv::Mat drawing = mat_of(picture.view());
  const cv::Scalar green{0, 255, 0};
  for (std::size_t i = 0; i < r.detections.size(); ++i) {
    const vision::Detection& d = r.detections[i];
    cv::rectangle(drawing, cv::Rect(d.x, d.y, d.width, d.height), green, 2);
    const firmware::DetectionDepth& depth = r.detection_depths[i];
    char label[32];
    if (depth.valid) {
      std::snprintf(label, sizeof label, "%.2f m", depth.depth);
    } else {
      std::snprintf(label, sizeof label, "depth unknown");
    }
    // Above the box, or below it when the box touches the top.
    const int above = d.y - 2 - label_height();
    draw_label(drawing, {d.x, above >= 0 ? above : d.y + d.height + 2}, label, green);
  }
  return picture;
}

// Writes the pictures of the first frames that show distinct images of the scene.
class PictureWriter final : public firmware::FrameObserver {
 public:
  PictureWriter(fs::path directory, int images, int pictures, int max_disparity)
      : directory_(std::move(directory)),
        images_(images),
        pictures_(pictures),
        max_disparity_(max_disparity) {}

  void on_frame(const firmware::FrameResult& r) override {
    const int image = static_cast<int>(r.frame % static_cast<std::uint32_t>(images_));
    if (image >= pictures_ || std::find(done_.begin(), done_.end(), image) != done_.end()) return;
    done_.push_back(image);
    const std::string prefix = cat("frame", r.frame, "-");
    const auto file = [&](const char* what) {
      written_.push_back(prefix + what);
      return directory_ / (prefix + what);
    };
    save_image(file("rectified-pair.png"), side_by_side_preview(r.left, r.right).view());
    if (!r.corners_left.empty() || (r.stages & firmware::stage_bit(protocol::Stage::corners))) {
      RgbImage corners = rgb_picture(r.left);
      cv::Mat drawing = mat_of(corners.view());
      for (const vision::Corner& c : r.corners_left) {
        cv::circle(drawing, {c.x, c.y}, 3, {0, 255, 0}, 1, cv::LINE_AA);
      }
      // Matched corners, coloured by disparity as the disparity picture (red near).
      for (const vision::SparseMatch& m : r.matches) {
        const cv::Point at(static_cast<int>(m.xl), static_cast<int>(m.yl));
        cv::circle(drawing, at, 4, colour_of(static_cast<double>(m.disparity) / max_disparity_),
                   cv::FILLED, cv::LINE_AA);
      }
      save_image(file("corners.png"), corners.view());
    }
    if ((r.stages & firmware::stage_bit(protocol::Stage::detect)) != 0) {
      save_image(file("detections.png"), detections_picture(r).view());
    }
    if (!r.disparity.empty()) {
      save_image(file("disparity.png"), disparity_picture(r.disparity, max_disparity_).view());
      Image<std::uint16_t> png(r.disparity.width(), r.disparity.height());
      for (int y = 0; y < png.height(); ++y) {
        for (int x = 0; x < png.width(); ++x) {
          png.view()(x, y) = static_cast<std::uint16_t>(std::max<int>(r.disparity(x, y), 0));
        }
      }
      save_image(file("disparity16.png"), ImageView<const std::uint16_t>(png.view()));
    }
  }
  const std::vector<std::string>& written() const { return written_; }

 private:
  fs::path directory_;
  int images_;
  int pictures_;
  int max_disparity_;
  std::vector<int> done_;
  std::vector<std::string> written_;
};

// Counts a scene's pairs on the progress line, then hands each to the pictures.
class FrameProgress final : public firmware::FrameObserver {
 public:
  FrameProgress(firmware::FrameObserver& next, std::string scene, std::uint64_t frames)
      : next_(next), scene_(std::move(scene)), frames_(frames) {}
  void on_frame(const firmware::FrameResult& r) override {
    next_.on_frame(r);
    ++done_;
    progress_.show(cat("sim: ", scene_, ": pair ", done_, " of ", frames_), done_ == frames_);
    if (stop_ != nullptr && r.frame >= last_frame_) *stop_ = true;
  }
  void on_message(const protocol::Message& message) override { next_.on_message(message); }
  // A path ends at its last pose: the run stops once its pair is done (pairs skipped for the
  // loop's time would otherwise run on into the path's first poses again).
  void stop_after(std::uint32_t frame, std::atomic<bool>& stop) {
    last_frame_ = frame;
    stop_ = &stop;
  }

 private:
  std::atomic<bool>* stop_ = nullptr;
  std::uint32_t last_frame_ = 0;
  firmware::FrameObserver& next_;
  std::string scene_;
  std::uint64_t frames_;
  std::uint64_t done_ = 0;
  Progress progress_;
};

// A rendered world's exact truth beside its pictures (truth.yaml, true_disparity.png), and its
// ground for the summary; null for the other scenes.
nlohmann::json write_truth(const firmware::BoardConfig& config, const fs::path& directory) {
  const hal::SimScene& scene = hal::sim_settings(config.sections).chosen();
  const std::optional<calib::StereoCalibration> rig = firmware::load_board_calibration(config);
  if (!scene.world || !rig) return nullptr;
  hal::write_world_truth(*scene.world, *rig, directory);
  const hal::GroundTruth ground = hal::world_ground_truth(*scene.world, *rig);
  return {{"height_mm", ground.height_m * 1000},
          {"pitch_cdeg", ground.pitch_deg * 100},
          {"roll_cdeg", ground.roll_deg * 100}};
}

nlohmann::json run_scene(const std::string& scene, const SimOptions& options,
                         std::vector<std::string> overrides) {
  const std::vector<hal::BackendOption> chosen = {{"scene", scene}};
  const fs::path directory = fs::path(options.out) / scene;
  const bool record =
      std::find(options.record.begin(), options.record.end(), scene) != options.record.end();
  const fs::path recordings = directory / "recordings";
  if (record) fs::remove_all(recordings);  // this run's recording alone
  if (record) {
    for (std::string& setting : recording_overrides(recordings)) overrides.push_back(setting);
  }
  firmware::BoardConfig config = firmware::load_board_config(options.board, overrides, chosen);
  // A rendered path is walked to its end, one pair per pose; with --frames, its first poses.
  hal::SimSettings& sim = hal::sim_settings(config.sections);
  const hal::SimScene& chosen_scene = sim.chosen();
  const bool path = chosen_scene.world && chosen_scene.world->path;
  if (path && options.frames > 0) {
    for (hal::SimScene& s : sim.scenes) {
      if (s.name == chosen_scene.name) s.world->path->max_poses = options.frames;
    }
  }
  fs::create_directories(directory);
  // The pty's robot end: a link in the output folder, so the firmware's link is easy to find.
  if (hal::BackendRegistry::builtin().serial_traits(config.serial.backend).simulated &&
      config.serial.port.device.empty()) {
    config.serial.port.device = (directory / "link").string();
  }
  // The firmware reads compiled cascades: an XML cascade of the board is compiled here first.
  if (protocol::has_stage(config.stages, protocol::Stage::detect) &&
      config.detector.cascade.extension() == ".xml") {
    const std::vector<std::uint8_t> binary = load_cascade(config.detector.cascade).to_binary();
    const fs::path compiled = directory / "cascade.bin";
    std::ofstream(compiled, std::ios::binary)
        .write(reinterpret_cast<const char*>(binary.data()),
               static_cast<std::streamsize>(binary.size()));
    config.detector.cascade = compiled;
  }
  const nlohmann::json truth = write_truth(config, directory);
  firmware::Firmware fw(config);
  const int images = static_cast<int>(hal::simulated_board(fw.board().hardware())->scene_images());
  const std::uint64_t frames = options.frames > 0 ? options.frames
                               : path             ? static_cast<std::uint64_t>(images)
                                                  : kDefaultFrames;
  PictureWriter pictures(directory, images, options.pictures, config.stereo.max_disparity);
  FrameProgress progress(pictures, scene, frames);
  fw.frame_loop().set_observer(&progress);
  std::unique_ptr<LinkRecorder> recorder;
  if (!fw.board().serial_peer().empty()) {
    recorder =
        std::make_unique<LinkRecorder>(fw.board().serial_peer(), config.serial.protocol, directory);
  }
  std::atomic<bool> stop{false};
  if (path) progress.stop_after(static_cast<std::uint32_t>(frames - 1), stop);
  const firmware::RunSummary s = fw.run(frames, stop);
  if (recorder) recorder->finish();
  nlohmann::json odometry;
  if (path && recorder && fw.calibration()) {
    odometry = check_trajectory(recorder->odometry(),
                                hal::world_trajectory(*chosen_scene.world, *fw.calibration()),
                                chosen_scene.world->path->rate_hz, directory);
  }

  nlohmann::json out = {{"scene", scene},
                        {"images", images},
                        {"frames", s.frames},
                        {"stale_pairs", s.stale},
                        {"timeouts", s.timeouts},
                        {"pairs", s.pairing.pairs},
                        {"health_messages", s.health_messages},
                        {"messages_sent", s.link.messages_sent},
                        {"messages_dropped", s.link.messages_dropped},
                        {"calibration", fw.calibration() ? "yes" : "none"},
                        {"pictures", pictures.written()}};
  for (const firmware::OutputReport& o : s.outputs) {
    out["outputs"][o.name] = {
        {"delivered", o.delivered}, {"dropped", o.dropped}, {"failures", o.failures}};
  }
  if (record) {
    nlohmann::json files = nlohmann::json::array();
    for (const auto& e : fs::directory_iterator(recordings)) files.push_back(e.path().string());
    out["recordings"] = files;
  }
  if (!truth.is_null()) out["truth"] = truth;
  if (!odometry.is_null()) out["odometry"] = odometry;
  if (recorder) {
    out["last_ground"] = recorder->last_ground();
    out["received"] = recorder->counts();
    out["decoder"] = recorder->stats();
    out["last_health"] = recorder->last_health();
  }
  return out;
}

void print_scene(const nlohmann::json& s) {
  std::cout << "sim: scene " << s["scene"].get<std::string>() << ": " << s["frames"] << " pairs of "
            << s["images"] << " images, " << s["messages_sent"] << " messages sent ("
            << s["messages_dropped"] << " dropped)";
  if (s.contains("decoder")) {
    const nlohmann::json& d = s["decoder"];
    std::cout << ", " << d["frames"] << " decoded as " << d["protocol"].get<std::string>() << " ("
              << d["errors"] << " errors)";
  }
  if (s.contains("last_health") && !s["last_health"].is_null()) {
    const nlohmann::json& h = s["last_health"];
    std::cout << "; last health: " << h["fps_centi"].get<int>() / 100.0 << " fps, latency p50 "
              << h["latency_p50_us"].get<int>() / 1000.0 << " ms, p99 "
              << h["latency_p99_us"].get<int>() / 1000.0 << " ms, rectify "
              << h["rectify_us"].get<int>() / 1000.0 << " ms, corners "
              << h["corners_us"].get<int>() / 1000.0 << " ms, disparity "
              << h["disparity_us"].get<int>() / 1000.0 << " ms, busy "
              << h["busy_permille"].get<int>() / 10.0 << " %";
  }
  if (s.contains("odometry") && !s["odometry"].is_null()) {
    const nlohmann::json& o = s["odometry"];
    std::cout << "; odometry at the last pair " << o["end_error_m"].get<double>() << " m ("
              << o["end_error_percent"].get<double>() << " % of " << o["path_m"].get<double>()
              << " m) and " << o["end_heading_deg"].get<double>() << " deg off";
  }
  std::cout << "\n";
}

void run_sim(const SimOptions& options) {
  const firmware::BoardConfig board = firmware::load_board_config(options.board);
  require(hal::BackendRegistry::builtin().camera_traits(board.cameras.backend).simulated,
          options.board,
          ": not a simulated board (cameras.backend "
          "is '",
          board.cameras.backend, "')");
  std::vector<std::string> scenes = options.scenes;
  std::map<std::string, std::string> replayed;  // scene: its override
  for (const std::string& file : options.replay) {
    const ReplayedScene r = replayed_scene(file);
    require(replayed.emplace(r.name, r.setting).second, "--replay ", file,
            ": two recordings named ", r.name);
    scenes.push_back(r.name);
  }
  if (scenes.empty()) {
    for (const auto& s : hal::sim_settings(board.sections).scenes) scenes.push_back(s.name);
  }
  fs::create_directories(options.out);
  nlohmann::json summary = {{"board", board.name}, {"scenes", nlohmann::json::array()}};
  for (const std::string& scene : options.record) {
    require(std::find(scenes.begin(), scenes.end(), scene) != scenes.end(), "--record ", scene,
            ": not a scene this run runs");
  }
  for (const std::string& scene : scenes) {
    const auto replay = replayed.find(scene);
    const nlohmann::json s = run_scene(
        scene, options,
        replay == replayed.end() ? std::vector<std::string>() : std::vector{replay->second});
    for (const auto& file : s.value("recordings", nlohmann::json::array())) {
      if (!options.json)
        std::cout << "sim: scene " << scene << " recorded into " << file.get<std::string>() << "\n";
    }
    if (!options.json) print_scene(s);
    summary["scenes"].push_back(s);
  }
  std::ofstream(fs::path(options.out) / "summary.json") << summary.dump(2) << "\n";
  if (options.json) {
    std::cout << summary.dump(2) << "\n";
  } else {
    std::cout << "sim: pictures, serial streams and summary.json in " << options.out << "\n";
  }
}

}  // namespace

void add_sim_command(CLI::App& app, const GlobalOptions&) {
  auto options = std::make_shared<SimOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sim", "Run the firmware on the simulated board over real stereo images, with pictures");
  cmd->add_option("--board", options->board, "The simulated board's folder or file")
      ->capture_default_str();
  cmd->add_option("--scene", options->scenes, "Scenes to run (default: all of the board's)");
  cmd->add_option("--frames,-n", options->frames,
                  "Frame pairs per scene (default 30; a rendered path: its whole path, one pair "
                  "per pose, or with this its first N poses)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--pictures", options->pictures,
                  "Pictures of the first N distinct images of each scene")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--out,-o", options->out, "Output folder")->capture_default_str();
  cmd->add_option("--record", options->record,
                  "Scenes to record, every pair, into OUT/SCENE/recordings/ (MCAP: "
                  "docs/outputs.md)");
  cmd->add_option("--replay", options->replay,
                  "MCAP recordings to replay, each a scene named after its file: its raw pairs "
                  "with the calibration it carries (docs/outputs.md)");
  cmd->add_flag("--json", options->json,
                "Print the summary (as summary.json) instead of a line per scene");
  cmd->callback([options] { run_sim(*options); });
}

}  // namespace epipole::tools

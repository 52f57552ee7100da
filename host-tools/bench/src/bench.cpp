#include "epipole/tools/bench.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "epipole/calib/camera_turn.hpp"
#include "epipole/calib/rectification_map.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/firmware/board.hpp"
#include "epipole/firmware/cascade_file.hpp"
#include "epipole/firmware/firmware.hpp"
#include "epipole/firmware/pipeline.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "epipole/tools/opencv_mat.hpp"
#include "epipole/tools/progress.hpp"
#include "opencv_pipeline.hpp"
#include "sim/sim_scene.hpp"
#include "sim/sim_settings.hpp"
#include "timing_summary.hpp"

namespace epipole::tools {

namespace {

using protocol::Stage;

struct BenchImages {
  std::vector<GrayImage> left, right;
  std::string source;
};

BenchImages bench_images(const BenchOptions& options, const firmware::BoardConfig& board) {
  BenchImages images;
  if (!options.left.empty()) {
    const GrayImage left = load_gray(options.left);
    const GrayImage right = load_gray(options.right);
    require(same_size(left.view(), right.view()), options.right, " is ", right.width(), "x",
            right.height(), " but ", options.left, " is ", left.width(), "x", left.height());
    images.left.push_back(hal::letterbox(left.view(), board.width(), board.height()));
    images.right.push_back(hal::letterbox(right.view(), board.width(), board.height()));
    images.source = options.left + " and " + options.right;
    return images;
  }
  require(board.sections.find("sim") != nullptr, "board ", board.name,
          " has no simulated scenes to take images from: give --left and --right");
  const hal::SimSettings& sim = hal::sim_settings(board.sections);
  hal::StereoImages scene = hal::load_scene(sim.chosen(), board.width(), board.height());
  images.left = std::move(scene.left);
  images.right = std::move(scene.right);
  images.source = "scene " + sim.scene;
  return images;
}

// The stages' and the pairs' times of one side (Epipole or OpenCV) at one thread count.
struct SideTimes {
  protocol::StageMask stages = 0;
  // What the measured pairs found (Epipole's side): the same at every thread count.
  std::uint64_t corners = 0, matches = 0, detections = 0;
  std::array<std::vector<double>, protocol::kStageCount> stage_ms;
  std::vector<double> pair_ms;
  double seconds = 0;                           // the measured pairs, back to back
  std::vector<firmware::OutputReport> outputs;  // with the board's outputs on: what each did
  std::vector<double> rebuild_ms;  // with a map rebuilt beside each pair: each rebuild's time

  void add(const std::array<double, protocol::kStageCount>& ms, double pair) {
    for (const protocol::StageInfo& s : protocol::kStages) {
      if (protocol::has_stage(stages, s.id)) {
        stage_ms[static_cast<std::size_t>(s.id)].push_back(ms[static_cast<std::size_t>(s.id)]);
      }
    }
    pair_ms.push_back(pair);
    seconds += pair / 1000.0;
  }
  double pairs_per_second() const {
    return seconds > 0 ? static_cast<double>(pair_ms.size()) / seconds : 0;
  }
};

// The bench's next pair is always there: its images, in turn.
class NextBenchPair final : public firmware::NextPair {
 public:
  NextBenchPair(const BenchImages& images, int warmup) : images_(images), warmup_(warmup) {}
  // The pair after pair i (counting from -warmup).
  void after(int i) { next_ = i + 1; }
  std::optional<Images> take() override {
    const std::size_t k = static_cast<std::size_t>(next_ + warmup_) % images_.left.size();
    return Images{images_.left[k].view(), images_.right[k].view(),
                  static_cast<std::uint32_t>(next_ + warmup_)};
  }

 private:
  const BenchImages& images_;
  int warmup_;
  int next_ = 0;
};

// The right rectification map rebuilt on a thread of its own, as a correction of the rig does
// (firmware::RigCorrection's maps thread, at SCHED_IDLE unless the board's threads.maps says
// normal: calib::fill_fixed_point_map into a map made at start-up), for the right camera turned 0.3
// degrees of pitch and 0.2 of roll. Its time is from the request to the map done: the time the
// pairs left it, as in the firmware.
class MapRebuilder {
 public:
  MapRebuilder(const calib::StereoCalibration& rig, int width, int height, bool idle)
      : idle_(idle),
        right_(calib::with_right_camera_turned(
                   rig, calib::turn_rotation({radians(0.3), radians(0.2), 0}))
                   .right),
        map_(width, height),
        thread_([this] { run(); }) {}
  ~MapRebuilder() {
    {
      const std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  MapRebuilder(const MapRebuilder&) = delete;
  MapRebuilder& operator=(const MapRebuilder&) = delete;

  void start() {
    {
      const std::lock_guard lock(mutex_);
      requested_ = true;
      requested_at_ = std::chrono::steady_clock::now();
    }
    wake_.notify_all();
  }
  // The rebuild's time, once it is done.
  double wait() {
    std::unique_lock lock(mutex_);
    wake_.wait(lock, [&] { return !requested_; });
    return ms_;
  }

 private:
  void run() {
    if (idle_) {
      firmware::enter_thread_role(firmware::ThreadRole::maps);
    } else {
      firmware::name_thread(firmware::ThreadRole::maps);
    }
    std::unique_lock lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return stopping_ || requested_; });
      if (stopping_) return;
      const auto start = requested_at_;
      lock.unlock();
      calib::fill_fixed_point_map(right_, map_.xy(), map_.fractions());
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      lock.lock();
      ms_ = ms;
      requested_ = false;
      wake_.notify_all();
    }
  }

  bool idle_;  // the board's threads.maps
  calib::CameraCalibration right_;
  vision::RemapMap map_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool requested_ = false, stopping_ = false;
  std::chrono::steady_clock::time_point requested_at_;
  double ms_ = 0;
  std::thread thread_;
};

std::vector<hal::BackendOption> scene_option(const std::string& scene) {
  if (scene.empty()) return {};
  return {{"scene", scene}};
}

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

class Bench {
 public:
  Bench(const BenchOptions& options, SimdPath path)
      : options_(options),
        board_(firmware::load_board_config(options.board, options.overrides,
                                           scene_option(options.scene))),
        path_(path) {
    if (!options.stages.empty()) {
      board_.stages &= static_cast<protocol::StageMask>(~protocol::kSwitchableStages);
      for (const std::string& name : options.stages) {
        for (const protocol::StageInfo& s : protocol::kStages) {
          if (s.name == name) board_.stages |= protocol::stage_bit(s.id);
        }
      }
    }
    images_ = bench_images(options, board_);
    calibration_ = firmware::load_board_calibration(board_);
    if (!options.rebuild_map.empty()) {
      require(options.epipole, "--rebuild-map times Epipole's side: not with --opencv-only");
      require(calibration_.has_value(), "--rebuild-map: the board has no calibration");
    }
  }

  nlohmann::json run() {
    if (options_.opencv) make_opencv_pipeline();
    nlohmann::json runs = nlohmann::json::array();
    for (const int threads : options_.threads) {
      nlohmann::json run = {{"threads", threads}};
      if (options_.epipole) {
        const SideTimes ours = epipole(threads, false);
        run["epipole"] = summary(ours);
        run["epipole"]["found"] = {
            {"corners", ours.corners}, {"matches", ours.matches}, {"detections", ours.detections}};
        // The board's outputs (outputs: in its file, or --set outputs...): the same pairs again
        // with them on, side by side.
        if (!board_.outputs.empty()) run["epipole_outputs"] = summary(epipole(threads, true));
        if (!options_.rebuild_map.empty()) {
          run["epipole_rebuilding"] = summary(epipole(threads, false, true));
          run["epipole_rebuilding"]["rebuild_map"] = options_.rebuild_map;
        }
      }
      if (opencv_pipeline_) run["opencv"] = summary(opencv(threads));
      runs.push_back(run);
    }
    progress_.done();
    return {{"board", board_.name},
            {"images", images_.source},
            {"width", board_.width()},
            {"height", board_.height()},
            {"max_disparity", board_.stereo.max_disparity},
            {"method", board_.stereo.method == vision::StereoMethod::sgm ? "sgm" : "bm"},
            {"set", options_.overrides},
            {"kernels", std::string(to_string(path_))},
            {"pairs", options_.pairs},
            {"rectify_ahead", options_.rectify_ahead},
            {"warmup", options_.warmup},
            {"notes", notes_},
            {"runs", runs}};
  }

 private:
  // `outputs`: with the board's outputs, each pair handed to them as the frame loop does (its
  // time holds the hand-off; their work runs on their own threads, beside the pool).
  // `rebuilding`: a map rebuilt for each pair (MapRebuilder, --rebuild-map beside or after).
  SideTimes epipole(int threads, bool outputs, bool rebuilding = false) {
    firmware::BoardConfig config = board_;
    config.threads.count = threads;
    firmware::Pipeline pipeline(config, calibration_, path_);
    std::optional<firmware::Outputs> on;
    if (outputs) {
      on.emplace(config, calibration_);
      on->start();
    }
    if (!pipeline.missing_cascade().empty() && !noted_missing_cascade_) {
      notes_.push_back("detect: off, no compiled cascade (" +
                       firmware::cascade_compile_command(pipeline.missing_cascade()) + ")");
      noted_missing_cascade_ = true;
    }
    SideTimes times;
    times.stages = board_.stages & pipeline.available() & protocol::kSwitchableStages;
    NextBenchPair next(images_, options_.warmup);
    std::optional<MapRebuilder> rebuilder;
    if (rebuilding) {
      rebuilder.emplace(*calibration_, board_.width(), board_.height(), board_.threads.maps_idle);
    }
    for (int i = -options_.warmup; i < options_.pairs; ++i) {
      const std::size_t k = static_cast<std::size_t>(i + options_.warmup) % images_.left.size();
      next.after(i);
      const bool beside = rebuilder && options_.rebuild_map == "beside";
      if (beside) rebuilder->start();
      const auto start = std::chrono::steady_clock::now();
      const firmware::FrameResult& r = pipeline.process(
          images_.left[k].view(), images_.right[k].view(),
          static_cast<std::uint32_t>(i + options_.warmup), 0, board_.stages,
          options_.rectify_ahead ? &next : nullptr);  // each pair's time holds one rectification
      if (on) on->publish(r, 0);
      const double pair = ms_since(start);
      if (rebuilder && !beside) rebuilder->start();
      const double rebuild = rebuilder ? rebuilder->wait() : 0;
      show(threads,
           outputs      ? "epipole with outputs"
           : rebuilding ? "epipole with a map rebuilt"
                        : "epipole",
           i);
      if (i < 0) continue;
      if (rebuilder) times.rebuild_ms.push_back(rebuild);
      std::array<double, protocol::kStageCount> ms{};
      for (std::size_t s = 0; s < ms.size(); ++s) ms[s] = static_cast<double>(r.times[s]) / 1e6;
      times.add(ms, pair);
      times.corners += r.corners_left.size() + r.corners_right.size();
      times.matches += r.matches.size();
      times.detections += r.detections.size();
    }
    if (on) {
      on->stop();
      times.outputs = on->reports();
    }
    return times;
  }

  SideTimes opencv(int threads) {
    cv::setNumThreads(threads);
    SideTimes times;
    times.stages = opencv_pipeline_->stages();
    std::vector<cv::Mat> left, right;
    for (std::size_t k = 0; k < images_.left.size(); ++k) {
      left.push_back(mat_of(images_.left[k].view()));
      right.push_back(mat_of(images_.right[k].view()));
    }
    for (int i = -options_.warmup; i < options_.pairs; ++i) {
      const std::size_t k = static_cast<std::size_t>(i + options_.warmup) % left.size();
      const auto start = std::chrono::steady_clock::now();
      const OpenCvPipeline::Times ms = opencv_pipeline_->process(left[k], right[k]);
      const double pair = ms_since(start);
      show(threads, "opencv", i);
      if (i >= 0) times.add(ms, pair);
    }
    return times;
  }

  // OpenCV does the stages the firmware does, where it has them (no sparse matching); detection
  // with the XML the board's compiled cascade was made from.
  void make_opencv_pipeline() {
    require(options_.opencv_sgbm == "3way" || options_.opencv_sgbm == "default",
            "OpenCV's SGBM mode '", options_.opencv_sgbm, "' is neither 3way nor default");
    const firmware::Pipeline pipeline(board_, calibration_, path_);  // what the board can run
    std::filesystem::path xml;
    if (protocol::has_stage(pipeline.available() & board_.stages, Stage::detect)) {
      xml = firmware::opencv_cascade_xml(board_.detector.cascade);
      if (xml.empty()) {
        notes_.push_back("opencv detect: off, no OpenCV XML for " +
                         board_.detector.cascade.string() + " in the data cache");
      }
    }
    opencv_pipeline_.emplace(board_, calibration_, xml, options_.opencv_sgbm == "3way");
    if (board_.stereo.method == vision::StereoMethod::sgm) {
      notes_.push_back("opencv sgm: StereoSGBM, mode " + options_.opencv_sgbm);
    }
    notes_.push_back("opencv has no sparse matching: its pair is without that stage");
  }

  void show(int threads, const char* side, int i) {
    const int total = options_.warmup + options_.pairs;
    const int done = i + options_.warmup + 1;
    progress_.show(cat("bench: ", threads, threads == 1 ? " thread: " : " threads: ", side,
                       " pair ", done, " of ", total),
                   done == total);
  }

  static nlohmann::json summary(const SideTimes& t) {
    const auto json = [](const TimingSummary& s) {
      return nlohmann::json{{"p50_ms", s.p50_ms}, {"p99_ms", s.p99_ms}, {"mean_ms", s.mean_ms}};
    };
    nlohmann::json stages = nlohmann::json::object();
    for (const protocol::StageInfo& s : protocol::kStages) {
      if (!protocol::has_stage(t.stages, s.id)) continue;
      stages[std::string(s.name)] = json(summarize(t.stage_ms[static_cast<std::size_t>(s.id)]));
    }
    nlohmann::json out = {{"stages", stages},
                          {"pair", json(summarize(t.pair_ms))},
                          {"pairs_per_second", t.pairs_per_second()}};
    if (!t.rebuild_ms.empty()) out["map_rebuild"] = json(summarize(t.rebuild_ms));
    for (const firmware::OutputReport& o : t.outputs) {
      out["outputs"][o.name] = {
          {"delivered", o.delivered},
          {"dropped", o.dropped},
          {"failures", o.failures},
          {"work_ms_per_pair",
           o.delivered > 0 ? static_cast<double>(o.work_ns) / 1e6 / static_cast<double>(o.delivered)
                           : 0.0}};
    }
    return out;
  }

  BenchOptions options_;
  firmware::BoardConfig board_;
  SimdPath path_;
  BenchImages images_;
  std::optional<calib::StereoCalibration> calibration_;
  std::optional<OpenCvPipeline> opencv_pipeline_;
  std::vector<std::string> notes_;
  bool noted_missing_cascade_ = false;
  Progress progress_;
};

void print_table(const nlohmann::json& b) {
  std::printf(
      "epipole bench: board %s, %dx%d, %d disparities (%s), %s, kernels %s; %d pairs "
      "after %d warm-up\n",
      b["board"].get<std::string>().c_str(), b["width"].get<int>(), b["height"].get<int>(),
      b["max_disparity"].get<int>(), b["method"].get<std::string>().c_str(),
      b["images"].get<std::string>().c_str(), b["kernels"].get<std::string>().c_str(),
      b["pairs"].get<int>(), b["warmup"].get<int>());
  std::printf("  each pair rectified %s\n", b["rectify_ahead"].get<bool>()
                                                ? "ahead, while the one before ends"
                                                : "when it is processed (--no-rectify-ahead)");
  for (const auto& key : b["set"]) std::printf("  set: %s\n", key.get<std::string>().c_str());
  for (const auto& note : b["notes"]) std::printf("  note: %s\n", note.get<std::string>().c_str());
  for (const auto& all_sides : b["runs"]) {
    // With one side only (--no-opencv, --opencv-only), its figures take the first columns.
    const bool opencv = all_sides.contains("epipole") && all_sides.contains("opencv");
    const std::string first = all_sides.contains("epipole") ? "epipole" : "opencv";
    nlohmann::json run = {{"threads", all_sides["threads"]}, {"epipole", all_sides[first]}};
    if (opencv) run["opencv"] = all_sides["opencv"];
    const int threads = run["threads"].get<int>();
    std::printf("\n%d %-8s   %7s p50    p99 ms%s\n", threads, threads == 1 ? "thread" : "threads",
                first.c_str(), opencv ? "   opencv p50    p99 ms   opencv/epipole" : "");
    const auto row = [&](const std::string& name, const nlohmann::json& ours,
                         const nlohmann::json* theirs) {
      std::printf("  %-12s %10.2f %8.2f", name.c_str(), ours["p50_ms"].get<double>(),
                  ours["p99_ms"].get<double>());
      if (theirs != nullptr) {
        std::printf("  %10.2f %8.2f   %6.1fx", (*theirs)["p50_ms"].get<double>(),
                    (*theirs)["p99_ms"].get<double>(),
                    (*theirs)["p50_ms"].get<double>() / ours["p50_ms"].get<double>());
      } else if (opencv) {
        std::printf("  %10s %8s", "-", "-");
      }
      std::printf("\n");
    };
    for (const protocol::StageInfo& s : protocol::kStages) {  // in the order they run
      const std::string name(s.name);
      if (!run["epipole"]["stages"].contains(name)) continue;
      const bool both = opencv && run["opencv"]["stages"].contains(name);
      row(name, run["epipole"]["stages"][name], both ? &run["opencv"]["stages"][name] : nullptr);
    }
    row("pair", run["epipole"]["pair"], opencv ? &run["opencv"]["pair"] : nullptr);
    const double ours = run["epipole"]["pairs_per_second"].get<double>();
    std::printf("  %-12s %10.1f %8s", "pairs/s", ours, "");
    if (opencv) {
      const double theirs = run["opencv"]["pairs_per_second"].get<double>();
      std::printf("  %10.1f %8s   %6.1fx", theirs, "", ours / theirs);
    }
    std::printf("\n");
    if (all_sides.contains("epipole_outputs")) {
      const nlohmann::json& with = all_sides["epipole_outputs"];
      const double rate = with["pairs_per_second"].get<double>();
      std::printf("  with outputs: pair %.2f / %.2f ms, %.1f pairs/s (%.0f %% of without)\n",
                  with["pair"]["p50_ms"].get<double>(), with["pair"]["p99_ms"].get<double>(), rate,
                  100.0 * rate / ours);
      for (const auto& [name, o] : with["outputs"].items()) {
        std::printf(
            "    output %-6s %.2f ms of work a pair delivered, %llu delivered, %llu dropped, "
            "%llu failures\n",
            name.c_str(), o["work_ms_per_pair"].get<double>(),
            o["delivered"].get<unsigned long long>(), o["dropped"].get<unsigned long long>(),
            o["failures"].get<unsigned long long>());
      }
    }
    if (all_sides.contains("epipole_rebuilding")) {
      const nlohmann::json& with = all_sides["epipole_rebuilding"];
      std::printf(
          "  a map rebuilt %s each pair: pair %.2f / %.2f ms (%.0f %% of without), the "
          "rebuild %.2f / %.2f ms\n",
          with["rebuild_map"].get<std::string>().c_str(), with["pair"]["p50_ms"].get<double>(),
          with["pair"]["p99_ms"].get<double>(),
          100.0 * with["pair"]["p50_ms"].get<double>() /
              run["epipole"]["pair"]["p50_ms"].get<double>(),
          with["map_rebuild"]["p50_ms"].get<double>(), with["map_rebuild"]["p99_ms"].get<double>());
    }
  }
}

}  // namespace

void run_bench(BenchOptions options, SimdPath path) {
  if (options.threads.empty()) {
    for (int n = 1; n <= std::min(usable_cpus(), 64); ++n) options.threads.push_back(n);
  }
  Bench bench(options, path);
  const nlohmann::json result = bench.run();
  if (options.json) {
    std::cout << result.dump(2) << "\n";
  } else {
    print_table(result);
  }
}

void add_bench_options(CLI::App& command, BenchOptions& options) {
  CLI::App* cmd = &command;
  cmd->add_option("--board", options.board, "The board's folder or file")->capture_default_str();
  cmd->add_option("--scene", options.scene,
                  "The simulated scene to take images from (default: the board's)");
  auto* left = cmd->add_option("--left", options.left, "Left image instead of a scene")
                   ->check(CLI::ExistingFile);
  auto* right = cmd->add_option("--right", options.right, "Right image instead of a scene")
                    ->check(CLI::ExistingFile);
  left->needs(right);
  right->needs(left);
  cmd->add_option("--threads", options.threads,
                  "Thread counts to measure, e.g. 1,2,4 (default: 1 to the CPUs usable)")
      ->delimiter(',')
      ->check(CLI::Range(1, 64));
  std::vector<std::string> switchable;
  for (const protocol::StageInfo& s : protocol::kStages) {
    if (s.kind == protocol::StageKind::switchable) switchable.emplace_back(s.name);
  }
  cmd->add_option("--stages", options.stages,
                  "Run only these stages, e.g. rectify,disparity (default: the board's)")
      ->delimiter(',')
      ->check(CLI::IsMember(switchable));
  cmd->add_option("--set", options.overrides,
                  "Set a key of the board file first, e.g. --set stereo.method=bm (repeatable)")
      ->type_name("KEY=VALUE");
  cmd->add_option("--pairs,-n", options.pairs, "Pairs measured per thread count and side")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--warmup", options.warmup, "Pairs run first and not measured")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  auto* no_opencv =
      cmd->add_flag("--no-opencv{false}", options.opencv, "Time the firmware's stages only");
  cmd->add_flag("--opencv-only{false}", options.epipole,
                "Time OpenCV's pipeline only (for one side's instruction count under QEMU)")
      ->excludes(no_opencv);
  cmd->add_flag("--no-rectify-ahead{false}", options.rectify_ahead,
                "Rectify each pair when it is processed, not in the gaps while the one before "
                "ends (the firmware's loop does that when the next pair is already there)");
  cmd->add_option("--opencv-sgbm", options.opencv_sgbm,
                  "OpenCV's mode of StereoSGBM beside SGM: 3way (MODE_SGBM_3WAY) or default "
                  "(MODE_SGBM)")
      ->check(CLI::IsMember({"3way", "default"}))
      ->capture_default_str();
  cmd->add_option("--rebuild-map", options.rebuild_map,
                  "Also run the pairs with the right rectification map rebuilt for each on a "
                  "thread of its own, as a correction of the rig does: beside the pair (the "
                  "pairs' times with it) or after it (the rebuild's own time; exact "
                  "instruction counts)")
      ->check(CLI::IsMember({"beside", "after"}));
  cmd->add_flag("--json", options.json, "Print the figures as JSON");
}

}  // namespace epipole::tools

// epipole detect IMAGE --cascade FILE: Viola-Jones detection (the firmware's detector), as
// JSON boxes and/or a picture with the boxes drawn.
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/tools/cascade_xml.hpp"
#include "epipole/vision/cascade.hpp"
#include "pictures.hpp"

namespace epipole::tools {

namespace {

struct DetectOptions {
  std::string image;
  std::string cascade;
  double scale_factor = 1.1;
  int min_neighbors = 3;
  int min_size = 0;
  int max_size = 0;
  bool json = false;
  std::string draw;
};

void run_detect(const DetectOptions& options, const GlobalOptions& global) {
  const GrayImage image = load_gray(options.image);
  const vision::CascadeModel model = load_cascade(options.cascade);
  vision::CascadeConfig config;
  config.max_width = image.width();
  config.max_height = image.height();
  config.scale_factor = options.scale_factor;
  config.min_neighbors = options.min_neighbors;
  config.min_object_width = config.min_object_height = options.min_size;
  config.max_object_width = config.max_object_height = options.max_size;
  vision::CascadeDetector detector(model, config, parse_simd_path(global.kernels));
  const auto start = std::chrono::steady_clock::now();
  const std::span<const vision::Detection> detections = detector.detect(image.view());
  const std::chrono::duration<double, std::milli> elapsed =
      std::chrono::steady_clock::now() - start;

  if (options.json) {
    nlohmann::json boxes = nlohmann::json::array();
    for (const vision::Detection& d : detections) {
      boxes.push_back(
          {{"x", d.x}, {"y", d.y}, {"w", d.width}, {"h", d.height}, {"neighbors", d.neighbors}});
    }
    const nlohmann::json out = {{"width", image.width()},
                                {"height", image.height()},
                                {"cascade", std::string(to_string(model.feature_type()))},
                                {"window", {model.window_width(), model.window_height()}},
                                {"levels", detector.levels()},
                                {"raw_hits", detector.raw_hits().size()},
                                {"truncated", detector.truncated()},
                                {"kernels", std::string(to_string(detector.simd_path()))},
                                {"working_set_bytes", detector.working_set_bytes()},
                                {"milliseconds", elapsed.count()},
                                {"detections", std::move(boxes)}};
    std::cout << out.dump() << "\n";
  } else {
    std::cout << detections.size() << " detections (" << to_string(model.feature_type()) << " "
              << model.window_width() << "x" << model.window_height() << ", " << detector.levels()
              << " levels, " << detector.raw_hits().size() << " raw hits, "
              << to_string(detector.simd_path()) << ") in " << elapsed.count() << " ms"
              << (detector.truncated() ? ", truncated" : "") << "\n";
  }

  if (!options.draw.empty()) {
    RgbImage picture = rgb_picture(image.view());
    cv::Mat drawing = mat_of(picture.view());
    for (const vision::Detection& d : detections) {
      cv::rectangle(drawing, cv::Rect(d.x, d.y, d.width, d.height), {0, 255, 0}, 2);
    }
    save_image(options.draw, ImageView<const Rgb8>(picture.view()));
  }
}

}  // namespace

void add_detect_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<DetectOptions>();
  CLI::App* cmd = app.add_subcommand(
      "detect", "Detect objects with a Viola-Jones cascade (OpenCV XML or compiled .bin)");
  cmd->add_option("image", options->image, "Image file (PNG, JPEG, PGM)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--cascade", options->cascade,
                  "Cascade: OpenCV's XML (traincascade format) or epipole cascade-compile output")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--scale-factor", options->scale_factor,
                  "Each pyramid level is this much smaller (> 1)")
      ->check(CLI::Range(1.0001, 100.0))
      ->capture_default_str();
  cmd->add_option("--min-neighbors", options->min_neighbors,
                  "Keep groups of more than N raw hits (0: every raw hit, ungrouped)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd->add_option("--min-size", options->min_size, "Smallest window side searched (0: none)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_option("--max-size", options->max_size,
                  "Largest window side searched (0: the image size)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_flag("--json", options->json,
                R"(Print {"detections":[{"x","y","w","h","neighbors"}], ...} as JSON)");
  cmd->add_option("--draw", options->draw, "Write a picture with the boxes drawn (.png)");
  cmd->callback([options, &global] { run_detect(*options, global); });
}

}  // namespace epipole::tools

// epipole features IMAGE: corners of one image, as JSON and/or a picture.
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "epipole/core/draw.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/vision/fast.hpp"

namespace epipole::tools {

namespace {

struct FeaturesOptions {
  std::string image;
  std::string detector = "fast";
  int threshold = 20;
  int max_corners = 10'000;
  bool no_nonmax = false;
  bool json = false;
  std::string draw;
};

void run_features(const FeaturesOptions& options, const GlobalOptions& global) {
  const GrayImage image = load_gray(options.image);
  vision::FastConfig config;
  config.width = image.width();
  config.height = image.height();
  config.threshold = options.threshold;
  config.max_corners = options.max_corners;
  config.nonmax = !options.no_nonmax;
  vision::FastDetector detector(config, parse_simd_path(global.kernels));

  const auto start = std::chrono::steady_clock::now();
  const std::span<const vision::Corner> corners = detector.detect(image.view());
  const std::chrono::duration<double, std::milli> elapsed =
      std::chrono::steady_clock::now() - start;

  if (options.json) {
    nlohmann::json keypoints = nlohmann::json::array();
    for (const vision::Corner& c : corners) {
      keypoints.push_back({{"x", c.x}, {"y", c.y}, {"score", c.score}});
    }
    const nlohmann::json out = {{"width", image.width()},
                                {"height", image.height()},
                                {"detector", options.detector},
                                {"threshold", config.threshold},
                                {"kernels", to_string(detector.simd_path())},
                                {"truncated", detector.truncated()},
                                {"keypoints", std::move(keypoints)}};
    std::cout << out.dump() << "\n";
  } else {
    std::cout << corners.size() << " corners (" << options.detector << ", threshold "
              << config.threshold << ", " << to_string(detector.simd_path()) << ") in "
              << elapsed.count() << " ms" << (detector.truncated() ? ", truncated" : "") << "\n";
  }

  if (!options.draw.empty()) {
    RgbImage picture(image.width(), image.height());
    gray_to_rgb(image.view(), picture.view());
    for (const vision::Corner& c : corners) {
      draw_circle(picture.view(), c.x, c.y, 3, {0, 255, 0});
    }
    save_image(options.draw, ImageView<const Rgb8>(picture.view()));
  }
}

}  // namespace

void add_features_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<FeaturesOptions>();
  CLI::App* cmd = app.add_subcommand("features", "Detect corners in an image (FAST-9)");
  cmd->add_option("image", options->image, "Image file (PNG, JPEG, PGM)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--detector", options->detector, "Corner detector")
      ->check(CLI::IsMember({"fast"}))
      ->capture_default_str();
  cmd->add_option("--threshold,-t", options->threshold, "FAST intensity threshold (0..255)")
      ->check(CLI::Range(0, 255))
      ->capture_default_str();
  cmd->add_option("--max,-n", options->max_corners, "Keep at most N corners (the strongest)")
      ->check(CLI::Range(1, 10'000'000))
      ->capture_default_str();
  cmd->add_flag("--no-nonmax", options->no_nonmax, "Skip 3x3 non-maximum suppression");
  cmd->add_flag("--json", options->json,
                R"(Print {"width","height","keypoints":[{"x","y","score"}]} as JSON)");
  cmd->add_option("--draw", options->draw, "Write a picture with the corners circled (.png)");
  cmd->callback([options, &global] { run_features(*options, global); });
}

}  // namespace epipole::tools

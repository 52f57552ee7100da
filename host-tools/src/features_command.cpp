// epipole features IMAGE: corners of one image, as JSON and/or a picture.
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/vision/fast.hpp"
#include "epipole/vision/harris.hpp"
#include "pictures.hpp"

namespace epipole::tools {

namespace {

struct FeaturesOptions {
  std::string image;
  std::string detector = "fast";
  int threshold = 20;
  int max_corners = 10'000;
  bool no_nonmax = false;
  double quality = 0.01;     // Harris
  double min_distance = 10;  // Harris
  int block_size = 3;        // Harris
  double k = 0.04;           // Harris
  bool json = false;
  std::string draw;
};

// The corners of one detector run and what describes it.
struct Detection {
  std::span<const vision::Corner> corners;
  SimdPath path = SimdPath::reference;
  bool truncated = false;
  double milliseconds = 0.0;
  nlohmann::json parameters;  // the detector's settings, for the JSON and the summary line
};

template <typename Detector>
Detection run_detector(Detector& detector, const GrayImage& image) {
  const auto start = std::chrono::steady_clock::now();
  Detection d;
  d.corners = detector.detect(image.view());
  const std::chrono::duration<double, std::milli> elapsed =
      std::chrono::steady_clock::now() - start;
  d.milliseconds = elapsed.count();
  d.path = detector.simd_path();
  d.truncated = detector.truncated();
  return d;
}

void run_features(const FeaturesOptions& options, const GlobalOptions& global) {
  const GrayImage image = load_gray(options.image);
  const SimdPath path = parse_simd_path(global.kernels);
  std::unique_ptr<vision::FastDetector> fast;
  std::unique_ptr<vision::HarrisDetector> harris;
  Detection detection;
  if (options.detector == "harris") {
    vision::HarrisConfig config;
    config.width = image.width();
    config.height = image.height();
    config.block_size = options.block_size;
    config.k = options.k;
    config.quality_level = options.quality;
    config.min_distance = options.min_distance;
    config.max_corners = options.max_corners;
    harris = std::make_unique<vision::HarrisDetector>(config, path);
    detection = run_detector(*harris, image);
    detection.parameters = {{"quality", config.quality_level},
                            {"min_distance", config.min_distance},
                            {"block_size", config.block_size},
                            {"k", config.k}};
  } else {
    vision::FastConfig config;
    config.width = image.width();
    config.height = image.height();
    config.threshold = options.threshold;
    config.max_corners = options.max_corners;
    config.nonmax = !options.no_nonmax;
    fast = std::make_unique<vision::FastDetector>(config, path);
    detection = run_detector(*fast, image);
    detection.parameters = {{"threshold", fast->config().threshold}};
  }
  const std::span<const vision::Corner> corners = detection.corners;

  if (options.json) {
    nlohmann::json keypoints = nlohmann::json::array();
    for (const vision::Corner& c : corners) {
      keypoints.push_back({{"x", c.x}, {"y", c.y}, {"score", c.score}});
    }
    nlohmann::json out = {
        {"width", image.width()}, {"height", image.height()}, {"detector", options.detector}};
    out.update(detection.parameters);
    out["kernels"] = to_string(detection.path);
    out["truncated"] = detection.truncated;
    out["keypoints"] = std::move(keypoints);
    std::cout << out.dump() << "\n";
  } else {
    std::cout << corners.size() << " corners (" << options.detector;
    for (const auto& [name, value] : detection.parameters.items()) {
      std::cout << ", " << name << " " << value.dump();
    }
    std::cout << ", " << to_string(detection.path) << ") in " << detection.milliseconds << " ms"
              << (detection.truncated ? ", truncated" : "") << "\n";
  }

  if (!options.draw.empty()) {
    RgbImage picture = rgb_picture(image.view());
    cv::Mat drawing = mat_of(picture.view());
    for (const vision::Corner& c : corners) {
      cv::circle(drawing, {c.x, c.y}, 3, {0, 255, 0}, 1, cv::LINE_AA);
    }
    save_image(options.draw, ImageView<const Rgb8>(picture.view()));
  }
}

}  // namespace

void add_features_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<FeaturesOptions>();
  CLI::App* cmd = app.add_subcommand("features", "Detect corners in an image (FAST-9 or Harris)");
  cmd->add_option("image", options->image, "Image file (PNG, JPEG, PGM)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--detector", options->detector, "Corner detector")
      ->check(CLI::IsMember({"fast", "harris"}))
      ->capture_default_str();
  cmd->add_option("--threshold,-t", options->threshold, "FAST intensity threshold (0..255)")
      ->check(CLI::Range(0, 255))
      ->capture_default_str();
  cmd->add_option("--max-corners,--max,-c", options->max_corners,
                  "Keep at most N corners (the strongest)")
      ->check(CLI::Range(1, 10'000'000))
      ->capture_default_str();
  cmd->add_flag("--no-nonmax", options->no_nonmax, "FAST: skip 3x3 non-maximum suppression");
  cmd->add_option("--quality", options->quality,
                  "Harris: keep R > quality * max(R) (as goodFeaturesToTrack's qualityLevel)")
      ->check(CLI::Range(1e-9, 1.0))
      ->capture_default_str();
  cmd->add_option("--min-distance", options->min_distance,
                  "Harris: minimum distance between corners, in pixels")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  cmd->add_option("--block-size", options->block_size,
                  "Harris: window of the structure tensor (odd, 1..31)")
      ->check(CLI::Range(1, vision::kHarrisMaxBlockSize))
      ->capture_default_str();
  cmd->add_option("--k", options->k, "Harris: k in R = det(M) - k trace(M)^2")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_flag("--json", options->json,
                R"(Print {"width","height","keypoints":[{"x","y","score"}]} as JSON)");
  cmd->add_option("--draw", options->draw, "Write a picture with the corners circled (.png)");
  cmd->callback([options, &global] { run_features(*options, global); });
}

}  // namespace epipole::tools

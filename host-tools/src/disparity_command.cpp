// epipole disparity LEFT RIGHT: dense disparity of a (rectified, or rectified here with --calib)
// pair, as a 16-bit PNG of disparity x16 (0 = invalid) and optionally a colour picture with a
// legend.
#include <algorithm>
#include <array>
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/vision/stereo.hpp"
#include "pictures.hpp"
#include "stereo_input.hpp"

namespace epipole::tools {

namespace {

struct DisparityOptions {
  std::string left;
  std::string right;
  std::string calib;
  int max_disparity = 64;
  std::string method = "sgm";
  int block_size = 7;
  int p1 = 11;
  int p2 = 120;
  int uniqueness = 10;
  int threads = 1;
  bool fill_occlusions = false;
  int spatial = 0;
  int hole_fill = 0;
  std::string out;
  std::string color;
  std::string confidence;
  bool json = false;
};

void run_disparity(const DisparityOptions& options, const GlobalOptions& global) {
  const SimdPath path = parse_simd_path(global.kernels);
  const StereoInput input = load_stereo_input(options.left, options.right, options.calib, path);
  const GrayView left_view = input.left;
  const GrayView right_view = input.right;

  vision::StereoConfig config;
  config.width = left_view.width();
  config.height = left_view.height();
  config.max_disparity = options.max_disparity;
  config.method = options.method == "bm" ? vision::StereoMethod::bm : vision::StereoMethod::sgm;
  config.block_size = options.block_size;
  config.p1 = options.p1;
  config.p2 = options.p2;
  config.uniqueness = options.uniqueness;
  config.threads = options.threads;
  config.fill_occlusions = options.fill_occlusions;
  config.spatial_percent = options.spatial;
  config.hole_fill = options.hole_fill;
  config.confidence = !options.confidence.empty();
  vision::StereoMatcher matcher(config, path);

  const auto start = std::chrono::steady_clock::now();
  const ImageView<const std::int16_t> disparity = matcher.compute(left_view, right_view);
  const std::chrono::duration<double, std::milli> elapsed =
      std::chrono::steady_clock::now() - start;

  Image<std::uint16_t> png(disparity.width(), disparity.height());
  long valid = 0;
  int lowest = 0x7FFF;
  int highest = 0;
  for (int y = 0; y < disparity.height(); ++y) {
    for (int x = 0; x < disparity.width(); ++x) {
      const int d = disparity(x, y);
      if (d == vision::kInvalidDisparity) {
        png(x, y) = 0;
        continue;
      }
      ++valid;
      lowest = std::min(lowest, d);
      highest = std::max(highest, d);
      png(x, y) = static_cast<std::uint16_t>(std::max(d, 0));
    }
  }
  save_image(options.out, ImageView<const std::uint16_t>(png.view()));
  if (!options.color.empty()) {
    const RgbImage picture = disparity_picture(disparity, config.max_disparity);
    save_image(options.color, picture.view());
  }
  if (config.confidence) save_image(options.confidence, matcher.confidence());
  const double density =
      static_cast<double>(valid) / (static_cast<double>(disparity.width()) * disparity.height());
  if (valid == 0) lowest = 0;
  if (options.json) {
    nlohmann::json out = {{"width", disparity.width()},
                          {"height", disparity.height()},
                          {"method", options.method},
                          {"max_disparity", config.max_disparity},
                          {"kernels", to_string(matcher.simd_path())},
                          {"threads", config.threads},
                          {"rectified", input.rectifiers.has_value()},
                          {"density", density},
                          {"min_disparity", lowest / 16.0},
                          {"max_disparity_found", highest / 16.0},
                          {"milliseconds", elapsed.count()},
                          {"out", options.out}};
    if (config.confidence) out["confidence"] = options.confidence;
    std::cout << out.dump() << "\n";
  } else {
    std::cout << "disparity " << disparity.width() << "x" << disparity.height() << " ("
              << options.method << ", " << config.max_disparity << " disparities, "
              << to_string(matcher.simd_path()) << "): " << 100.0 * density << " % valid, "
              << lowest / 16.0 << ".." << highest / 16.0 << " px, " << elapsed.count() << " ms -> "
              << options.out << "\n";
  }
}

}  // namespace

void add_disparity_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<DisparityOptions>();
  CLI::App* cmd = app.add_subcommand(
      "disparity", "Dense disparity of a stereo pair (16-bit PNG of disparity x16, 0 = invalid)");
  cmd->add_option("left", options->left, "Left image (PNG, JPEG, PGM)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("right", options->right, "Right image")->required()->check(CLI::ExistingFile);
  cmd->add_option("--calib", options->calib,
                  "Calibration file (YAML): rectify the raw pair before matching")
      ->check(CLI::ExistingFile);
  cmd->add_option("--max-disparity,-d", options->max_disparity,
                  "Disparities 0..N-1 are searched (16..256, a multiple of 16)")
      ->capture_default_str();
  cmd->add_option("--method", options->method, "sgm (quality) or bm (fast)")
      ->check(CLI::IsMember({"sgm", "bm"}))
      ->capture_default_str();
  cmd->add_option("--block-size", options->block_size, "bm: box size (odd, 3..21)")
      ->capture_default_str();
  cmd->add_option("--p1", options->p1, "sgm: penalty for a disparity step of 1")
      ->capture_default_str();
  cmd->add_option("--p2", options->p2, "sgm: penalty for larger steps (P1..224)")
      ->capture_default_str();
  cmd->add_option("--uniqueness", options->uniqueness, "Uniqueness ratio, percent (0..99)")
      ->capture_default_str();
  cmd->add_flag("--fill-occlusions", options->fill_occlusions,
                "Fill the pixels the right camera cannot see (found by the left-right check) "
                "from their background");
  cmd->add_option("--spatial", options->spatial,
                  "Edge-preserving smoothing along rows and columns: a pixel's own weight "
                  "against its filtered neighbour, percent (1..99; 0: off)")
      ->check(CLI::Range(0, 99))
      ->capture_default_str();
  cmd->add_option("--hole-fill", options->hole_fill,
                  "Fill holes up to this many pixels along a row from their background side "
                  "(0: off)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Row stripes on this many threads (1..64)")
      ->capture_default_str();
  cmd->add_option("--out,-o", options->out, "Disparity x16 as a 16-bit PNG (0 = invalid)")
      ->required();
  cmd->add_option("--color", options->color,
                  "Colour picture of the disparity with a legend (.png)");
  cmd->add_option("--confidence", options->confidence,
                  "Each pixel's confidence as an 8-bit PNG: 1..255, how clearly its disparity "
                  "beat the others; 0 where it is invalid or filled");
  cmd->add_flag("--json", options->json, "Print a summary as JSON");
  cmd->callback([options, &global] { run_disparity(*options, global); });
}

}  // namespace epipole::tools

// epipole eval-disparity DISP GT: a disparity map against ground truth, in the figures of the
// Middlebury and KITTI benchmarks (vision/disparity_quality.hpp), over every pixel with ground
// truth and, with a mask, over the non-occluded ones.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "commands.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/vision/disparity_quality.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::tools {

namespace {

struct EvalOptions {
  std::string disparity;
  std::string truth;
  std::string mask;
  double disparity_scale = vision::kDisparityScale;
  double truth_scale = 1;
  bool json = false;
};

// The map as the matcher gives it: x16, missing below 0 (a file's 0 is missing).
Image<std::int16_t> load_disparity(const EvalOptions& options) {
  const Image<std::uint16_t> file = load_gray16(options.disparity);
  Image<std::int16_t> d(file.width(), file.height());
  const double to_x16 = vision::kDisparityScale / options.disparity_scale;
  for (int y = 0; y < file.height(); ++y) {
    for (int x = 0; x < file.width(); ++x) {
      const double v = std::round(file(x, y) * to_x16);
      require(v <= 32767, options.disparity, ": ", file(x, y), " at (", x, ", ", y, ") is ",
              v / vision::kDisparityScale, " px, beyond what a disparity map holds (2047 px)",
              " (is --disparity-scale right?)");
      d(x, y) = file(x, y) == 0 ? vision::kInvalidDisparity : static_cast<std::int16_t>(v);
    }
  }
  return d;
}

Image<float> load_truth(const EvalOptions& options) {
  const Image<std::uint16_t> file = load_gray16(options.truth);
  Image<float> t(file.width(), file.height());
  for (int y = 0; y < file.height(); ++y) {
    for (int x = 0; x < file.width(); ++x) {
      t(x, y) = static_cast<float>(file(x, y) / options.truth_scale);
    }
  }
  return t;
}

// Middlebury's masks: 255 non-occluded, 128 occluded, 0 unknown.
Image<std::uint8_t> load_nonoccluded(const std::string& file) {
  const GrayImage mask = load_gray(file);
  Image<std::uint8_t> m(mask.width(), mask.height());
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x < mask.width(); ++x) m(x, y) = mask(x, y) == 255 ? 1 : 0;
  }
  return m;
}

nlohmann::json json_of(const vision::DisparityQuality& q) {
  return {{"pixels", q.known},    {"valid", q.valid},
          {"bad1", q.bad1},       {"bad2", q.bad2},
          {"bad4", q.bad4},       {"d1", q.d1},
          {"density", q.density}, {"mean_error_px", q.mean_error}};
}

void print_row(const char* name, const vision::DisparityQuality& q) {
  std::printf("%-14s %6.2f %% %6.2f %% %6.2f %% %6.2f %% %7.2f %% %8.3f px %10lld\n", name,
              100 * q.bad1, 100 * q.bad2, 100 * q.bad4, 100 * q.d1, 100 * q.density, q.mean_error,
              static_cast<long long>(q.known));
}

void run_eval(const EvalOptions& options) {
  const Image<std::int16_t> disparity = load_disparity(options);
  const Image<float> truth = load_truth(options);
  require(same_size(disparity.view(), truth.view()), options.disparity, " is ", disparity.width(),
          "x", disparity.height(), " but ", options.truth, " is ", truth.width(), "x",
          truth.height());
  const vision::DisparityQuality all = vision::disparity_quality(disparity.view(), truth.view());
  std::optional<vision::DisparityQuality> nonoccluded;
  if (!options.mask.empty()) {
    const Image<std::uint8_t> mask = load_nonoccluded(options.mask);
    require(same_size(mask.view(), truth.view()), options.mask, " is ", mask.width(), "x",
            mask.height(), " but ", options.truth, " is ", truth.width(), "x", truth.height());
    nonoccluded = vision::disparity_quality(disparity.view(), truth.view(), mask.view());
  }
  require(all.known > 0, options.truth, " has no pixel with ground truth (all 0)");
  if (options.json) {
    nlohmann::json out = {{"disparity", options.disparity},
                          {"truth", options.truth},
                          {"width", truth.width()},
                          {"height", truth.height()},
                          {"all", json_of(all)}};
    if (nonoccluded) out["nonoccluded"] = json_of(*nonoccluded);
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::printf("%s against %s (%dx%d)\n", options.disparity.c_str(), options.truth.c_str(),
              truth.width(), truth.height());
  std::printf("%-14s %8s %8s %8s %8s %9s %11s %10s\n", "pixels", "bad1", "bad2", "bad4", "D1",
              "density", "mean error", "with truth");
  print_row("all", all);
  if (nonoccluded) print_row("non-occluded", *nonoccluded);
}

}  // namespace

void add_eval_disparity_command(CLI::App& app, const GlobalOptions&) {
  auto options = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand(
      "eval-disparity",
      "Score a disparity map against ground truth: bad1/bad2/bad4 (missing or off by more than "
      "1/2/4 px), KITTI's D1, density, mean error, over all pixels with ground truth and the "
      "non-occluded ones");
  cmd->add_option("disparity", options->disparity,
                  "Disparity map: 16-bit PNG or PGM, 0 missing (epipole disparity --out)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("truth", options->truth, "Ground truth: 8- or 16-bit PNG or PGM, 0 unknown")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--mask", options->mask,
                  "Non-occluded pixels: 255 (Middlebury's masks: 128 occluded, 0 unknown)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--disparity-scale", options->disparity_scale,
                  "File values per pixel of disparity (16: epipole's; 256: KITTI's)")
      ->check(CLI::Range(1.0, 65535.0))
      ->capture_default_str();
  cmd->add_option("--truth-scale", options->truth_scale,
                  "Ground-truth values per pixel (1: Middlebury's 8-bit; 256: KITTI's)")
      ->check(CLI::Range(1.0, 65535.0))
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the figures as JSON");
  cmd->callback([options] { run_eval(*options); });
}

}  // namespace epipole::tools

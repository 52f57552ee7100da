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
#include "epipole/core/draw.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/vision/stereo.hpp"
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
  std::string out;
  std::string color;
  bool json = false;
};

// A colour for t in [0, 1]: blue (far) through green and yellow to red (near).
Rgb8 colour_of(double t) {
  t = std::clamp(t, 0.0, 1.0);
  const auto ramp = [](double v) {
    return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);
  };
  return {ramp(1.5 - std::abs(4.0 * t - 3.0)), ramp(1.5 - std::abs(4.0 * t - 2.0)),
          ramp(1.5 - std::abs(4.0 * t - 1.0))};
}

// A 3x5 digit font: each digit is 5 rows of 3 bits (bit 2 = left column).
constexpr std::array<std::array<std::uint8_t, 5>, 10> kDigits = {{{7, 5, 5, 5, 7},
                                                                  {2, 6, 2, 2, 7},
                                                                  {7, 1, 7, 4, 7},
                                                                  {7, 1, 7, 1, 7},
                                                                  {5, 5, 7, 1, 1},
                                                                  {7, 4, 7, 1, 7},
                                                                  {7, 4, 7, 5, 7},
                                                                  {7, 1, 1, 1, 1},
                                                                  {7, 5, 7, 5, 7},
                                                                  {7, 5, 7, 1, 7}}};
constexpr int kFontScale = 2;

void draw_number(ImageView<Rgb8> image, int x, int y, int value, Rgb8 colour) {
  const std::string text = std::to_string(value);
  for (const char c : text) {
    const auto& glyph = kDigits[static_cast<std::size_t>(c - '0')];
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < 3; ++col) {
        if ((glyph[static_cast<std::size_t>(row)] >> (2 - col) & 1) == 0) continue;
        for (int dy = 0; dy < kFontScale; ++dy) {
          for (int dx = 0; dx < kFontScale; ++dx) {
            const int px = x + col * kFontScale + dx;
            const int py = y + row * kFontScale + dy;
            if (px >= 0 && py >= 0 && px < image.width() && py < image.height()) {
              image(px, py) = colour;
            }
          }
        }
      }
    }
    x += 4 * kFontScale;
  }
}

int text_width(int value) {
  return static_cast<int>(std::to_string(value).size()) * 4 * kFontScale;
}

// The disparity in colour (black: invalid) above a legend: a colour bar from 0 to
// max_disparity pixels with labelled ticks.
RgbImage colour_picture(ImageView<const std::int16_t> disparity, int max_disparity) {
  constexpr int kLegend = 40;
  const int width = disparity.width();
  const int height = disparity.height();
  RgbImage picture(width, height + kLegend);
  const ImageView<Rgb8> view = picture.view();
  for (int y = 0; y < height + kLegend; ++y) std::fill_n(view.row(y), width, Rgb8{});
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int d = disparity(x, y);
      if (d == vision::kInvalidDisparity) continue;
      view(x, y) = colour_of(d / (16.0 * max_disparity));
    }
  }
  const int margin = 8;
  const int bar_width = std::max(1, width - 2 * margin);
  const int bar_top = height + 6;
  for (int i = 0; i < bar_width; ++i) {
    const Rgb8 c = colour_of(static_cast<double>(i) / std::max(1, bar_width - 1));
    for (int y = bar_top; y < bar_top + 12; ++y) view(margin + i, y) = c;
  }
  const Rgb8 white{255, 255, 255};
  constexpr int kTicks = 4;
  for (int t = 0; t <= kTicks; ++t) {
    const int value = max_disparity * t / kTicks;
    const int x = margin + (bar_width - 1) * t / kTicks;
    draw_line(view, x, bar_top + 12, x, bar_top + 16, white);
    const int label_x =
        std::clamp(x - text_width(value) / 2, 0, std::max(0, width - text_width(value)));
    draw_number(view, label_x, bar_top + 18, value, white);
  }
  return picture;
}

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
    const RgbImage picture = colour_picture(disparity, config.max_disparity);
    save_image(options.color, picture.view());
  }
  const double density =
      static_cast<double>(valid) / (static_cast<double>(disparity.width()) * disparity.height());
  if (valid == 0) lowest = 0;
  if (options.json) {
    const nlohmann::json out = {{"width", disparity.width()},
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
  cmd->add_option("--threads", options->threads, "Row stripes on this many threads (1..64)")
      ->capture_default_str();
  cmd->add_option("--out,-o", options->out, "Disparity x16 as a 16-bit PNG (0 = invalid)")
      ->required();
  cmd->add_option("--color", options->color,
                  "Colour picture of the disparity with a legend (.png)");
  cmd->add_flag("--json", options->json, "Print a summary as JSON");
  cmd->callback([options, &global] { run_disparity(*options, global); });
}

}  // namespace epipole::tools

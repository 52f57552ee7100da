// epipole match LEFT RIGHT: sparse stereo matches of a rectified pair (or a raw pair rectified
// here with --calib), and with --calib their 3-D points, as JSON and/or a picture.
#include <chrono>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "commands.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/firmware/sparse_points.hpp"
#include "epipole/vision/fast.hpp"
#include "epipole/vision/harris.hpp"
#include "epipole/vision/sparse_stereo.hpp"
#include "pictures.hpp"
#include "stereo_input.hpp"

namespace epipole::tools {

namespace {

struct MatchOptions {
  std::string left;
  std::string right;
  std::string calib;
  std::string detector = "fast";
  int threshold = 20;  // FAST
  int max_corners = 4000;
  int max_disparity = 64;
  int row_tolerance = 1;
  int ratio = 80;
  int max_distance = 64;
  bool json = false;
  std::string draw;
};

// The corners of both images with the chosen detector (each image its own detector, as the
// frame loop has them).
struct Corners {
  std::vector<vision::Corner> left, right;
};

Corners detect(const MatchOptions& options, GrayView left, GrayView right, SimdPath path) {
  Corners c;
  const auto run = [&](auto& detector, GrayView image, std::vector<vision::Corner>& out) {
    const auto found = detector.detect(image);
    out.assign(found.begin(), found.end());
  };
  for (const bool is_left : {true, false}) {
    const GrayView image = is_left ? left : right;
    std::vector<vision::Corner>& out = is_left ? c.left : c.right;
    if (options.detector == "harris") {
      vision::HarrisConfig config{.width = image.width(), .height = image.height()};
      config.min_distance = 5;
      config.max_corners = options.max_corners;
      vision::HarrisDetector harris(config, path);
      run(harris, image, out);
    } else {
      vision::FastDetector fast({.width = image.width(),
                                 .height = image.height(),
                                 .threshold = options.threshold,
                                 .max_corners = options.max_corners},
                                path);
      run(fast, image, out);
    }
  }
  return c;
}

// Left | right side by side, each match a line between its two corners, colour by disparity.
RgbImage match_picture(GrayView left, GrayView right, std::span<const vision::SparseMatch> matches,
                       int max_disparity) {
  const int w = left.width();
  RgbImage picture = side_by_side(left, right);
  cv::Mat drawing = mat_of(picture.view());
  for (const vision::SparseMatch& m : matches) {
    const cv::Scalar colour = colour_of(static_cast<double>(m.disparity) / max_disparity);
    const cv::Point l(static_cast<int>(std::lround(m.xl)), static_cast<int>(std::lround(m.yl)));
    const cv::Point r(static_cast<int>(std::lround(m.xr)) + w, static_cast<int>(std::lround(m.yr)));
    cv::circle(drawing, l, 3, colour, 1, cv::LINE_AA);
    cv::circle(drawing, r, 3, colour, 1, cv::LINE_AA);
    cv::line(drawing, l, r, colour, 1, cv::LINE_AA);
  }
  return picture;
}

// What a match found, for its report.
struct MatchRun {
  int width = 0;
  int height = 0;
  std::string kernels;
  bool rectified = false;
  bool truncated = false;
  const Corners* corners = nullptr;
  std::span<const vision::SparseMatch> matches;
  const std::vector<firmware::SparsePoint>* points = nullptr;  // null without a calibration
  double milliseconds = 0;
};

nlohmann::json match_json(const MatchOptions& options, const MatchRun& run) {
  nlohmann::json m = nlohmann::json::array();
  for (const vision::SparseMatch& s : run.matches) {
    m.push_back({{"xl", s.xl},
                 {"yl", s.yl},
                 {"xr", s.xr},
                 {"yr", s.yr},
                 {"disparity", s.disparity},
                 {"distance", s.distance}});
  }
  nlohmann::json out = {{"width", run.width},
                        {"height", run.height},
                        {"detector", options.detector},
                        {"kernels", run.kernels},
                        {"rectified", run.rectified},
                        {"max_disparity", options.max_disparity},
                        {"row_tolerance", options.row_tolerance},
                        {"ratio", options.ratio},
                        {"left_corners", run.corners->left.size()},
                        {"right_corners", run.corners->right.size()},
                        {"truncated", run.truncated},
                        {"milliseconds", run.milliseconds},
                        {"matches", std::move(m)}};
  if (run.points != nullptr) {
    nlohmann::json p = nlohmann::json::array();
    for (const firmware::SparsePoint& s : *run.points) {
      p.push_back({{"xl", s.xl},
                   {"yl", s.yl},
                   {"disparity", s.disparity},
                   {"x", s.x},
                   {"y", s.y},
                   {"z", s.z}});
    }
    out["points"] = std::move(p);
  } else {
    out["points"] = nullptr;
    out["points_note"] = "no 3-D points without --calib (the pair is taken as rectified)";
  }
  return out;
}

void print_match(const MatchOptions& options, const MatchRun& run) {
  std::cout << run.matches.size() << " matches of " << run.corners->left.size() << " / "
            << run.corners->right.size() << " corners (" << options.detector << ", "
            << options.max_disparity << " disparities, " << run.kernels << ") in "
            << run.milliseconds << " ms";
  if (run.points != nullptr) {
    std::cout << ", " << run.points->size() << " 3-D points";
  } else {
    std::cout << " (no 3-D points without --calib)";
  }
  std::cout << (run.truncated ? ", truncated" : "") << "\n";
}

void run_match(const MatchOptions& options, const GlobalOptions& global) {
  const SimdPath path = parse_simd_path(global.kernels);
  const StereoInput input = load_stereo_input(options.left, options.right, options.calib, path);
  const int width = input.left.width();
  const int height = input.left.height();
  vision::SparseStereoMatcher matcher({.width = width,
                                       .height = height,
                                       .max_disparity = options.max_disparity,
                                       .row_tolerance = options.row_tolerance,
                                       .ratio = options.ratio,
                                       .max_distance = options.max_distance,
                                       .max_corners = options.max_corners,
                                       .max_matches = options.max_corners},
                                      path);
  const Corners corners = detect(options, input.left, input.right, path);
  const auto start = std::chrono::steady_clock::now();
  const std::span<const vision::SparseMatch> matches =
      matcher.match(input.left, corners.left, input.right, corners.right);
  const std::chrono::duration<double, std::milli> elapsed =
      std::chrono::steady_clock::now() - start;

  std::vector<firmware::SparsePoint> points;
  if (input.calibration) {
    const calib::Triangulator triangulator(*input.calibration);
    points.resize(matches.size());
    points.resize(firmware::triangulate_matches(triangulator, matches, points));
  }
  const MatchRun run{width,
                     height,
                     std::string(to_string(matcher.simd_path())),
                     input.rectifiers.has_value(),
                     matcher.truncated(),
                     &corners,
                     matches,
                     input.calibration ? &points : nullptr,
                     elapsed.count()};
  if (options.json) {
    std::cout << match_json(options, run).dump() << "\n";
  } else {
    print_match(options, run);
  }
  if (!options.draw.empty()) {
    const RgbImage picture = match_picture(input.left, input.right, matches, options.max_disparity);
    save_image(options.draw, ImageView<const Rgb8>(picture.view()));
  }
}

}  // namespace

void add_match_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<MatchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "match", "Sparse stereo: corners matched along the rows, 3-D points with --calib");
  cmd->add_option("left", options->left, "Left image (PNG, JPEG, PGM)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("right", options->right, "Right image")->required()->check(CLI::ExistingFile);
  cmd->add_option("--calib", options->calib,
                  "Calibration file (YAML): rectify the raw pair first and triangulate the "
                  "matches into 3-D points (without it the pair is taken as rectified and no "
                  "points are computed)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--detector", options->detector, "Corner detector: fast or harris")
      ->check(CLI::IsMember({"fast", "harris"}))
      ->capture_default_str();
  cmd->add_option("--threshold,-t", options->threshold, "FAST intensity threshold (0..255)")
      ->check(CLI::Range(0, 255))
      ->capture_default_str();
  cmd->add_option("--max-corners,-c", options->max_corners,
                  "Corners per image, and matches, at most")
      ->check(CLI::Range(1, 1'000'000))
      ->capture_default_str();
  cmd->add_option("--max-disparity,-d", options->max_disparity,
                  "Disparities 0..N-1 are searched (smaller than the width)")
      ->capture_default_str();
  cmd->add_option("--row-tolerance", options->row_tolerance,
                  "Candidates on rows y-T..y+T of the other image (0..16)")
      ->capture_default_str();
  cmd->add_option("--ratio", options->ratio,
                  "Ratio test, percent: best distance below this share of the second best")
      ->capture_default_str();
  cmd->add_option("--max-distance", options->max_distance,
                  "Largest Hamming distance of the 256-bit descriptors")
      ->capture_default_str();
  cmd->add_flag("--json", options->json,
                R"(Print {"matches":[{"xl","yl","xr","yr","disparity","distance"}],)"
                R"("points":[{"xl","yl","disparity","x","y","z"}] (null without --calib),...})");
  cmd->add_option("--draw", options->draw,
                  "Write the pair side by side with a line for each match (.png)");
  cmd->callback([options, &global] { run_match(*options, global); });
}

}  // namespace epipole::tools

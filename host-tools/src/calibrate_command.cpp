// epipole calibrate: stereo calibration from chessboard pairs (OpenCV), or the import of an
// OpenCV or ROS calibration, into an Epipole calibration file (docs/calibration.md).
#include <glob.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "epipole/calib/calibration.hpp"
#include "epipole/calib/health.hpp"
#include "epipole/calib/rectification_map.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/firmware/stereo_rectification.hpp"
#include "epipole/tools/opencv_calibration.hpp"
#include "epipole/tools/opencv_mat.hpp"
#include "epipole/tools/progress.hpp"
#include "stereo_preview.hpp"

namespace epipole::tools {

namespace {

struct CalibrateOptions {
  std::string left_glob;
  std::string right_glob;
  std::string board = "chessboard:9x6";
  double square = 0.025;
  std::string output;
  std::string report;
  std::string preview;
  double alpha = 0.0;
  std::string left_id = "left";
  std::string right_id = "right";
  bool drop_outliers = false;
  std::vector<std::string> from_opencv;
  std::vector<std::string> from_ros;
  std::string export_opencv;  // folders for the calibration in OpenCV's and ROS's files
  std::string export_ros;
  bool json = false;  // the summary as JSON on stdout instead of its line
  std::string size;
};

// An outlier view: its worse camera's RMS error is above kOutlierFactor times the median of
// that figure over all views.
constexpr double kOutlierFactor = 3.0;
constexpr int kMinViews = 3;

struct Board {
  int columns = 0;  // inner corners
  int rows = 0;
};

// "WxH" as two positive integers; `what` names the option for the error.
std::pair<int, int> parse_size(const std::string& text, const std::string& what) {
  const std::size_t x = text.find('x');
  int a = 0;
  int b = 0;
  const auto ok = [](const char* first, const char* last, int& out) {
    const auto [end, error] = std::from_chars(first, last, out);
    return error == std::errc() && end == last && first != last && out > 0;
  };
  require(x != std::string::npos && ok(text.data(), text.data() + x, a) &&
              ok(text.data() + x + 1, text.data() + text.size(), b),
          what, ": '", text, "' is not WIDTHxHEIGHT (two positive integers)");
  return {a, b};
}

Board parse_board(const std::string& text) {
  const std::string prefix = "chessboard:";
  require(text.starts_with(prefix), "--board: '", text,
          "' is not supported (chessboard:COLSxROWS, inner corners, e.g. chessboard:9x6)");
  const auto [columns, rows] = parse_size(text.substr(prefix.size()), "--board");
  require(columns >= 2 && rows >= 2 && columns <= 100 && rows <= 100, "--board: ", columns, "x",
          rows, " inner corners is outside 2..100");
  require(columns != rows, "--board: a square board (", columns, "x", rows,
          ") is ambiguous under rotation; use one with different counts");
  return {columns, rows};
}

std::vector<std::string> expand(const std::string& pattern, const char* option) {
  glob_t matches{};
  const int status = ::glob(pattern.c_str(), 0, nullptr, &matches);
  std::vector<std::string> files;
  if (status == 0) {
    for (std::size_t i = 0; i < matches.gl_pathc; ++i) files.emplace_back(matches.gl_pathv[i]);
  }
  globfree(&matches);
  require(status == 0 || status == GLOB_NOMATCH, option, " '", pattern, "': cannot list files");
  require(!files.empty(), option, " '", pattern, "' matches no file");
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<cv::Point2f> find_board(const GrayImage& image, Board board, bool* found) {
  const cv::Mat mat = mat_of(image.view());
  std::vector<cv::Point2f> corners;
  *found = cv::findChessboardCorners(mat, {board.columns, board.rows}, corners,
                                     cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  if (*found) {
    cv::cornerSubPix(mat, corners, {11, 11}, {-1, -1},
                     {cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01});
  }
  return corners;
}

struct View {
  std::string left;
  std::string right;
  std::vector<cv::Point2f> left_corners;
  std::vector<cv::Point2f> right_corners;
  double left_rms = 0;
  double right_rms = 0;
  bool outlier = false;
  bool used = true;
};

struct StereoResult {
  double rms = 0;
  cv::Mat K1, D1, K2, D2, R, T;
};

// Each camera alone first (a good start for every intrinsic), then both together with every
// parameter free: K, k1 k2 p1 p2 k3 of both cameras, R and T.
StereoResult stereo_calibrate(std::vector<View>& views, Board board, double square, cv::Size size) {
  std::vector<cv::Point3f> object;
  for (int r = 0; r < board.rows; ++r) {
    for (int c = 0; c < board.columns; ++c) {
      object.emplace_back(static_cast<float>(c * square), static_cast<float>(r * square), 0.0f);
    }
  }
  std::vector<std::vector<cv::Point3f>> objects;
  std::vector<std::vector<cv::Point2f>> left;
  std::vector<std::vector<cv::Point2f>> right;
  std::vector<View*> used;
  for (View& v : views) {
    if (!v.used) continue;
    objects.push_back(object);
    left.push_back(v.left_corners);
    right.push_back(v.right_corners);
    used.push_back(&v);
  }
  StereoResult r;
  std::vector<cv::Mat> rvecs;
  std::vector<cv::Mat> tvecs;
  cv::calibrateCamera(objects, left, size, r.K1, r.D1, rvecs, tvecs);
  cv::calibrateCamera(objects, right, size, r.K2, r.D2, rvecs, tvecs);
  cv::Mat E, F, errors;
  r.rms = cv::stereoCalibrate(objects, left, right, r.K1, r.D1, r.K2, r.D2, size, r.R, r.T, E, F,
                              errors, cv::CALIB_USE_INTRINSIC_GUESS,
                              {cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10});
  for (std::size_t i = 0; i < used.size(); ++i) {
    used[i]->left_rms = errors.at<double>(static_cast<int>(i), 0);
    used[i]->right_rms = errors.at<double>(static_cast<int>(i), 1);
  }
  return r;
}

Eigen::Matrix3d eigen3(const cv::Mat& m) {
  Eigen::Matrix3d e;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) e(r, c) = m.at<double>(r, c);
  }
  return e;
}

nlohmann::json matrix_json(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json camera_json(const calib::CameraCalibration& c) {
  const calib::Distortion& d = c.camera.distortion;
  return {{"id", c.id},
          {"K", matrix_json(c.camera_matrix())},
          {"distortion", {d.k1, d.k2, d.p1, d.p2, d.k3}}};
}

struct RowError {
  double mean = 0;
  double max = 0;
  calib::HealthFigure figure;
};

// |y_left - y_right| of every board corner after rectification (calib::rectify_point).
RowError rectified_row_error(const calib::StereoCalibration& c, const std::vector<View>& views) {
  std::vector<calib::RectifiedMatch> matches;
  for (const View& v : views) {
    if (!v.used) continue;
    for (std::size_t i = 0; i < v.left_corners.size(); ++i) {
      const Eigen::Vector2d l =
          calib::rectify_point(c.left, {v.left_corners[i].x, v.left_corners[i].y});
      const Eigen::Vector2d r =
          calib::rectify_point(c.right, {v.right_corners[i].x, v.right_corners[i].y});
      matches.push_back({static_cast<float>(l.x()), static_cast<float>(l.y()),
                         static_cast<float>(r.x()), static_cast<float>(r.y())});
    }
  }
  RowError e;
  calib::CalibrationHealth health(static_cast<int>(std::max<std::size_t>(matches.size(), 1)));
  e.figure = health.measure(matches);
  double sum = 0;
  int n = 0;
  for (const calib::RectifiedMatch& m : matches) {
    const double d = std::abs(static_cast<double>(m.right_y) - static_cast<double>(m.left_y));
    if (!std::isfinite(d)) continue;
    sum += d;
    e.max = std::max(e.max, d);
    ++n;
  }
  e.mean = n > 0 ? sum / n : std::nan("");
  return e;
}

void write_preview(const calib::StereoCalibration& c, const GrayImage& left, const GrayImage& right,
                   const std::string& file, SimdPath path) {
  firmware::StereoRectifiers rectifiers = firmware::make_stereo_rectifiers(c, path);
  const GrayView l = rectifiers.left.rectify(left.view());
  const GrayView r = rectifiers.right.rectify(right.view());
  const RgbImage picture = side_by_side_preview(l, r);
  save_image(file, ImageView<const Rgb8>(picture.view()));
}

// The calibration also as OpenCV's and ROS's files, where asked: a line each, or (--json) the
// files in the summary.
void export_calibration(const CalibrateOptions& options, const calib::StereoCalibration& c,
                        nlohmann::json& summary) {
  summary["exported"] = nlohmann::json::array();
  const auto wrote = [&](const std::filesystem::path& folder, const char* first, const char* second,
                         const char* format) {
    summary["exported"].push_back(
        {{"format", format}, {"files", {(folder / first).string(), (folder / second).string()}}});
    if (!options.json) {
      std::cout << "wrote " << (folder / first).string() << " and " << second << " (" << format
                << ")\n";
    }
  };
  if (!options.export_opencv.empty()) {
    export_opencv_calibration(c, options.export_opencv);
    wrote(options.export_opencv, "intrinsics.yml", "extrinsics.yml", "opencv");
  }
  if (!options.export_ros.empty()) {
    calib::export_ros_calibration(c, options.export_ros);
    wrote(options.export_ros, "left.yaml", "right.yaml", "ros");
  }
}

void run_import(const CalibrateOptions& options) {
  calib::StereoCalibration c;
  if (!options.from_opencv.empty()) {
    int width = 0;
    int height = 0;
    if (!options.size.empty()) std::tie(width, height) = parse_size(options.size, "--size");
    try {
      c = import_opencv_calibration(options.from_opencv[0], options.from_opencv[1], width, height);
    } catch (const Error& e) {
      const std::string message = e.what();
      if (message.starts_with("the image size is unknown")) {
        throw Error(message + " (--size WIDTHxHEIGHT)");
      }
      throw;
    }
  } else {
    c = calib::import_ros_calibration(options.from_ros[0], options.from_ros[1]);
  }
  calib::save_calibration(options.output, c);
  if (!options.json) {
    std::cout << "imported a " << c.width << "x" << c.height << " stereo calibration (baseline "
              << c.T.norm() << "): wrote " << options.output << "\n";
  }
  nlohmann::json summary = {{"imported", c.source},
                            {"image_size", {{"width", c.width}, {"height", c.height}}},
                            {"baseline", c.T.norm()},
                            {"output", options.output}};
  export_calibration(options, c, summary);
  if (options.json) std::cout << summary.dump(2) << "\n";
}

// The pairs whose board was found in both images, and those rejected (with the reason).
struct Views {
  std::vector<View> found;
  nlohmann::json rejected = nlohmann::json::array();
  int width = 0;
  int height = 0;
};

Views find_views(const std::vector<std::string>& lefts, const std::vector<std::string>& rights,
                 Board board) {
  Views out;
  std::string first;
  Progress progress;
  for (std::size_t i = 0; i < lefts.size(); ++i) {
    progress.show(cat("calibrate: pair ", i + 1, " of ", lefts.size(), ": ", lefts[i]));
    const GrayImage left = load_gray(lefts[i]);
    const GrayImage right = load_gray(rights[i]);
    const std::pair<const GrayImage*, const std::string*> images[] = {{&left, &lefts[i]},
                                                                      {&right, &rights[i]}};
    for (const auto& [image, name] : images) {
      if (first.empty()) {
        out.width = image->width();
        out.height = image->height();
        first = *name;
      }
      require(image->width() == out.width && image->height() == out.height, *name, ": image is ",
              image->width(), "x", image->height(), " but ", first, " is ", out.width, "x",
              out.height, ": every image of a calibration must have the same size");
    }
    require(out.width >= 2 * board.columns && out.height >= 2 * board.rows, first, ": a ",
            out.width, "x", out.height, " image is too small for a board of ", board.columns, "x",
            board.rows, " inner corners");
    View v{lefts[i], rights[i], {}, {}, 0, 0, false, true};
    bool found_left = false;
    bool found_right = false;
    v.left_corners = find_board(left, board, &found_left);
    v.right_corners = find_board(right, board, &found_right);
    if (found_left && found_right) {
      out.found.push_back(std::move(v));
    } else {
      const char* where = !found_left && !found_right ? "both images"
                          : !found_left               ? "the left image"
                                                      : "the right image";
      out.rejected.push_back({{"left", lefts[i]},
                              {"right", rights[i]},
                              {"reason", std::string("board not found in ") + where}});
    }
  }
  progress.done();
  return out;
}

// Flags the views whose worse camera is far above the typical view; how many.
int flag_outliers(std::vector<View>& views) {
  std::vector<double> worst;
  for (const View& v : views) worst.push_back(std::max(v.left_rms, v.right_rms));
  std::vector<double> sorted = worst;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2),
                   sorted.end());
  const double median = sorted[sorted.size() / 2];
  int outliers = 0;
  for (std::size_t i = 0; i < views.size(); ++i) {
    views[i].outlier = worst[i] > kOutlierFactor * median;
    outliers += views[i].outlier ? 1 : 0;
  }
  return outliers;
}

calib::CameraCalibration camera_of(const cv::Mat& k, const cv::Mat& d, const cv::Mat& r,
                                   const cv::Mat& p, const std::string& id) {
  calib::CameraCalibration cam;
  cam.id = id;
  cam.camera.intrinsics = {k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2),
                           k.at<double>(1, 2)};
  const auto coefficient = [&](int i) { return d.at<double>(i); };
  cam.camera.distortion = {coefficient(0), coefficient(1), coefficient(2), coefficient(3),
                           coefficient(4)};
  cam.rectification = eigen3(r);
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 4; ++col) cam.projection(row, col) = p.at<double>(row, col);
  }
  return cam;
}

// The rig's calibration with OpenCV's rectification of it (alpha as asked), and the views used.
calib::StereoCalibration rectified(const StereoResult& result, cv::Size size,
                                   const CalibrateOptions& options,
                                   const std::vector<View>& views) {
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(result.K1, result.D1, result.K2, result.D2, size, result.R, result.T, R1, R2,
                    P1, P2, Q, cv::CALIB_ZERO_DISPARITY, options.alpha);
  calib::StereoCalibration c;
  c.width = size.width;
  c.height = size.height;
  c.left = camera_of(result.K1, result.D1, R1, P1, options.left_id);
  c.right = camera_of(result.K2, result.D2, R2, P2, options.right_id);
  c.R = eigen3(result.R);
  c.T = {result.T.at<double>(0), result.T.at<double>(1), result.T.at<double>(2)};
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 4; ++col) c.Q(row, col) = Q.at<double>(row, col);
  }
  c.rms = result.rms;
  for (const View& v : views) {
    if (v.used) c.views.push_back({v.left, v.right, v.left_rms, v.right_rms});
  }
  c.date = calib::utc_now();
  c.source = "epipole calibrate";
  return c;
}

// What --report writes and --json prints (the exports added later).
nlohmann::json calibration_report(const calib::StereoCalibration& c, const Views& views,
                                  std::size_t pairs, double rms_with_all, Board board,
                                  const CalibrateOptions& options) {
  const RowError row_error = rectified_row_error(c, views.found);
  nlohmann::json view_list = nlohmann::json::array();
  nlohmann::json outlier_list = nlohmann::json::array();
  for (const View& v : views.found) {
    view_list.push_back({{"left", v.left},
                         {"right", v.right},
                         {"left_rms", v.left_rms},
                         {"right_rms", v.right_rms},
                         {"outlier", v.outlier},
                         {"used", v.used}});
    if (v.outlier) outlier_list.push_back({{"left", v.left}, {"right", v.right}});
  }
  nlohmann::json report = {
      {"rms", c.rms.value_or(0.0)},
      {"rms_before_dropping_outliers", rms_with_all},
      {"image_size", {{"width", c.width}, {"height", c.height}}},
      {"board",
       {{"type", "chessboard"},
        {"columns", board.columns},
        {"rows", board.rows},
        {"square", options.square}}},
      {"pairs", pairs},
      {"views_used", c.views.size()},
      {"views", view_list},
      {"rejected", views.rejected},
      {"outliers", outlier_list},
      {"outlier_rule",
       "worse camera's view RMS > 3 x the median of that figure over the accepted views"},
      {"rectified_row_error",
       {{"mean", row_error.mean},
        {"median", row_error.figure.median_px},
        {"p90", row_error.figure.p90_px},
        {"max", row_error.max},
        {"points", row_error.figure.matches}}},
      {"alpha", options.alpha},
      {"baseline", c.T.norm()},
      {"left", camera_json(c.left)},
      {"right", camera_json(c.right)},
      {"output", options.output}};
  return report;
}

void run_calibrate(const CalibrateOptions& options, const GlobalOptions& global) {
  if (!options.from_opencv.empty() || !options.from_ros.empty()) {
    run_import(options);
    return;
  }
  require(!options.left_glob.empty() && !options.right_glob.empty(),
          "calibrate: give --left and --right image patterns (or --from-opencv / --from-ros)");
  require(!options.output.empty(), "calibrate: give the output file (-o rig.yaml)");
  require(options.square > 0 && std::isfinite(options.square), "--square: ", options.square,
          " must be > 0");
  const Board board = parse_board(options.board);
  const std::vector<std::string> lefts = expand(options.left_glob, "--left");
  const std::vector<std::string> rights = expand(options.right_glob, "--right");
  require(lefts.size() == rights.size(), "--left matches ", lefts.size(), " files but --right ",
          rights.size(), ": the images must come in pairs (sorted by name)");
  Views views = find_views(lefts, rights, board);
  require(static_cast<int>(views.found.size()) >= kMinViews,
          "calibrate: the board was found in both images of only ", views.found.size(), " of ",
          lefts.size(), " pairs (need at least ", kMinViews, ")");

  Progress progress;
  progress.show(cat("calibrate: calibrating with ", views.found.size(), " views"));
  const cv::Size size(views.width, views.height);
  StereoResult result = stereo_calibrate(views.found, board, options.square, size);
  const int outliers = flag_outliers(views.found);
  const double rms_with_all = result.rms;
  if (options.drop_outliers && outliers > 0 &&
      static_cast<int>(views.found.size()) - outliers >= kMinViews) {
    for (View& v : views.found) v.used = !v.outlier;
    result = stereo_calibrate(views.found, board, options.square, size);
  }
  progress.done();
  const calib::StereoCalibration c = rectified(result, size, options, views.found);
  calib::save_calibration(options.output, c);

  nlohmann::json report = calibration_report(c, views, lefts.size(), rms_with_all, board, options);
  if (!options.report.empty()) {
    std::ofstream out(options.report);
    out << report.dump(2) << "\n";
    out.close();
    require(static_cast<bool>(out), options.report, ": cannot write the report");
  }
  if (!options.preview.empty()) {
    const auto used =
        std::find_if(views.found.begin(), views.found.end(), [](const View& w) { return w.used; });
    write_preview(c, load_gray(used->left), load_gray(used->right), options.preview,
                  parse_simd_path(global.kernels));
  }
  if (!options.json) {
    std::cout << "calibrated " << c.views.size() << " of " << lefts.size() << " pairs ("
              << views.rejected.size() << " rejected, " << outliers << " outlier"
              << (outliers == 1 ? "" : "s") << (options.drop_outliers ? " dropped" : " flagged")
              << "): RMS " << result.rms << " px, rectified row error mean "
              << report["rectified_row_error"]["mean"].get<double>() << " px; wrote "
              << options.output << "\n";
  }
  export_calibration(options, c, report);
  if (options.json) std::cout << report.dump(2) << "\n";
}

}  // namespace

void add_calibrate_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate", "Calibrate a stereo rig from chessboard image pairs (or import a calibration)");
  auto* left = cmd->add_option("--left", options->left_glob,
                               "Left images, a quoted glob pattern ('calib/left*.png')");
  auto* right = cmd->add_option("--right", options->right_glob,
                                "Right images, a quoted glob pattern; paired by sorted name");
  cmd->add_option("--board", options->board,
                  "Calibration target: chessboard:COLSxROWS (inner corners)")
      ->capture_default_str();
  cmd->add_option("--square", options->square,
                  "Side of a chessboard square, in metres (the unit of T and of 3-D points)")
      ->capture_default_str();
  cmd->add_option("-o,--output", options->output, "Calibration file to write (.yaml)")->required();
  cmd->add_option("--report", options->report,
                  "Write a JSON report: RMS, per-view errors, rejected and outlier views, "
                  "rectified row error");
  cmd->add_option("--preview", options->preview,
                  "Write the first pair rectified side by side with horizontal lines (.png)");
  cmd->add_option("--alpha", options->alpha,
                  "Rectification scaling: 0 keeps only valid pixels, 1 keeps every source pixel")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--left-id", options->left_id, "Identifier of the left camera")
      ->capture_default_str();
  cmd->add_option("--right-id", options->right_id, "Identifier of the right camera")
      ->capture_default_str();
  cmd->add_flag("--drop-outliers", options->drop_outliers,
                "Calibrate again without the views flagged as outliers");
  auto* opencv = cmd->add_option("--from-opencv", options->from_opencv,
                                 "Import OpenCV's stereo calibration output instead: "
                                 "INTRINSICS EXTRINSICS (FileStorage YAML or XML)")
                     ->expected(2);
  auto* ros = cmd->add_option("--from-ros", options->from_ros,
                              "Import a ROS camera_info YAML pair instead: LEFT RIGHT")
                  ->expected(2);
  cmd->add_option("--export-opencv", options->export_opencv,
                  "Also write the calibration as OpenCV's stereo_calib sample does: "
                  "DIR/intrinsics.yml and DIR/extrinsics.yml (cv::FileStorage)");
  cmd->add_option("--export-ros", options->export_ros,
                  "Also write it as ROS camera_info files: DIR/left.yaml and DIR/right.yaml");
  cmd->add_flag("--json", options->json,
                "Print the summary as JSON (the --report object; for an import its size, "
                "baseline and output) instead of its line");
  cmd->add_option("--size", options->size,
                  "With --from-opencv: image size WIDTHxHEIGHT when the files do not record it");
  opencv->excludes(left)->excludes(right)->excludes(ros);
  ros->excludes(left)->excludes(right);
  cmd->callback([options, &global] { run_calibrate(*options, global); });
}

}  // namespace epipole::tools

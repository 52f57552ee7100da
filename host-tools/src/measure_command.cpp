// epipole measure IMAGE --points u,v,... --world x,y,...: measurements on a plane seen in one
// image ("unwarp, then measure"): the homography between the image and the plane from four or
// more points whose plane coordinates are known (calib::find_homography), then distances and
// areas of other image points on that plane, and the plane's unwarped view.
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "commands.hpp"
#include "epipole/calib/homography.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "pictures.hpp"

namespace epipole::tools {

namespace {

struct MeasureOptions {
  std::string image;
  std::string points;   // u,v,u,v,... pixels
  std::string world;    // x,y,x,y,... on the plane
  std::string measure;  // u,v,... to measure (default: the points themselves)
  std::string unwarp;   // the plane's view, .png
  double scale = 0;     // its pixels per unit of the plane (0: at most 1000 pixels across)
  double inlier_px = calib::HomographyOptions{}.inlier_px;
  bool json = false;
};

// "1.5,2,3,4" as points; errors name the option.
std::vector<Eigen::Vector2d> parse_points(const std::string& text, const char* option) {
  std::vector<double> numbers;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used > 0 && used == item.size() && std::isfinite(value), option, ": '", item,
            "' is not a number (give x,y,x,y,...)");
    numbers.push_back(value);
  }
  require(!numbers.empty() && numbers.size() % 2 == 0, option, ": ", numbers.size(),
          " numbers; give pairs x,y,x,y,...");
  std::vector<Eigen::Vector2d> points;
  for (std::size_t i = 0; i < numbers.size(); i += 2)
    points.emplace_back(numbers[i], numbers[i + 1]);
  return points;
}

// The polygon's area by the shoelace formula (its points in order, either way round).
double polygon_area(const std::vector<Eigen::Vector2d>& p) {
  double twice = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& a = p[i];
    const Eigen::Vector2d& b = p[(i + 1) % p.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return std::abs(twice) / 2;
}

// The plane's view over the reference points' extent (and a tenth more each way): plane x to
// the right, plane y down, `scale` pixels a unit.
void write_unwarped(const GrayImage& image, const Eigen::Matrix3d& plane_to_image,
                    const std::vector<Eigen::Vector2d>& world, double scale,
                    const std::string& file) {
  Eigen::Vector2d low = world.front(), high = world.front();
  for (const auto& w : world) {
    low = low.cwiseMin(w);
    high = high.cwiseMax(w);
  }
  const Eigen::Vector2d margin = (high - low) * 0.1;
  low -= margin;
  high += margin;
  const Eigen::Vector2d extent = high - low;
  require(extent.minCoeff() > 0, "--unwarp: the points span no area of the plane");
  if (scale <= 0) scale = 1000 / extent.maxCoeff();
  const double across = std::ceil(extent.x() * scale), down = std::ceil(extent.y() * scale);
  require(across >= 1 && down >= 1 && across <= 20000 && down <= 20000, "--unwarp: ", across, "x",
          down, " pixels at ", scale, " a unit; give another --scale");
  const int width = static_cast<int>(across);
  const int height = static_cast<int>(down);
  // Output pixel -> plane -> image, for cv::warpPerspective's inverse map.
  Eigen::Matrix3d to_plane;
  to_plane << 1 / scale, 0, low.x(), 0, 1 / scale, low.y(), 0, 0, 1;
  const Eigen::Matrix3d map = plane_to_image * to_plane;
  cv::Mat m(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.at<double>(r, c) = map(r, c);
  }
  const cv::Mat source(image.height(), image.width(), CV_8UC1,
                       const_cast<std::uint8_t*>(image.view().row(0)),
                       static_cast<std::size_t>(image.stride()));
  GrayImage out(width, height);
  cv::Mat target(height, width, CV_8UC1, out.view().row(0), static_cast<std::size_t>(out.stride()));
  cv::warpPerspective(source, target, m, target.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  save_image(file, out.view());
}

void run_measure(const MeasureOptions& o) {
  const GrayImage image = load_gray(o.image);
  const std::vector<Eigen::Vector2d> pixels = parse_points(o.points, "--points");
  const std::vector<Eigen::Vector2d> world = parse_points(o.world, "--world");
  require(pixels.size() == world.size(), "--points has ", pixels.size(), " points but --world ",
          world.size());
  require(pixels.size() >= 4,
          "four points at least, with their plane coordinates, make the plane (", pixels.size(),
          " given)");
  for (const auto& p : pixels) {
    require(p.x() >= 0 && p.y() >= 0 && p.x() <= image.width() && p.y() <= image.height(),
            "--points: (", p.x(), ", ", p.y(), ") is outside the ", image.width(), "x",
            image.height(), " image");
  }
  // The plane to the image, so that RANSAC's inlier distance is in pixels.
  calib::HomographyOptions options;
  options.inlier_px = o.inlier_px;
  const calib::HomographyFit fit = calib::find_homography(world, pixels, options);
  const Eigen::Matrix3d image_to_plane = fit.H.inverse();
  const std::vector<Eigen::Vector2d> measured =
      o.measure.empty() ? pixels : parse_points(o.measure, "--measure");
  // The plane's horizon: image points on or beyond it (where the plane's w changes sign from the
  // reference points') are no points of the plane.
  const double side = (image_to_plane * pixels.front().homogeneous()).z();
  std::vector<Eigen::Vector2d> on_plane;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const double w = (image_to_plane * measured[i].homogeneous()).z();
    require(w * side > 0 && std::abs(w) > 1e-12 * std::abs(side), "--measure: point ", i + 1, " (",
            measured[i].x(), ", ", measured[i].y(),
            ") is on or beyond the plane's horizon: no point of the plane");
    on_plane.push_back(calib::apply_homography(image_to_plane, measured[i]));
  }
  std::vector<double> distances;
  for (std::size_t i = 0; i + 1 < on_plane.size(); ++i) {
    distances.push_back((on_plane[i + 1] - on_plane[i]).norm());
  }
  const double area = on_plane.size() >= 3 ? polygon_area(on_plane) : 0;
  if (!o.unwarp.empty()) write_unwarped(image, fit.H, world, o.scale, o.unwarp);

  nlohmann::json residuals = nlohmann::json::array();
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    residuals.push_back((calib::apply_homography(fit.H, world[i]) - pixels[i]).norm());
  }
  if (o.json) {
    nlohmann::json points = nlohmann::json::array();
    for (const auto& p : on_plane) points.push_back({p.x(), p.y()});
    nlohmann::json h = nlohmann::json::array();
    for (int r = 0; r < 3; ++r)
      h.push_back({image_to_plane(r, 0) / image_to_plane(2, 2),
                   image_to_plane(r, 1) / image_to_plane(2, 2),
                   image_to_plane(r, 2) / image_to_plane(2, 2)});
    std::vector<bool> inliers = fit.inliers;
    std::cout << nlohmann::json{{"image_to_plane", h},
                                {"inliers", inliers},
                                {"residuals_px", residuals},
                                {"rms_px", fit.rms_px},
                                {"points", points},
                                {"distances", distances},
                                {"area", area},
                                {"unwarped",
                                 o.unwarp.empty() ? nlohmann::json() : nlohmann::json(o.unwarp)}}
                     .dump(2)
              << "\n";
    return;
  }
  std::cout << std::fixed << std::setprecision(4);
  std::cout << "plane from " << fit.inlier_count << " of " << pixels.size()
            << " points, reprojection error " << fit.rms_px << " px rms\n";
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (!fit.inliers[i]) {
      std::cout << "  point " << i + 1 << " left out: " << residuals[i].get<double>()
                << " px from the plane's others\n";
    }
  }
  for (std::size_t i = 0; i < on_plane.size(); ++i) {
    std::cout << "  " << i + 1 << ": (" << measured[i].x() << ", " << measured[i].y() << ") px -> ("
              << on_plane[i].x() << ", " << on_plane[i].y() << ")\n";
  }
  for (std::size_t i = 0; i < distances.size(); ++i) {
    std::cout << "  " << i + 1 << " to " << i + 2 << ": " << distances[i] << "\n";
  }
  if (on_plane.size() >= 3)
    std::cout << "  area of the polygon 1.." << on_plane.size() << ": " << area << "\n";
  if (!o.unwarp.empty()) std::cout << "the plane's view: " << o.unwarp << "\n";
}

}  // namespace

void add_measure_command(CLI::App& app, const GlobalOptions& /*global*/) {
  auto options = std::make_shared<MeasureOptions>();
  CLI::App* cmd = app.add_subcommand(
      "measure",
      "Distances and areas on a plane seen in one image, from four or more points whose plane "
      "coordinates are known (a homography: normalised DLT, RANSAC, Levenberg-Marquardt)");
  cmd->add_option("image", options->image, "The image (PNG, JPEG, PGM)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--points", options->points, "Reference points in the image: u,v,u,v,... pixels")
      ->required();
  cmd->add_option("--world", options->world,
                  "Their coordinates on the plane, in the same order: x,y,x,y,... (any unit: "
                  "the distances and areas are in it)")
      ->required();
  cmd->add_option("--measure", options->measure,
                  "Image points to measure: u,v,...; the distances between consecutive ones and "
                  "their polygon's area (default: the reference points)");
  cmd->add_option("--unwarp", options->unwarp,
                  "Write the plane's view (.png): plane x to the right, y down, over the "
                  "reference points and a tenth more");
  cmd->add_option("--scale", options->scale, "The view's pixels per unit (default: 1000 across)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--inlier-px", options->inlier_px,
                  "RANSAC: a reference point farther than this from the others' plane is left out")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", options->json, "Print the result as JSON");
  cmd->callback([options] { run_measure(*options); });
}

}  // namespace epipole::tools

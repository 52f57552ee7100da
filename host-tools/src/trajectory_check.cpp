#include "trajectory_check.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "epipole/core/angles.hpp"
#include "epipole/core/error.hpp"
#include "epipole/core/image_io.hpp"
#include "epipole/core/text_file.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "pictures.hpp"
#include "sim/world_scene.hpp"

namespace epipole::tools {

namespace {

calib::RigidMotion pose_of(const nlohmann::json& m) {
  const Eigen::Quaterniond q(m["qw_e9"].get<double>() * 1e-9, m["qx_e9"].get<double>() * 1e-9,
                             m["qy_e9"].get<double>() * 1e-9, m["qz_e9"].get<double>() * 1e-9);
  return {
      q.normalized().toRotationMatrix(),
      Eigen::Vector3d(m["x_mm"].get<double>(), m["y_mm"].get<double>(), m["z_mm"].get<double>()) /
          1000.0};
}

// Seen from above: the odometry frame's x to the right, z up the picture (its y points down).
void draw_trajectories(std::span<const calib::RigidMotion> truth,
                       const std::vector<Eigen::Vector3d>& estimate,
                       const std::filesystem::path& file) {
  constexpr int kSize = 640;
  constexpr int kMargin = 48;
  double min_x = 0, max_x = 0, min_z = 0, max_z = 0;
  const auto extend = [&](const Eigen::Vector3d& p) {
    min_x = std::min(min_x, p.x());
    max_x = std::max(max_x, p.x());
    min_z = std::min(min_z, p.z());
    max_z = std::max(max_z, p.z());
  };
  for (const calib::RigidMotion& t : truth) extend(t.translation);
  for (const Eigen::Vector3d& p : estimate) extend(p);
  const double span = std::max({max_x - min_x, max_z - min_z, 0.5});
  const double scale = (kSize - 2 * kMargin) / span;
  const auto point = [&](const Eigen::Vector3d& p) {
    return cv::Point(static_cast<int>(std::lround(kMargin + (p.x() - min_x) * scale)),
                     static_cast<int>(std::lround(kSize - kMargin - (p.z() - min_z) * scale)));
  };
  RgbImage picture(kSize, kSize);
  cv::Mat drawing = mat_of(picture.view());
  drawing.setTo(cv::Scalar(255, 255, 255));
  std::vector<cv::Point> line;
  for (const calib::RigidMotion& t : truth) line.push_back(point(t.translation));
  cv::polylines(drawing, line, false, cv::Scalar(40, 160, 40), 5, cv::LINE_AA);
  line.clear();
  for (const Eigen::Vector3d& p : estimate) line.push_back(point(p));
  cv::polylines(drawing, line, false, cv::Scalar(220, 30, 30), 2, cv::LINE_AA);
  cv::circle(drawing, point(truth.front().translation), 6, cv::Scalar(0, 0, 0), 2, cv::LINE_AA);
  // A metre, for scale.
  const int metre = static_cast<int>(std::lround(scale));
  cv::line(drawing, {kMargin, kSize - 16}, {kMargin + metre, kSize - 16}, cv::Scalar(0, 0, 0), 2);
  draw_label(drawing, {kMargin + metre + 8, kSize - 16 - label_height() / 2}, "1 m",
             cv::Scalar(255, 255, 255));
  draw_label(drawing, {8, 8}, "from above: the path (green), the odometry (red)",
             cv::Scalar(255, 255, 255));
  save_image(file, std::as_const(picture).view());
}

}  // namespace

nlohmann::json check_trajectory(const std::vector<nlohmann::json>& odometry,
                                std::span<const calib::RigidMotion> truth, double rate_hz,
                                const std::filesystem::path& directory) {
  require(!truth.empty(), "no path to check the odometry against");
  const auto n = static_cast<std::uint64_t>(truth.size());
  std::vector<calib::RigidMotion> tracked;
  std::vector<std::uint64_t> frames;
  int lost = 0;
  int resets = 0;
  for (const nlohmann::json& m : odometry) {
    resets = m["reset_counter"].get<int>();
    const int status = m["status"].get<int>();  // protocol::OdometryStatus
    if (status == static_cast<int>(protocol::OdometryStatus::lost)) ++lost;
    if (status != static_cast<int>(protocol::OdometryStatus::tracking)) continue;
    tracked.push_back(pose_of(m));
    frames.push_back(m["frame"].get<std::uint64_t>());
  }
  if (tracked.empty()) return nullptr;
  // The odometry frame is the first keyframe's: the first pair tracked (pairs before it dropped
  // or too poor); the truth, in pair 0's, is taken to it.
  const calib::RigidMotion from_first =
      truth[static_cast<std::size_t>(frames.front() % n)].inverse();
  const auto truth_at = [&](std::uint64_t frame) {
    return from_first.after(truth[static_cast<std::size_t>(frame % n)]);
  };
  std::vector<calib::RigidMotion> timeline;  // the truth up to the last pair
  double path_m = 0;
  for (std::uint64_t f = frames.front(); f <= frames.back(); ++f) {
    if (f > frames.front()) {
      path_m += (truth_at(f).translation - truth_at(f - 1).translation).norm();
    }
    timeline.push_back(truth_at(f));
  }
  std::vector<Eigen::Vector3d> estimate;
  for (const calib::RigidMotion& p : tracked) estimate.push_back(p.translation);
  write_text_file_atomically(directory / "odometry.tum", [&] {
    std::string text;
    for (std::size_t i = 0; i < tracked.size(); ++i) {  // at its frame's time on the path
      text += hal::tum_line(static_cast<double>(frames[i]) / rate_hz, tracked[i]);
    }
    return text;
  }());
  draw_trajectories(timeline, estimate, directory / "trajectory.png");
  const calib::RigidMotion& last = tracked.back();
  const calib::RigidMotion true_last = truth_at(frames.back());
  const double error = (last.translation - true_last.translation).norm();
  const double heading =
      degrees(Eigen::AngleAxisd(true_last.rotation.transpose() * last.rotation).angle());
  return {{"pairs", odometry.size()},
          {"tracked", tracked.size()},
          {"lost", lost},
          {"resets", resets},
          {"last_frame", frames.back()},
          {"path_m", path_m},
          {"end_error_m", error},
          {"end_error_percent", path_m > 0 ? 100 * error / path_m : 0.0},
          {"end_heading_deg", heading}};
}

}  // namespace epipole::tools

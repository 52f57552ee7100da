#include "epipole/firmware/pair_messages.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "epipole/core/angles.hpp"
#include "wire_units.hpp"

namespace epipole::firmware {

using detail::in_units;
using detail::saturate;
using detail::to_us;

namespace {

std::uint64_t non_negative(hal::Nanoseconds ns) {
  return static_cast<std::uint64_t>(std::max<hal::Nanoseconds>(ns, 0));
}

protocol::FrameSummary summary_of(const FrameResult& r, hal::Nanoseconds latency,
                                  bool trigger_from_capture) {
  protocol::FrameSummary s;
  s.frame = r.frame;
  s.trigger_ns = non_negative(r.trigger_ns);
  s.latency_us = to_us(latency);
  s.corners_left = saturate<std::uint16_t>(r.corners_left.size());
  s.corners_right = saturate<std::uint16_t>(r.corners_right.size());
  s.valid_disparity_permille = static_cast<std::uint16_t>(r.valid_disparity_permille);
  s.points = saturate<std::uint16_t>(r.best_points.size());
  s.detections = saturate<std::uint8_t>(r.detections.size());
  if (trigger_from_capture) s.flags |= protocol::kFrameTriggerFromCapture;
  return s;
}

protocol::Detections detections_of(const FrameResult& r) {
  protocol::Detections d;
  d.frame = r.frame;
  const std::size_t n = std::min(r.detections.size(), d.items.size());
  d.count = static_cast<std::uint8_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const vision::Detection& box = r.detections[i];
    const DetectionDepth& depth = r.detection_depths[i];
    protocol::Detection& out = d.items[i];
    out.x = saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(box.x, 0)));
    out.y = saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(box.y, 0)));
    out.width = saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(box.width, 0)));
    out.height = saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(box.height, 0)));
    out.neighbors = saturate<std::uint8_t>(static_cast<std::uint64_t>(std::max(box.neighbors, 0)));
    // 65 535 mm is kUnknownDepth: depths from 65.5 m on are not told apart from unknown.
    out.depth_mm = depth.valid && depth.depth > 0 && depth.depth < 65.5
                       ? static_cast<std::uint16_t>(std::lround(depth.depth * 1000))
                       : protocol::kUnknownDepth;
  }
  return d;
}

// Clamped before rounding: a long has 32 bits on armhf.
std::int32_t millimetres(float metres) {
  const double mm = std::clamp(static_cast<double>(metres) * 1000.0, -2e9, 2e9);
  return static_cast<std::int32_t>(std::lround(std::isnan(mm) ? 0.0 : mm));
}

protocol::Points points_of(const FrameResult& r) {
  protocol::Points points;
  points.frame = r.frame;
  const std::size_t n = std::min(r.best_points.size(), points.items.size());
  points.count = static_cast<std::uint8_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const SparsePoint& p = r.points[r.best_points[i]];
    points.items[i] = {static_cast<std::uint16_t>(std::lround(p.xl * 16.0f)),
                       static_cast<std::uint16_t>(std::lround(p.yl * 16.0f)), millimetres(p.x),
                       millimetres(p.y), millimetres(p.z)};
  }
  return points;
}

}  // namespace

PairMessages pair_messages(const FrameResult& r, hal::Nanoseconds latency,
                           bool trigger_from_capture) {
  PairMessages m;
  m.summary = summary_of(r, latency, trigger_from_capture);
  if (protocol::has_stage(r.stages, protocol::Stage::detect)) m.detections = detections_of(r);
  if (r.obstacles != nullptr) m.obstacles = *r.obstacles;
  if (r.depth_grid != nullptr) m.depth_grid = *r.depth_grid;
  if (!r.best_points.empty()) m.points = points_of(r);
  m.stage_messages = r.stage_messages;
  return m;
}

protocol::CalibrationHealth calibration_health_message(
    const calib::HealthFigure& figure, const std::optional<calib::DriftEstimate>& drift,
    const RigCorrection* correction) {
  protocol::CalibrationHealth c;
  c.matches = saturate<std::uint16_t>(static_cast<std::uint64_t>(std::max(figure.matches, 0)));
  c.median_offset_centipx = in_units<std::int16_t>(figure.median_signed_px, 0.01);
  c.p90_offset_centipx = in_units<std::uint16_t>(figure.p90_px, 0.01);
  if (drift && drift->valid) {
    constexpr double kMilliDegree = radians(0.001);
    c.flags |= protocol::kDriftEstimated;
    c.window_pairs = saturate<std::uint16_t>(static_cast<std::uint64_t>(drift->pairs));
    c.pitch_mdeg = in_units<std::int16_t>(drift->pitch, kMilliDegree);
    c.roll_mdeg = in_units<std::int16_t>(drift->roll, kMilliDegree);
    c.pitch_sigma_mdeg = in_units<std::uint16_t>(drift->pitch_sigma, kMilliDegree);
    c.roll_sigma_mdeg = in_units<std::uint16_t>(drift->roll_sigma, kMilliDegree);
  }
  if (correction != nullptr) {
    constexpr double kMilliDegree = radians(0.001);
    if (correction->rebuilding()) c.flags |= protocol::kRigCorrecting;
    c.corrections = saturate<std::uint16_t>(static_cast<std::uint64_t>(correction->corrections()));
    const calib::CameraTurn total = correction->total();
    c.corrected_pitch_mdeg = in_units<std::int16_t>(total.pitch, kMilliDegree);
    c.corrected_roll_mdeg = in_units<std::int16_t>(total.roll, kMilliDegree);
  }
  return c;
}

mavlink::ObstacleDistance obstacle_distance_message(const protocol::Obstacles& obstacles,
                                                    hal::Nanoseconds trigger_ns,
                                                    const BoardConfig::Obstacles& range) {
  const auto cm = [](double m) { return static_cast<std::uint16_t>(m * 100 + 0.5); };
  return mavlink::to_obstacle_distance(obstacles, non_negative(trigger_ns) / 1000,
                                       cm(range.min_depth_m), cm(range.max_depth_m));
}

}  // namespace epipole::firmware

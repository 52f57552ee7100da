// The ground: the plane under the rig, found in the dense disparity once it is done
// (vision::GroundPlaneFinder: the v-disparity, its line by a Hough transform, the plane by
// RANSAC and least squares), in metres through Q (calib::metric_plane); then the obstacle
// sectors, counting only what stands higher than the board's clearance above it, so that the
// floor is no obstacle. Without a ground in sight the sectors count everything, as without
// this stage.
#include <yaml-cpp/yaml.h>

#include <cmath>

#include "epipole/calib/disparity_plane.hpp"
#include "epipole/core/angles.hpp"
#include "epipole/core/yaml_fields.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/vision/ground_plane.hpp"
#include "stage_files.hpp"

namespace epipole::firmware::stages {

namespace {

// The board file's `ground:` (docs/boards.md).
struct GroundSettings final : StageSettings {
  double clearance_m = 0.10;   // obstacles: what stands at least this high above the ground
  double min_height_m = 0.05;  // the rig's mounting: its height above the ground,
  double max_height_m = 3.0;
  double max_pitch_deg = 45;  // its pitch and roll against it, either way
  double max_roll_deg = 30;
  int iterations = 64;     // RANSAC's budget (docs/vision.md: enough for 99.9 % at half inliers)
  double inlier_px = 1.0;  // a pixel on the ground is this near its disparity
  std::unique_ptr<StageSettings> clone() const override {
    return std::make_unique<GroundSettings>(*this);
  }
};

std::unique_ptr<StageSettings> read_settings(const YAML::Node& n, const yaml::Fields& f) {
  auto s = std::make_unique<GroundSettings>();
  if (!n.IsDefined() || n.IsNull()) return s;
  const std::string path = "ground";
  f.only_keys(
      n, path,
      {"clearance_m", "height_m", "max_pitch_deg", "max_roll_deg", "iterations", "inlier_px"});
  f.if_present(n, path, "clearance_m", [&](const YAML::Node& v, const std::string& k) {
    s->clearance_m = f.number_in(v, k, 0, 5);
  });
  f.if_present(n, path, "height_m", [&](const YAML::Node& v, const std::string& k) {
    const std::vector<double> range = f.numbers(v, k);
    if (range.size() != 2 || !(range[0] >= 0.01) || !(range[1] > range[0]) || range[1] > 50) {
      f.fail(k, "must be [lowest, highest] metres, 0.01 <= lowest < highest <= 50");
    }
    s->min_height_m = range[0];
    s->max_height_m = range[1];
  });
  f.if_present(n, path, "max_pitch_deg", [&](const YAML::Node& v, const std::string& k) {
    s->max_pitch_deg = f.number_in(v, k, 0, 80);
  });
  f.if_present(n, path, "max_roll_deg", [&](const YAML::Node& v, const std::string& k) {
    s->max_roll_deg = f.number_in(v, k, 0, 60);
  });
  f.if_present(n, path, "iterations", [&](const YAML::Node& v, const std::string& k) {
    s->iterations = f.integer_in(v, k, 1, 10'000);
  });
  f.if_present(n, path, "inlier_px", [&](const YAML::Node& v, const std::string& k) {
    s->inlier_px = f.number_in(v, k, 0.1, 8);
  });
  return s;
}

// The Hough transform's lines for the rigs the board admits. The ground's disparity is
// d = baseline / height * (n . (u - cx, v - cy, f)) with n its downward normal, once Q's offset
// (cx - cx') is taken out: rows slope by baseline * n_y / height, n_y = cos(pitch) cos(roll), and
// d is 0 at the horizon, cy - f tan(pitch) / cos(roll); a margin for the bins.
vision::GroundPlaneConfig finder_config(const BoardConfig& board, const GroundSettings& s,
                                        const Eigen::Matrix4d& Q) {
  const double f = Q(2, 3), cx = -Q(0, 3), cy = -Q(1, 3);
  const double baseline = 1.0 / std::abs(Q(3, 2));
  const double pitch = radians(s.max_pitch_deg), roll = radians(s.max_roll_deg);
  vision::GroundPlaneConfig c;
  c.width = board.width();
  c.height = board.height();
  c.max_disparity = board.stereo.max_disparity;
  c.min_slope = baseline * std::cos(pitch) * std::cos(roll) / s.max_height_m;
  c.max_slope = baseline / s.min_height_m;
  const double reach = f * std::tan(pitch) / std::cos(roll) * 1.1 + 20;
  c.min_horizon = cy - reach;
  c.max_horizon = cy + reach;
  c.horizon_bins = std::clamp(static_cast<int>((c.max_horizon - c.min_horizon) / 4), 32, 1024);
  c.disparity_offset = Q(3, 3) / Q(3, 2);
  c.centre_column = cx;
  c.max_tilt = std::tan(roll);
  c.iterations = s.iterations;
  c.inlier_px = s.inlier_px;
  return c;
}

class GroundStage final : public PipelineStage {
 public:
  explicit GroundStage(const StageContext& c)
      : settings_(settings_of<GroundSettings>(c, protocol::Stage::ground)),
        obstacles_(c.obstacles) {
    if (c.triangulator == nullptr) return;  // a plane in metres needs Q
    Q_ = c.triangulator->Q();
    finder_ =
        std::make_unique<vision::GroundPlaneFinder>(finder_config(c.board, settings_, Q_), c.path);
  }

  bool available() const override { return finder_ != nullptr; }
  std::size_t working_set_bytes() const override {
    return finder_ ? finder_->working_set_bytes() : 0;
  }
  // After the disparity's last stripe.
  int add_tasks(PairWork& work) override {
    work_ = &work;
    return work.batch.add(1, task_,
                          work.parts[static_cast<std::size_t>(protocol::Stage::disparity)]);
  }

 private:
  void find(FrameResult& r) {
    const vision::GroundPlaneFit& fit = finder_->find(r.disparity);
    auto& message = std::get<protocol::Ground>(message_);
    message = protocol::Ground{};
    message.frame = r.frame;
    const PixelHalfSpace* above = nullptr;
    if (const auto plane = fit.found ? calib::metric_plane(Q_, fit.a, fit.b, fit.c) : std::nullopt;
        plane && admitted(*plane)) {
      message.flags = protocol::kGroundFound;
      message.height_mm =
          static_cast<std::uint16_t>(std::lround(std::min(plane->distance, 65.0) * 1000));
      message.pitch_cdeg = static_cast<std::int16_t>(std::lround(calib::pitch_deg(*plane) * 100));
      message.roll_cdeg = static_cast<std::int16_t>(std::lround(calib::roll_deg(*plane) * 100));
      message.inliers_permille =
          static_cast<std::uint16_t>(fit.valid > 0 ? fit.inliers * 1000 / fit.valid : 0);
      const Eigen::Vector4d form = calib::clearance_form(Q_, *plane, settings_.clearance_m);
      plane_ = {*plane, {form(0), form(1), form(2), form(3)}};
      above = &plane_.clear;
      r.ground_plane = &plane_;
    }
    r.ground = &message;
    r.stage_messages[static_cast<std::size_t>(protocol::Stage::ground)] = &message_;
    if (obstacles_ != nullptr) {
      r.obstacles = &obstacles_->measure(r.disparity, r.frame, r.disparity_confidence, above);
    }
  }
  // Within the board's mounting (the Hough transform admits a little more).
  bool admitted(const calib::MetricPlane& plane) const {
    const double pitch = calib::pitch_deg(plane), roll = calib::roll_deg(plane);
    return plane.distance >= settings_.min_height_m && plane.distance <= settings_.max_height_m &&
           std::abs(pitch) <= settings_.max_pitch_deg && std::abs(roll) <= settings_.max_roll_deg;
  }

  struct Task {
    GroundStage& s;
    void operator()(int, int) const { s.find(s.work_->result); }
  };

  GroundSettings settings_;
  ObstacleSectors* obstacles_;
  Eigen::Matrix4d Q_ = Eigen::Matrix4d::Zero();
  std::unique_ptr<vision::GroundPlaneFinder> finder_;
  protocol::Message message_{protocol::Ground{}};
  GroundPlane plane_;
  PairWork* work_ = nullptr;
  Task task_{*this};
};

}  // namespace

extern constinit const StageDefinition ground_stage{make_stage<GroundStage>, read_settings};

}  // namespace epipole::firmware::stages

// Visual odometry: where the rig is and how it moves, from the sparse stage's features and
// their 3-D points (VisualOdometry, docs/odometry.md), once the sparse matching is done. Needs a
// calibration (the points in metres). A pair it does not run on (the stage or the sparse
// matching off, a camera lost) makes it start again from the pose it has: reset_counter says so.
#include <yaml-cpp/yaml.h>

#include "epipole/core/yaml_fields.hpp"
#include "epipole/firmware/odometry_messages.hpp"
#include "epipole/firmware/visual_odometry.hpp"
#include "stage_files.hpp"

namespace epipole::firmware::stages {

namespace {

// The board file's `odometry:` (docs/boards.md).
struct OdometrySettings final : StageSettings {
  OdometryConfig config;
  std::unique_ptr<StageSettings> clone() const override {
    return std::make_unique<OdometrySettings>(*this);
  }
};

std::unique_ptr<StageSettings> read_settings(const YAML::Node& n, const yaml::Fields& f) {
  auto s = std::make_unique<OdometrySettings>();
  if (!n.IsDefined() || n.IsNull()) return s;
  const std::string path = "odometry";
  OdometryConfig& c = s->config;
  f.only_keys(
      n, path,
      {"max_landmarks", "search_radius_px", "iterations", "inlier_px", "keyframe_distance_m",
       "keyframe_angle_deg", "lost_pairs_to_reset", "max_speed_mps", "max_turn_dps"});
  const auto number = [&](const char* key, double& out, double lo, double hi) {
    f.if_present(n, path, key, [&](const YAML::Node& v, const std::string& k) {
      out = f.number_in(v, k, lo, hi);
    });
  };
  const auto integer = [&](const char* key, int& out, int lo, int hi) {
    f.if_present(n, path, key, [&](const YAML::Node& v, const std::string& k) {
      out = f.integer_in(v, k, lo, hi);
    });
  };
  integer("max_landmarks", c.max_landmarks, c.motion.min_inliers, 10'000);
  integer("search_radius_px", c.search_radius_px, 4, 256);
  integer("iterations", c.motion.iterations, 1, 10'000);
  number("inlier_px", c.motion.inlier_px, 0.1, 8);
  number("keyframe_distance_m", c.keyframe_distance_m, 0.01, 100);
  number("keyframe_angle_deg", c.keyframe_angle_deg, 0.5, 90);
  integer("lost_pairs_to_reset", c.lost_pairs_to_reset, 1, 1000);
  number("max_speed_mps", c.max_speed_mps, 0.1, 1000);
  number("max_turn_dps", c.max_turn_dps, 1, 10'000);
  return s;
}

class OdometryStage final : public PipelineStage {
 public:
  explicit OdometryStage(const StageContext& c) {
    if (!c.calibration) return;  // points in metres need a calibration
    odometry_.emplace(calib::RectifiedStereoCameras::of(*c.calibration), c.board.width(),
                      c.board.height(), c.board.corners.max_corners, c.board.sparse.max_matches,
                      settings_of<OdometrySettings>(c, protocol::Stage::odometry).config, c.path);
  }

  bool available() const override { return odometry_.has_value(); }
  std::size_t working_set_bytes() const override {
    return odometry_ ? odometry_->working_set_bytes() : 0;
  }
  void skip(PairWork&) override {
    if (odometry_ && odometry_->state().status != OdometryState::Status::starting) {
      odometry_->restart();
    }
  }
  // After the sparse matching's task.
  int add_tasks(PairWork& work) override {
    work_ = &work;
    return work.batch.add(1, task_, work.parts[static_cast<std::size_t>(protocol::Stage::sparse)]);
  }
  void forget_history() override {
    if (odometry_) odometry_->restart();
  }

 private:
  void update(FrameResult& r) {
    const OdometryState& state = odometry_->update(r.trigger_ns, r.left_features, r.points);
    message_ = odometry_message(state, r.frame, r.trigger_ns);
    r.odometry = &state;
    r.stage_messages[static_cast<std::size_t>(protocol::Stage::odometry)] = &message_;
  }

  struct Task {
    OdometryStage& s;
    void operator()(int, int) const { s.update(s.work_->result); }
  };

  std::optional<VisualOdometry> odometry_;
  protocol::Message message_{protocol::Odometry{}};
  PairWork* work_ = nullptr;
  Task task_{*this};
};

}  // namespace

extern constinit const StageDefinition odometry_stage{make_stage<OdometryStage>, read_settings};

}  // namespace epipole::firmware::stages

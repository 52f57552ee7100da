#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "epipole/calib/calibration.hpp"
#include "epipole/calib/disparity_plane.hpp"
#include "epipole/calib/drift_estimator.hpp"
#include "epipole/calib/health.hpp"
#include "epipole/calib/triangulation.hpp"
#include "epipole/core/image.hpp"
#include "epipole/core/simd.hpp"
#include "epipole/core/task_batch.hpp"
#include "epipole/core/thread_pool.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/depth_grid.hpp"
#include "epipole/firmware/detection_depth.hpp"
#include "epipole/firmware/health_monitor.hpp"
#include "epipole/firmware/memory_report.hpp"
#include "epipole/firmware/obstacles.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "epipole/firmware/rig_correction.hpp"
#include "epipole/firmware/sparse_points.hpp"
#include "epipole/firmware/visual_odometry.hpp"
#include "epipole/vision/cascade.hpp"
#include "epipole/vision/corner.hpp"
#include "epipole/vision/sparse_stereo.hpp"
#include "epipole/vision/stereo.hpp"

namespace epipole::firmware {

namespace stages {
class PipelineStage;
}

// Which stages run, one bit per protocol::Stage (protocol/stages.hpp).
using protocol::stage_bit;
using protocol::StageMask;

// The ground the ground stage found under the rig (stages/ground.cpp): the plane in the
// rectified left camera's frame, and the pixels (u, v, disparity) of what stands at least the
// board's ground.clearance_m above it.
struct GroundPlane {
  calib::MetricPlane plane;
  PixelHalfSpace clear;
};

// What the stages made of one frame pair. Views and spans point into the pipeline's own
// buffers and stay valid until the next process() call.
struct FrameResult {
  std::uint32_t frame = 0;          // the trigger's sequence number
  hal::Nanoseconds trigger_ns = 0;  // the trigger edge on the board's clock
  StageMask stages = 0;             // the stages that ran
  GrayView left_raw, right_raw;     // as captured
  GrayView left, right;             // rectified (the raw images when rectification is off)
  std::span<const vision::Corner> corners_left, corners_right;
  ImageView<const std::int16_t> disparity;  // x16, vision::kInvalidDisparity; empty when off
  ImageView<const std::uint8_t> disparity_confidence;  // when the board's filters ask for it
  int valid_disparity_permille = 0;
  const protocol::Ground* ground = nullptr;   // the ground stage's (its flags say if one was found)
  const GroundPlane* ground_plane = nullptr;  // when it found one
  const protocol::Obstacles* obstacles = nullptr;   // null without disparity or calibration
  const protocol::DepthGrid* depth_grid = nullptr;  // the same, or without the board's grid
  std::span<const vision::SparseMatch> matches;     // sparse matches along the rows
  vision::DescribedCorners left_features;           // the left corners the matches index
  std::span<const SparsePoint> points;              // their 3-D points (with a calibration)
  // The matches to send as 3-D points (sparse.max_points, smallest descriptor distance first):
  // indices into `points`.
  std::span<const std::uint32_t> best_points;
  // How well the rectification holds (only when the images were rectified with a calibration):
  // the vertical offsets of the corners' matches on a band of rows, to a fraction of a pixel,
  // and the right camera's turn since the calibration, estimated over a window of pairs.
  std::optional<calib::HealthFigure> calibration_health;
  std::optional<calib::DriftEstimate> drift;
  // Where the rig is and how it moves (the odometry stage's; null when it did not run).
  const OdometryState* odometry = nullptr;
  // Viola-Jones detections in the rectified left image, and each one's depth (valid when the
  // disparity ran and the box holds valid disparities).
  std::span<const vision::Detection> detections;
  std::span<const DetectionDepth> detection_depths;
  StageTimes times{};
  // The message each stage sends for the pair, by protocol::Stage (null: none), in the stage's
  // own memory (a stage's finish() sets its own).
  std::array<const protocol::Message*, protocol::kStageCount> stage_messages{};
};

// Where the pipeline finds the pair after the one it is working on (pipelining across pairs):
// the frame loop's grabber. take() returns the next pair's images when it has arrived, without
// waiting; process() calls it at most once, on one of the pool's workers, once every task of the
// current pair has started, and rectifies what it gets into its second set of images while the
// current pair's last tasks run. The images must stay as they are until they are given to
// process() (or dropped for a fresher pair).
class NextPair {
 public:
  struct Images {
    GrayView left, right;
    std::uint32_t frame = 0;
  };
  virtual ~NextPair() = default;
  virtual std::optional<Images> take() = 0;
};

// The vision stages of the frame loop, built once from the board configuration (and the rig's
// calibration, when there is one) with all their memory; process() never allocates.
class Pipeline {
 public:
  // Throws Error when the calibration does not fit the board (size), a stage's configuration
  // is not valid, or the detector's cascade (a compiled file, epipole cascade-compile) is
  // OpenCV's XML or does not read; one that does not exist yet leaves detection off
  // (missing_cascade()). `cascade`: the model to use instead of the board's file (tests, the host
  // tool).
  Pipeline(const BoardConfig& board, const std::optional<calib::StereoCalibration>& calibration,
           SimdPath path = best_simd_path(), const vision::CascadeModel* cascade = nullptr);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Runs the enabled stages (a stage whose inputs are off does not run) on a captured pair.
  // With `next`, the pair after it is taken and rectified ahead, in the workers' last gaps; a
  // later process() of exactly those images (the same buffers and frame) uses that result, which
  // is the same as rectifying them then. Its time is the rectification's of that pair.
  const FrameResult& process(GrayView left, GrayView right, std::uint32_t frame,
                             hal::Nanoseconds trigger_ns, StageMask enabled,
                             NextPair* next = nullptr);

  // The next pair starts a new sequence: what filters over time (the disparity's temporal
  // filter) forgets the pairs before it. The frame loop calls it when a camera is lost; a pair
  // after one without disparity starts a new sequence by itself.
  void reset_history();
  // The pair taken ahead (NextPair) will not be processed: its buffers went back to the cameras,
  // and a later pair in the same buffers with the same number (a camera's count restarted) must
  // not be taken for it.
  void drop_pair_ahead();

  // The stages this pipeline can run (rectification needs a calibration, and so on).
  StageMask available() const { return available_; }
  bool has_calibration() const { return triangulator_ != nullptr; }
  // The compiled cascade the board names for detection that is not there yet (detection is off
  // until it is made and the firmware restarted); empty otherwise.
  std::filesystem::path missing_cascade() const;
  const calib::Triangulator* triangulator() const { return triangulator_.get(); }
  const ObstacleSectors* obstacle_sectors() const { return obstacles_.get(); }
  // The rig corrected while running (null without a calibration).
  RigCorrection* rig_correction() { return correction_.get(); }
  const RigCorrection* rig_correction() const { return correction_.get(); }
  // Every stage's buffers, one part per stage (as the table of stages names them).
  void add_memory(MemoryReport& report) const;
  // Pairs rectified ahead (NextPair), and how many of them process() then used.
  std::uint64_t pairs_rectified_ahead() const;
  std::uint64_t pairs_used_ahead() const;

 private:
  void make_depth_outputs(const BoardConfig& board, const calib::StereoCalibration& calibration);

  std::unique_ptr<ThreadPool> pool_;  // every stage's tasks: threads.count workers
  TaskBatch batch_;
  std::unique_ptr<calib::Triangulator> triangulator_;
  std::unique_ptr<ObstacleSectors> obstacles_;
  std::unique_ptr<DepthGrid> depth_grid_;
  std::unique_ptr<RigCorrection> correction_;
  // The stages of firmware/src/stages/stage_table.hpp, by id (null: not a pipeline stage).
  std::array<std::unique_ptr<stages::PipelineStage>, protocol::kStageCount> stages_;
  StageMask available_ = 0;
  FrameResult result_;
};

}  // namespace epipole::firmware

#pragma once

// The work of the firmware's stages done by OpenCV, for `epipole bench` to set beside the
// firmware: remap of both images, FAST (or Harris) corners on both, StereoSGBM in 3-way mode
// (or its default mode, or StereoBM) with the same disparity range, CascadeClassifier on the left
// image. The sparse matcher has no OpenCV counterpart.
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/objdetect.hpp>

#include <array>
#include <filesystem>
#include <optional>

#include "epipole/calib/calibration.hpp"
#include "epipole/firmware/board_config.hpp"
#include "epipole/firmware/protocol/stages.hpp"

namespace epipole::tools {

class OpenCvPipeline {
 public:
  // Milliseconds per stage of protocol::kStages (0 where the stage did not run).
  using Times = std::array<double, protocol::kStageCount>;

  // The stages the board enables that OpenCV can do: rectification needs the calibration,
  // detection OpenCV's XML of the board's cascade (`cascade_xml`, empty: none). SGM:
  // StereoSGBM in 3-way mode, or in its default mode (MODE_SGBM) without `sgbm_3way`.
  OpenCvPipeline(const firmware::BoardConfig& board,
                 const std::optional<calib::StereoCalibration>& calibration,
                 const std::filesystem::path& cascade_xml, bool sgbm_3way = true);

  // The stages that run here (a subset of the board's).
  protocol::StageMask stages() const { return stages_; }

  // One pair through every stage, in the order of protocol::kStages, each timed.
  Times process(const cv::Mat& left, const cv::Mat& right);

 private:
  struct Images {
    cv::Mat left, right;
  };
  // Each stage's OpenCV counterpart (kSteps in the .cpp; the sparse matcher has none).
  void rectify(Images& images);
  void corners(Images& images);
  void disparity(Images& images);
  void detect(Images& images);
  struct Step {
    protocol::Stage id;
    void (OpenCvPipeline::*run)(Images&);
  };
  static const Step* step_of(protocol::Stage id);

  firmware::BoardConfig::Corners corners_;
  firmware::BoardConfig::Detector detector_;
  protocol::StageMask stages_ = 0;
  cv::Mat map1_[2], map2_[2];
  cv::Mat rectified_[2];
  cv::Ptr<cv::StereoMatcher> matcher_;
  cv::CascadeClassifier cascade_;
};

}  // namespace epipole::tools

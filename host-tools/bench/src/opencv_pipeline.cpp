#include "opencv_pipeline.hpp"

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <vector>

#include "epipole/core/error.hpp"
#include "epipole/tools/opencv_matrices.hpp"

namespace epipole::tools {

namespace {

using protocol::Stage;
using protocol::stage_bit;

// The rectification maps OpenCV's users make: initUndistortRectifyMap, fixed point (CV_16SC2).
void rectification_maps(const calib::StereoCalibration& c, const calib::CameraCalibration& camera,
                        cv::Mat& map1, cv::Mat& map2) {
  cv::initUndistortRectifyMap(opencv_matrix(camera.camera_matrix()),
                              opencv_coefficients(camera.camera.distortion),
                              opencv_matrix(camera.rectification), opencv_matrix(camera.projection),
                              {c.width, c.height}, CV_16SC2, map1, map2);
}

cv::Ptr<cv::StereoMatcher> stereo_matcher(const vision::StereoConfig& s, bool sgbm_3way) {
  if (s.method == vision::StereoMethod::bm) {
    auto bm = cv::StereoBM::create(s.max_disparity, std::max(5, s.block_size | 1));
    bm->setUniquenessRatio(s.uniqueness);
    bm->setSpeckleWindowSize(s.speckle_size);
    bm->setSpeckleRange(s.speckle_range);
    bm->setDisp12MaxDiff(s.lr_max_diff);
    return bm;
  }
  constexpr int kBlock = 5;
  return cv::StereoSGBM::create(
      0, s.max_disparity, kBlock, 8 * kBlock * kBlock, 32 * kBlock * kBlock, s.lr_max_diff, 63,
      s.uniqueness, s.speckle_size, s.speckle_range,
      sgbm_3way ? cv::StereoSGBM::MODE_SGBM_3WAY : cv::StereoSGBM::MODE_SGBM);
}

}  // namespace

OpenCvPipeline::OpenCvPipeline(const firmware::BoardConfig& board,
                               const std::optional<calib::StereoCalibration>& calibration,
                               const std::filesystem::path& cascade_xml, bool sgbm_3way)
    : corners_(board.corners), detector_(board.detector) {
  const auto enabled = [&](Stage s) { return protocol::has_stage(board.stages, s); };
  if (enabled(Stage::rectify) && calibration) {
    rectification_maps(*calibration, calibration->left, map1_[0], map2_[0]);
    rectification_maps(*calibration, calibration->right, map1_[1], map2_[1]);
    stages_ |= stage_bit(Stage::rectify);
  }
  if (enabled(Stage::corners)) stages_ |= stage_bit(Stage::corners);
  if (enabled(Stage::disparity)) {
    matcher_ = stereo_matcher(board.stereo, sgbm_3way);
    stages_ |= stage_bit(Stage::disparity);
  }
  if (enabled(Stage::detect) && !cascade_xml.empty()) {
    require(cascade_.load(cascade_xml.string()), cascade_xml.string(),
            ": OpenCV's CascadeClassifier cannot read it");
    stages_ |= stage_bit(Stage::detect);
  }
}

const OpenCvPipeline::Step* OpenCvPipeline::step_of(Stage id) {
  static constexpr std::array<Step, 4> kSteps{{
      {Stage::rectify, &OpenCvPipeline::rectify},
      {Stage::corners, &OpenCvPipeline::corners},
      {Stage::disparity, &OpenCvPipeline::disparity},
      {Stage::detect, &OpenCvPipeline::detect},
  }};
  for (const Step& step : kSteps) {
    if (step.id == id) return &step;
  }
  return nullptr;
}

OpenCvPipeline::Times OpenCvPipeline::process(const cv::Mat& left_raw, const cv::Mat& right_raw) {
  Times times{};
  // The inputs are never written: rectified images go to buffers of their own.
  Images images{left_raw, right_raw};
  for (const protocol::StageInfo& s : protocol::kStages) {
    const Step* step = step_of(s.id);
    if (step == nullptr || !protocol::has_stage(stages_, s.id)) continue;
    const auto start = std::chrono::steady_clock::now();
    (this->*step->run)(images);
    times[static_cast<std::size_t>(s.id)] =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  return times;
}

void OpenCvPipeline::rectify(Images& images) {
  cv::remap(images.left, rectified_[0], map1_[0], map2_[0], cv::INTER_LINEAR);
  cv::remap(images.right, rectified_[1], map1_[1], map2_[1], cv::INTER_LINEAR);
  images.left = rectified_[0];
  images.right = rectified_[1];
}

void OpenCvPipeline::corners(Images& images) {
  const auto& c = corners_;
  for (const cv::Mat* image : {&images.left, &images.right}) {
    std::vector<cv::KeyPoint> keypoints;
    std::vector<cv::Point2f> points;
    if (c.detector == firmware::BoardConfig::CornerDetector::fast) {
      cv::FAST(*image, keypoints, c.threshold, true);
    } else {
      cv::goodFeaturesToTrack(*image, points, c.max_corners, 0.01, 3, cv::noArray(), 3, true);
    }
  }
}

void OpenCvPipeline::disparity(Images& images) {
  cv::Mat disparity;
  matcher_->compute(images.left, images.right, disparity);
}

void OpenCvPipeline::detect(Images& images) {
  const auto& d = detector_;
  std::vector<cv::Rect> objects;
  const cv::Size max_size = d.max_size > 0 ? cv::Size(d.max_size, d.max_size) : cv::Size();
  cascade_.detectMultiScale(images.left, objects, d.scale_factor, d.min_neighbors, 0,
                            {d.min_size, d.min_size}, max_size);
}

}  // namespace epipole::tools
